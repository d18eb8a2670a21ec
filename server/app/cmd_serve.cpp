// `serve`: the render server. Its options and their precedence: app/serve_options.h.
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

#include "app/cmd_render_mpi.h"
#include "app/commands.h"
#include "app/serve_options.h"
#include "core/file_roots.h"
#include "core/log.h"
#include "net/server.h"

namespace peakcast::app {

namespace {

// The server until SIGTERM/SIGINT; 0 when it stopped cleanly.
int serve(const net::ServerConfig& c, const ServeOptions& o) {
  net::Server server(c);
  server.start();
  // This line on stdout is the contract scripts and tests wait for; the log goes to stderr.
  std::printf("peakcast: serving on http://%s:%u (renderer %s)\n", c.bind.c_str(), unsigned(server.port()),
              server.app().render.gl_renderer().c_str());
  log::info("serving", {{"bind", c.bind},
                        {"port", server.port()},
                        {"renderer", server.app().render.gl_renderer()},
                        {"data", o.data},
                        {"volumes", o.volumes},
                        {"auth", !c.token.empty() || !c.user_tokens.empty()},
                        {"ranks", c.ranks}});
  std::fflush(stdout);
  server.run_until_signal();
  std::printf("peakcast: stopped\n");
  return 0;
}

}  // namespace

void add_serve_command(CLI::App& app, Runner& run) {
  auto o = std::make_shared<ServeOptions>();
  auto* s = app.add_subcommand("serve", "Run the render server (HTTP + WebSocket on one port)");
  add_serve_options(*s, *o);
  s->callback([=, &run] {
    run = [=] {
      apply_env_and_file(*s, *o);
      if (o->print_config) {
        std::fputs(print_config(*s, *o).c_str(), stdout);
        return 0;
      }
      log::configure(log::parse_level(o->log_level), log::parse_format(o->log_format));
      net::ServerConfig config = o->resolved();
      unsetenv("PEAKCAST_TOKEN");  // read: not passed on to any process this one starts
      // Every rank reads only where the server may (net::read_roots): under mpirun the other
      // ranks open the bricks' files, chunks and data files themselves.
      file_roots::confine(net::read_roots(config));
      if (mpi_world_size_hint() > 1) {  // mpirun -np N peakcast serve: rank 0 serves, every rank renders
#ifdef PEAKCAST_HAVE_MPI
        return mpi_serve(config.backend, config.egl_device, [&](MpiServeHooks hooks) {
          config.wrap_renderer = std::move(hooks.wrap);
          config.volume_loader = std::move(hooks.loader);
          config.ranks = hooks.ranks;
          return serve(config, *o);
        });
#else
        throw std::invalid_argument("launched by mpirun with several ranks, but this peakcast was built without MPI");
#endif
      }
      return serve(config, *o);
    };
  });
}

}  // namespace peakcast::app
