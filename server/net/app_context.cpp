#include "net/app_context.h"

#include <string>

#include <boost/asio/post.hpp>

#include "core/file_roots.h"
#include "core/volume_io.h"
#include "encode/video.h"

namespace peakcast::net {

namespace {

LoadOptions load_options(const ServerConfig& c) {
  LoadOptions o;
  o.memory_budget_bytes = c.memory_budget_bytes;
  o.decode_budget_bytes = c.memory_budget_bytes;
  return o;
}

const ServerConfig& confine_reads(const ServerConfig& c) {
  file_roots::confine(read_roots(c));
  return c;
}

bool is_doc(const std::string& rel) { return rel.ends_with(".md") || rel.ends_with(".png"); }

}  // namespace

AppContext::AppContext(ServerConfig c)
    : config(confine_reads(c)),
      residency(config.gpu_budget_bytes),
      volumes(config.data_dirs, residency, load_options(config), config.volume_loader),
      uploads(config.upload_dir, config.upload_limits, volumes),
      chunked_uploads(uploads, config.memory_budget_bytes),
      render(residency, metrics,
             RenderServiceOptions{config.shader_dir, config.encode_threads,
                                  SchedulerOptions{config.max_queued_stills, config.still_band_samples,
                                                   limits::kStillDelay, config.max_fps},
                                  config.egl_device, config.backend, config.program_cache, config.wrap_renderer,
                                  config.ranks}),
      ws_sessions(config.max_sessions),
      access(config.token, config.user_tokens),
      hosts(config.bind, config.allowed_hosts) {
  // The client's files and the docs its help links open (docs/ beside client-web/, in the
  // container too): listed once, here; nothing else is ever served from disk.
  files.add_root(config.web_dir, "/");
  files.add_root((config.web_dir / "..").lexically_normal() / "docs", "/docs/", is_doc);
  // Which video encoders open is tried once, here, before serving: not on an io thread at the
  // first welcome (opening libaom and libx264 takes tens of ms).
  encode::available_codecs();
  volumes.set_preview(config.preview_voxels, [this](std::function<void()> fn) {
    boost::asio::post(pyramid, [fn = std::move(fn)] {
      try {
        fn();
      } catch (...) {  // nothing escapes a pool's handler (read_finer logs its own failures)
      }
    });
  });
}

std::vector<std::filesystem::path> read_roots(const ServerConfig& c) {
  std::vector<std::filesystem::path> roots = c.data_dirs;
  if (!c.upload_dir.empty()) roots.push_back(c.upload_dir);
  // The operator named them: a preloaded volume's folder may be read (a header's data file beside it).
  for (const auto& v : c.volumes) roots.push_back(std::filesystem::absolute(v).parent_path());
  return roots;
}

PngLocator AppContext::png_locator() const {
  return [dirs = config.data_dirs](const std::string& png) {
    if (dirs.empty()) throw SceneError("render.ray_texture.png: the server has no data directory to read PNGs from");
    try {
      return resolve_in_roots(png, dirs);
    } catch (const VolumeError& e) {
      throw SceneError(std::string("render.ray_texture.png: ") + e.what());
    }
  };
}

}  // namespace peakcast::net
