#include "net/app_context.h"

#include <cctype>
#include <string>

#include <boost/asio/post.hpp>

#include "core/volume_io.h"
#include "encode/video.h"

namespace peakcast::net {

namespace {

LoadOptions load_options(const ServerConfig& c) {
  LoadOptions o;
  o.memory_budget_bytes = c.memory_budget_bytes;
  return o;
}

}  // namespace

AppContext::AppContext(ServerConfig c)
    : config(std::move(c)),
      residency(config.gpu_budget_bytes),
      volumes(config.data_dirs, residency, load_options(config), config.volume_loader),
      uploads(config.upload_dir, config.upload_limits, volumes),
      render(residency, metrics,
             RenderServiceOptions{config.shader_dir, config.encode_threads,
                                  SchedulerOptions{config.max_queued_stills, config.still_band_samples,
                                                   limits::kStillDelay, config.max_fps},
                                  config.egl_device, config.backend, config.program_cache, config.wrap_renderer,
                                  config.ranks}),
      ws_sessions(config.max_sessions) {
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

std::string path_of(const std::string& target) { return target.substr(0, target.find('?')); }

std::string query_param(const std::string& target, const std::string& key) {
  const auto q = target.find('?');
  if (q == std::string::npos) return "";
  size_t i = q + 1;
  while (i < target.size()) {
    size_t amp = target.find('&', i);
    if (amp == std::string::npos) amp = target.size();
    const std::string pair = target.substr(i, amp - i);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) == key) return eq == std::string::npos ? "" : pair.substr(eq + 1);
    i = amp + 1;
  }
  return "";
}

std::string url_decode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '+') {
      out += ' ';
    } else if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
               std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out += char(std::stoi(s.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

std::string token_from(const std::string& authorization, const std::string& target) {
  const std::string prefix = "Bearer ";
  if (authorization.rfind(prefix, 0) == 0) return authorization.substr(prefix.size());
  return query_param(target, "token");
}

}  // namespace peakcast::net
