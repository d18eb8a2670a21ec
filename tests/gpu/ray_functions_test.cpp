// The two targets of the shared ray code (shaders/ray/), held together function by function: a
// table of cases (ray_functions/cases.glsl: rays through pixels at the image's corners and
// edges, axis-parallel and missing rays, chord ends, opacity steps across 0 and 1, composite
// sequences across opacity edges, Catmull-Rom windows, peak roots near tangencies, brick faces,
// clip spans, consume and peak finding, the virtual-sample window) run by a GL compute shader
// and by the C++ build of the same source, under four variants (Config). Measured on
// llvmpipe: equal bit for bit but where GL divides, takes roots or powers otherwise than libm
// (kBound). A function changed in one target only (the lattice's step in GL's copy) fails the
// comparison (BreakingOneTargetFails).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <glm/geometric.hpp>

#include "gpu/compute_table.h"
#include "gpu/gpu_fixture.h"
#include "render/ray_uniforms.h"
#include "render/shader_interface.h"
#include "unit/test_util.h"

namespace peakcast {
namespace {

namespace fs = std::filesystem;
using namespace peakcast::ray;

// Where the probe's generated GLSL goes (one folder per test binary run is not needed: the files
// are rewritten each time).
fs::path probe_dir() {
  const fs::path dir = fs::path(PEAKCAST_ARTIFACT_DIR) / "ray_functions";
  fs::create_directories(dir);
  return dir;
}

// The C++ build of the shared code, with the table's hooks (in a namespace of its own: its Ray is
// the shared one, not core's).
#define NO_PEAK_TEXEL (::peakcast::render::kNoPeakTexel)
namespace probe {
#include "ray/types.glsl"
struct Probe {
  const RayUniforms& P;
  const Variant V;
#include "ray/ray_setup.glsl"
#include "gpu/ray_functions/hooks.glsl"
#include "ray/lattice.glsl"
#include "ray/compositing.glsl"
#include "ray/shading.glsl"
#include "ray/catmull_rom.glsl"
#include "ray/peaks.glsl"
#include "ray/brick.glsl"
#include "ray/projection.glsl"
#include "ray/consume.glsl"
#include "gpu/ray_functions/cases.glsl"
};
}  // namespace probe
using probe::Probe;

// The variants the table runs under: perspective with differential and adaptive sampling, shading
// and virtual samples; orthographic, uniform; peaks (xor) shaded; preintegration; a maximum
// intensity projection (perspective, differential); a mean projection with virtual samples
// (orthographic).
enum class Config { Persp, Ortho, Peaks, Preint, Mip, Mean };
const Config kConfigs[] = {Config::Persp, Config::Ortho, Config::Peaks, Config::Preint, Config::Mip, Config::Mean};
const char* name(Config c) {
  const char* n[] = {"persp", "ortho", "peaks", "preint", "mip", "mean"};
  return n[int(c)];
}
bool ortho(Config c) { return c == Config::Ortho || c == Config::Preint || c == Config::Mean; }

RayUniforms uniforms(Config config) {
  const bool ortho = peakcast::ortho(config);
  RayUniforms u{};
  u.box_half = vec3(8.0f, 9.0f, 7.2f);
  u.spacing = vec3(1.0f, 1.125f, 0.8f);
  u.inv_spacing = 1.0f / u.spacing;
  u.min_spacing = 0.8f;
  u.sample_half = u.box_half;
  const vec3 forward = glm::normalize(vec3(-0.5f, -0.4f, -0.77f));
  const vec3 right = glm::normalize(glm::cross(forward, vec3(0.0f, 1.0f, 0.0f)));
  u.forward = forward;
  u.right = right;
  u.up = glm::cross(right, forward);
  u.p0 = vec3(0.3f, -0.2f, 0.1f);
  u.eye_distance = 40.0f;
  u.image_width = 64;
  u.image_height = 48;
  u.half_height = ortho ? 12.0f : std::tan(0.2617994f);
  u.half_width = u.half_height * 64.0f / 48.0f;
  u.step = 0.5f;
  u.stop = 0.99f;
  u.sample_cap = 100000;
  u.clip_box = 1;
  u.clip_lo = vec3(-6.0f, -9.5f, -5.0f);
  u.clip_hi = vec3(7.0f, 4.0f, 8.0f);
  u.clip_plane = 1;
  u.clip_normal = glm::normalize(vec3(0.3f, 0.9f, -0.2f));
  u.clip_offset = -2.0f;
  u.peak_bins = 64;
  u.peak_layers = 1;
  u.max_peaks = 4;
  u.secant_iterations = 4;
  u.tf_point_count = 4;
  u.differential_k = 0.5f;
  u.min_step = 0.1f;
  u.own_lo = vec3(4.0f, 3.0f, 5.0f);  // the brick [4, 12) x [3, 17) x [5, 11) of voxels 0..15 x 0..16 x 0..17
  u.own_hi = vec3(12.0f, 17.0f, 11.0f);
  u.open_hi = 2;  // y ends at the volume's last voxel: no bound there
  return u;
}

Variant variant(Config c) {
  Variant v{};
  v.orthographic = ortho(c);
  v.differential = !ortho(c);
  v.projection = c == Config::Mip ? Probe::kProjectionMax : c == Config::Mean ? Probe::kProjectionMean : 0;
  v.shading = c != Config::Ortho && v.projection == 0;
  v.adaptive = c == Config::Persp;
  v.virtual_samples = c == Config::Persp || c == Config::Mean ? 3 : 0;
  v.peaks = v.peak_xor = c == Config::Peaks;
  v.preintegration = c == Config::Preint;
  v.segments = v.peaks || v.preintegration || v.virtual_samples != 0;
  v.ray_texture = true;  // the table's weights are not 1
  return v;
}

std::vector<std::string> defines(Config c, int rows) {
  std::vector<std::string> d = render::interface_defines();  // UBO_RAY, NO_PEAK_TEXEL
  d.push_back("PROBE_ROWS " + std::to_string(rows));
  const Variant v = variant(c);
  if (v.orthographic) d.push_back("ORTHOGRAPHIC");
  if (v.differential) d.push_back("DIFFERENTIAL");
  if (v.shading) d.push_back("SHADING");
  if (v.adaptive) d.push_back("ADAPTIVE");
  if (v.virtual_samples) d.push_back("VIRTUAL_SAMPLES 3");
  if (v.peaks) d.insert(d.end(), {"PEAKS", "PEAK_XOR"});
  if (v.preintegration) d.push_back("PREINTEGRATION");
  if (v.ray_texture) d.push_back("RAY_TEXTURE");
  if (v.projection) d.push_back("PROJECTION " + std::to_string(v.projection));
  return d;
}

// Rows of 16 floats: k (kind and three more inputs), a, b, c. The rays, their spans and lattices
// are the C++ build's (make_ray, intersect_box, ray_lattice through pixels at the corners, the
// edges, the centre and at random), given to both targets alike; other inputs sit on the
// functions' edges (opacity 0 and 1, a flat gradient, a tangency, brick faces).
std::vector<float> table(Config config) {
  const RayUniforms u = uniforms(config);
  Probe p{u, variant(config)};
  std::mt19937 rng(45);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const float pixels[][2] = {{0.5f, 0.5f},   {63.5f, 0.5f},  {0.5f, 47.5f},   {63.5f, 47.5f},
                             {32.0f, 24.0f}, {31.5f, 23.5f}, {-20.0f, 24.0f}, {32.0f, 90.0f}};
  const float edges[] = {0.0f, 1.0f, 1e-7f, 0.9999999f};
  std::vector<float> rows;
  for (int kind = 0; kind < Probe::kKinds; ++kind)
    for (int n = 0; n < 96; ++n) {
      const float px = n < 8 ? pixels[n][0] : 64.0f * u01(rng), py = n < 8 ? pixels[n][1] : 48.0f * u01(rng);
      const probe::Ray ray = p.make_ray(vec2(px, py));
      const vec2 box = p.intersect_box(ray);
      const probe::Lattice L = p.ray_lattice(ray, box.x);
      const bool hit = box.x <= box.y;
      const int last = hit ? int(std::floor(p.lattice_index(L, box.y))) : 0;
      const float f = u01(rng), g = u01(rng), h = u01(rng), e = edges[n % 4];
      vec4 k(float(kind), 0.0f, 0.0f, 0.0f), a(ray.o, ray.t_eye), b(ray.d, 0.0f), c(L.t0, L.A, L.B, box.y);
      const float t_in = hit ? box.x + f * (box.y - box.x) : f;
      switch (kind) {
        case Probe::kMakeRay: a = vec4(px, py, 0.0f, 0.0f); break;
        case Probe::kSpans: k = vec4(float(kind), box.x, box.y, 0.0f); break;
        case Probe::kLattice:
          k = vec4(float(kind), std::floor(g * float(last + 1)), 1.0f + std::floor(8.0f * h), box.x);
          c.w = t_in;
          break;
        case Probe::kChord:
          k = vec4(float(kind), float(last), std::floor(g * float(last + 1)), 1.0f + std::floor(8.0f * h));
          break;
        case Probe::kOpacity:
          a = vec4(n % 3 == 0 ? e : f, 0.5f * (0.25f + 3.0f * g), h, n % 2 ? 0.5f : 0.01f + 2.0f * f);
          c = vec4(0.3f * h, 0.2f * h, 0.1f * h, std::max(h, 1e-6f));
          break;
        case Probe::kComposite:
          a = vec4(e, f, g, 1.0f - e);
          c = vec4(h, edges[(n + 1) % 4], g * h, 0.5f);
          break;
        case Probe::kShade:
          c = vec4(f, g, h, 0.0f);
          a = n % 5 == 0 ? vec4(0.0f) : vec4(f - 0.5f, g - 0.5f, h - 0.5f, 0.0f) * (n % 7 == 0 ? 1e-6f : 1.0f);
          break;
        case Probe::kCatmullRom:
          k = vec4(float(kind), n % 8 == 0 ? 0.0f : (n % 8 == 1 ? 1.0f : f), g, 0.0f);
          c = vec4(g, h, f, e);
          break;
        case Probe::kPeakRoot:
          k = vec4(float(kind), box.x + f * (box.y - box.x), box.x + g * (box.y - box.x), 0.0f);
          c = vec4(h, n % 4 == 0 ? 0.0f : (n % 4 == 1 ? 1e-6f : (n % 4 == 2 ? -1e-6f : 0.0f)), 1.2f * f - 0.1f,
                   1.2f * g - 0.1f);
          break;
        case Probe::kFindPeaks:
          k = vec4(float(kind), box.x + f * (box.y - box.x), box.x + g * (box.y - box.x), 0.0f);
          c = vec4(h, n % 5 == 0 ? 1.0f / 3.0f : e, f, g);  // values across 1/3 and 2/3, on a peak, on the ends
          break;
        case Probe::kConsume:
          k = vec4(float(kind), hit ? box.x : 0.0f, 0.25f + g, 0.0f);
          c = vec4(f, n % 4 == 0 ? 0.3f : g, n % 4 == 1 ? 0.8f : h, e);  // values on the TF's opacity edges
          a.w = 1.0f - f;
          break;
        case Probe::kProject:
          k = vec4(float(kind), hit ? box.x : 0.0f, 0.25f + g, 0.0f);
          c = vec4(f, n % 4 == 0 ? 1.0f : g, n % 4 == 1 ? 0.0f : h, e);  // values at the range's ends
          a.w = 1.0f - f;
          break;
        case Probe::kWindow:
          k = vec4(float(kind), float(last), std::floor(g * float(last + 1)), 0.0f);
          c.w = hit ? std::min(box.y, p.lattice_t(L, float(std::min(last, 40))) + 0.5f * L.B) : 0.0f;
          break;
        case Probe::kBrick:
          k = vec4(float(kind), box.x, box.y, float(hit ? last : -1));
          c.w = std::floor(g * float(last + 1));
          a.w = h;
          break;
      }
      for (const vec4& v : {k, a, b, c})
        for (int q = 0; q < 4; ++q) rows.push_back(v[q]);
    }
  return rows;
}

std::vector<float> run_cpu(Config config, const std::vector<float>& rows) {
  const RayUniforms u = uniforms(config);
  Probe probe{u, variant(config)};
  std::vector<float> out;
  for (size_t i = 0; i + 16 <= rows.size(); i += 16) {
    auto v4 = [&](size_t k) { return vec4(rows[i + k], rows[i + k + 1], rows[i + k + 2], rows[i + k + 3]); };
    vec4 r0, r1;
    probe.run_case(v4(0), v4(4), v4(8), v4(12), r0, r1);
    for (int k = 0; k < 4; ++k) out.push_back(r0[k]);
    for (int k = 0; k < 4; ++k) out.push_back(r1[k]);
  }
  return out;
}

// The probe's GLSL: probe.comp.in with the hooks and cases at their paths, and `lattice` as the
// lattice file it includes (the shared one, or a broken copy).
std::vector<float> run_gl(Config config, const std::vector<float>& rows, const std::string& key,
                          const fs::path& lattice = "ray/lattice.glsl") {
  const fs::path src = fs::path(PEAKCAST_SOURCE_DIR) / "tests/gpu/ray_functions";
  std::ifstream in(src / "probe.comp.in");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  auto fill = [&](const std::string& from, const std::string& to) { s.replace(s.find(from), from.size(), to); };
  fill("@HOOKS@", (src / "hooks.glsl").string());
  fill("@CASES@", (src / "cases.glsl").string());
  fill("ray/lattice.glsl", lattice.string());
  const fs::path comp = probe_dir() / (key + ".comp");
  std::ofstream(comp) << s;
  const int n = int(rows.size() / 16);
  const gpu::Program& program = test::gpu().shaders->get(key, {comp.string()}, defines(config, n));
  const RayUniforms u = uniforms(config);
  gpu::ComputeTable t;
  t.uniforms = &u;
  t.uniform_bytes = sizeof u;
  t.ubo_binding = render::kUboRay;
  t.in = rows;
  t.out_floats = size_t(n) * 8;
  t.rows = n;
  return gpu::run_compute_table(program, t);
}

struct KindDiff {
  int rows = 0, unequal = 0, answered = 0;  // answered: rows with a non-zero result (the case is not idle)
  double worst = 0;                         // |a - b| / max(1, |b|)
};

std::vector<KindDiff> compare(const std::vector<float>& rows, const std::vector<float>& gl,
                              const std::vector<float>& cpu) {
  std::vector<KindDiff> d(Probe::kKinds);
  for (size_t r = 0; r < rows.size() / 16; ++r) {
    KindDiff& k = d[size_t(rows[r * 16])];
    ++k.rows;
    bool unequal = false, answered = false;
    for (size_t c = 0; c < 8; ++c) answered = answered || cpu[r * 8 + c] != 0.0f;
    k.answered += answered ? 1 : 0;
    for (size_t c = 0; c < 8; ++c) {
      const float a = gl[r * 8 + c], b = cpu[r * 8 + c];
      if (a == b || (std::isnan(a) && std::isnan(b))) continue;
      unequal = true;
      const double e =
          std::isfinite(a) && std::isfinite(b) ? std::abs(double(a) - b) / std::max(1.0, std::abs(double(b))) : 1e30;
      k.worst = std::max(k.worst, e);
    }
    k.unequal += unequal ? 1 : 0;
    if (unequal && std::getenv("PEAKCAST_PRINT_ROWS")) {
      std::printf("row %zu kind %d:", r, int(rows[r * 16]));
      for (size_t c = 0; c < 8; ++c) std::printf(" %.9g/%.9g", gl[r * 8 + c], cpu[r * 8 + c]);
      std::printf("\n");
    }
  }
  return d;
}

// Relative differences allowed per kind (measured on llvmpipe, both variants, in brackets).
// Exact: what takes only products, sums and comparisons (chord ends, compositing, Catmull-Rom,
// a brick's points). One or two roundings apart: what divides, takes a square root or a power,
// which llvmpipe computes otherwise than libm (a / b as a * (1 / b), pow as exp2(y log2 x)):
// make_ray (1.9e-7), spans (8.1e-7), lattice (1.2e-7), opacity (1.8e-7), shade (3.9e-7), consume
// over six samples (8.3e-7), the virtual-sample window over a run (4.2e-7). A projection over six
// samples takes products, sums, comparisons and the TF's exact interpolation (a division): one
// rounding apart where it divides. A peak's root (2.0e-5) is regula falsi on a
// field that is nearly flat near a tangency, where a value one rounding apart moves the root by its error over the
// slope; find_peaks (7.5e-8) solves roots too, so it is held to the same bound.
const double kBound[] = {1e-6, 2e-6, 1e-6, 0.0, 1e-6, 0.0, 1e-6, 0.0, 1e-4, 0.0, 1e-4, 2e-6, 2e-6, 1e-6};

const char* const kNames[] = {"make_ray",    "spans",     "lattice", "chord",      "opacity", "composite", "shade",
                              "catmull_rom", "peak_root", "brick",   "find_peaks", "consume", "window",    "project"};

TEST(RayFunctions, GlslAndCxxAgreeRowByRow) {
  PEAKCAST_GL_ONLY();
  for (Config config : kConfigs) {
    const std::vector<float> rows = table(config);
    const auto gl = run_gl(config, rows, std::string("ray-functions-") + name(config));
    const auto cpu = run_cpu(config, rows);
    ASSERT_EQ(gl.size(), cpu.size());
    const auto d = compare(rows, gl, cpu);
    for (int k = 0; k < Probe::kKinds; ++k) {
      std::printf("%-6s %-12s rows %3d, answered %3d, unequal %3d, worst relative difference %.2e\n", name(config),
                  kNames[k], d[size_t(k)].rows, d[size_t(k)].answered, d[size_t(k)].unequal, d[size_t(k)].worst);
      EXPECT_GE(d[size_t(k)].answered, d[size_t(k)].rows / 2) << kNames[k] << ": most rows must ask something";
      // A GPU's GLSL may fuse multiply-adds and divide approximately where llvmpipe does neither:
      // there the exact kinds are held to one rounding's worth.
      const bool software = test::gpu().context->info().software;
      const double bound = kBound[k] == 0.0 && !software ? 2e-6 : kBound[k];
      EXPECT_LE(d[size_t(k)].worst, bound) << kNames[k];
      if (bound == 0.0) EXPECT_EQ(d[size_t(k)].unequal, 0) << kNames[k];
    }
  }
}

TEST(RayFunctions, BreakingOneTargetFails) {
  PEAKCAST_GL_ONLY();
  // GL's copy of the lattice with a slip in the differential step (j + m / 4 for j + m / 2).
  std::ifstream in(fs::path(PEAKCAST_SOURCE_DIR) / "shaders/ray/lattice.glsl");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string from = "m * (L.B + L.A * (j + 0.5f * m))";
  ASSERT_NE(s.find(from), std::string::npos);
  s.replace(s.find(from), from.size(), "m * (L.B + L.A * (j + 0.25f * m))");
  const fs::path broken = probe_dir() / "broken_lattice.glsl";
  std::ofstream(broken) << s;
  const std::vector<float> rows = table(Config::Persp);
  const auto d =
      compare(rows, run_gl(Config::Persp, rows, "ray-functions-broken", broken), run_cpu(Config::Persp, rows));
  EXPECT_GT(d[Probe::kLattice].worst, kBound[Probe::kLattice]);
  EXPECT_GT(d[Probe::kChord].unequal, 0);  // the chord ends use the step too
  EXPECT_GT(d[Probe::kLattice].unequal, 0);
}

}  // namespace
}  // namespace peakcast
