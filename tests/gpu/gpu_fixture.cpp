#include "gpu/gpu_fixture.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "cpu/cpu_renderer.h"
#include "encode/png.h"

namespace peakcast::test {

bool cpu_backend() {
  const char* b = std::getenv("PEAKCAST_TEST_BACKEND");
  return b && std::string(b) == "cpu";
}

Gpu& gpu() {
  static Gpu g = [] {
    Gpu x;
    if (cpu_backend()) {
      auto cpu = std::make_unique<TestCpuRenderer>();
      x.cpu = cpu.get();
      x.switches = cpu.get();
      x.caster = std::move(cpu);
    } else {
      x.context = gpu::EglContext::create();
      x.shaders = std::make_unique<gpu::ShaderCache>(std::filesystem::path(PEAKCAST_SOURCE_DIR) / "shaders");
      auto gl = std::make_unique<render::Switchable<gpu::GlRenderer>>(*x.shaders);
      x.gl = gl.get();
      x.switches = gl.get();
      x.caster = std::move(gl);
    }
    std::printf("renderer: %s\n", x.caster->description().c_str());
    return x;
  }();
  return g;
}

TestVolume::TestVolume(std::shared_ptr<const Volume> v, VolumeMacrocells cells)
    : r_(gpu().caster->make_resident(std::move(v), std::move(cells))) {}

ResolvedScene make_scene(const Volume& v, const nlohmann::json& overrides) {
  nlohmann::json j = {{"volume", "test"}, {"image", {{"width", 96}, {"height", 80}}}};
  j.merge_patch(overrides);
  return resolve_scene(parse_scene(j), v);
}

std::shared_ptr<Volume> make_volume(GeneratorKind kind, Dims dims, SourceType type, glm::dvec3 spacing) {
  GeneratorSpec s;
  s.kind = kind;
  s.dims = dims;
  s.type = type;
  s.spacing = spacing;
  return std::make_shared<Volume>(generate_volume(s));
}

Image render_gpu(const render::ResidentVolume& gv, const ResolvedScene& s, render::RenderPath path,
                 render::RenderStats* st) {
  return gpu().caster->render(gv, s, path, st);
}

void save_artifacts(const Image& actual, const Image& expected, const std::string& tag) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name() + "." + tag;
  for (auto& c : name)
    if (c == '/') c = '_';
  const std::filesystem::path dir = PEAKCAST_ARTIFACT_DIR;
  std::filesystem::create_directories(dir);
  encode::write_png(actual, dir / (name + ".actual.png"));
  encode::write_png(expected, dir / (name + ".expected.png"));
  Image diff(actual.width, actual.height);
  for (size_t i = 0; i < diff.rgba.size(); ++i)
    diff.rgba[i] = i % 4 == 3 ? 1.f : std::min(1.f, 10.f * std::abs(actual.rgba[i] - expected.rgba[i]));
  encode::write_png(diff, dir / (name + ".diff_x10.png"));
}

bool all_finite(const Image& img) {
  for (float v : img.rgba)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace peakcast::test

namespace {
// Every test in a GPU binary needs the context current before it creates GL objects (and the
// renderer line printed first).
class GpuEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { peakcast::test::gpu(); }
};
[[maybe_unused]] auto* const kGpuEnvironment = ::testing::AddGlobalTestEnvironment(new GpuEnvironment);
}  // namespace
