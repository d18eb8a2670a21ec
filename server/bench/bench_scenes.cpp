#include "bench/bench_scenes.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "core/generators.h"
#include "core/volume_io.h"

namespace peakcast::bench {

std::shared_ptr<Volume> bench_volume(const std::string& what) {
  if (std::filesystem::exists(what)) return std::make_shared<Volume>(load_volume(what));
  GeneratorSpec s;
  s.kind = parse_generator_kind(what);
  s.type = default_type(s.kind);
  s.dims = s.kind == GeneratorKind::MarschnerLobb ? Dims{128, 128, 128} : Dims{256, 256, 256};
  return std::make_shared<Volume>(generate_volume(s));
}

ResolvedScene bench_scene(const Volume& vol, int size, const std::string& filter) {
  const double lo = vol.min_value, hi = vol.max_value;
  nlohmann::json j = {
      {"volume", "bench"}, {"image", {{"width", size}, {"height", size}}}, {"render", {{"filter", filter}}}};
  j["tf"] = {{"points",
              {{lo, 0, 0, 0, 0},
               {lo + 0.3 * (hi - lo), 0.2, 0.4, 1.0, 0.0},
               {lo + 0.6 * (hi - lo), 1.0, 0.8, 0.4, 0.3},
               {hi, 1, 1, 1, 0.6}}}};
  ResolvedScene s = resolve_scene(parse_scene(j), vol);
  const glm::dvec3 c = s.camera.center;
  s.camera.eye = c + (s.camera.eye - c).z * glm::dvec3(0.55, 0.45, 0.7);
  return s;
}

Camera orbit_camera(const Camera& c, double deg) {
  const glm::dmat4 rot = glm::rotate(glm::dmat4(1.0), glm::radians(deg), glm::normalize(c.up));
  Camera o = c;
  o.eye = c.center + glm::dvec3(rot * glm::dvec4(c.eye - c.center, 0.0));
  return o;
}

BenchRenderer make_bench_renderer() {
  BenchRenderer r;
  static_cast<render::RenderBackend&>(r) = render::open_backend(render::requested_backend());
  if (r.backend == render::Backend::Cpu) {
    r.renderer = make_bare_cpu_renderer(r.bench);
  } else {
#ifdef PEAKCAST_HAVE_GL
    r.renderer = make_bare_gl_renderer(*r.device->shaders(), r.bench);
#else
    throw std::logic_error("a GL backend in a build without GL");
#endif
  }
  std::fprintf(stderr, "renderer: %s\n", r.description().c_str());  // stdout may be --json
  return r;
}

}  // namespace peakcast::bench
