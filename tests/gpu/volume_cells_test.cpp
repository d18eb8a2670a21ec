// Macrocell grids off the render thread: the store builds them with the
// volume on the loader pool, the backend's resident volume takes them and builds nothing on the
// render thread.
#include <filesystem>

#include "core/volume_writer.h"
#include "cpu/cpu_renderer.h"
#include "gpu/gpu_fixture.h"
#include "render/backend.h"
#include "session/residency.h"
#include "session/volume_store.h"

using namespace peakcast;

namespace {

ResolvedScene scene(const Volume& v, const char* filter) {
  const double lo = v.min_value, hi = v.max_value;
  return test::make_scene(
      v, {{"tf", {{"points", {{lo, 0, 0, 0, 0}, {lo + 0.5 * (hi - lo), 1, 0.5, 0.2, 0.0}, {hi, 1, 1, 1, 0.8}}}}},
          {"render", {{"filter", filter}}}});
}

}  // namespace

// A 40x33x21 blobs volume loaded through the server's store (from a NRRD in a scratch directory).
struct Stored {
  std::shared_ptr<Volume> v = test::make_volume(GeneratorKind::Blobs, {40, 33, 21}, SourceType::U8);
  Residency residency{int64_t(1) << 30};
  std::unique_ptr<VolumeStore> store;
  std::shared_ptr<VolumeEntry> e;
  Stored() {
    const auto dir = std::filesystem::temp_directory_path() / ("peakcast_cells_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    write_volume(dir / "b.nrrd", *v);
    store = std::make_unique<VolumeStore>(std::vector<std::filesystem::path>{dir}, residency);
    e = store->get("b.nrrd");
    std::filesystem::remove_all(dir);
  }
};

TEST(VolumeCells, StoreBuildsBothGridsWithTheVolume) {
  Stored st;
  auto& e = st.e;
  ASSERT_TRUE(e->macrocells.trilinear && e->macrocells.tricubic);
  const MacrocellGrid want_lin = build_macrocells(*e->volume, 0, FilterSupport::Trilinear);
  const MacrocellGrid want_cub = build_macrocells(*e->volume, 0, FilterSupport::Tricubic);
  EXPECT_EQ(e->macrocells.trilinear->min, want_lin.min);
  EXPECT_EQ(e->macrocells.trilinear->max, want_lin.max);
  EXPECT_EQ(e->macrocells.tricubic->min, want_cub.min);
  EXPECT_EQ(e->macrocells.tricubic->max, want_cub.max);
  EXPECT_EQ(e->macrocells.trilinear->stddev, want_lin.stddev);
  EXPECT_EQ(e->macrocells.tricubic->stddev, want_cub.stddev);
}

TEST(VolumeCells, ResidentVolumeUsesTheGivenGridsAndRendersTheSame) {
  auto v = test::make_volume(GeneratorKind::Blobs, {40, 33, 21}, SourceType::U8);
  const VolumeMacrocells cells = build_volume_macrocells(*v);
  test::TestVolume given(v, cells), built(v);
  for (const char* filter : {"trilinear", "tricubic"}) {
    const ResolvedScene s = scene(*v, filter);
    render::RenderStats a, b;
    const Image ia = test::render_gpu(given, s, render::RenderPath::Fragment, &a);
    const Image ib = test::render_gpu(built, s, render::RenderPath::Fragment, &b);
    EXPECT_EQ(ia.rgba, ib.rgba) << filter;
    EXPECT_GT(a.empty_cells, 0) << filter << ": the TF should leave cells empty (skipping in use)";
    EXPECT_EQ(a.empty_cells, b.empty_cells) << filter;
  }
  EXPECT_EQ(&given.macrocells(Filter::Trilinear), cells.trilinear.get());
  EXPECT_EQ(&given.macrocells(Filter::Tricubic), cells.tricubic.get());
  EXPECT_EQ(given.macrocell_ms(), 0.0) << "grids were built on the render thread";
  EXPECT_GT(built.macrocell_ms(), 0.0);
}

TEST(VolumeCells, ResidentVolumeRefusesGridsOfAnotherVolume) {
  auto v = test::make_volume(GeneratorKind::Blobs, {40, 33, 21}, SourceType::U8);
  auto w = test::make_volume(GeneratorKind::Blobs, {40, 33, 40}, SourceType::U8);
  try {
    test::TestVolume gv(v, build_volume_macrocells(*w));
    ADD_FAILURE() << "grids of a 40x33x40 volume were accepted for a 40x33x21 one";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("do not fit the 40x33x21 volume"), std::string::npos) << e.what();
  }
}

// The server keeps the host voxels after the backend's copy is made: its probes read them on
// the loader pool at any time (a GL texture lives in the GPU's memory; on llvmpipe, in host
// memory too). The CPU backend reads integer voxels where they lie, so it makes no copy at all.
// The renders, the entry's metadata and the copy for later frames stay, and no resident volume
// can be made from a volume without voxels (a clear error, no read of freed memory).
TEST(VolumeCells, ResidencyKeepsTheVolumeOnceAfterTheUpload) {
  Stored st;
  auto& v = st.v;
  auto& e = st.e;
  Residency& residency = st.residency;
  ASSERT_TRUE(e->volume->has_voxels());
  const ResolvedScene s = scene(*e->volume, "tricubic");
  test::TestVolume fresh(v);  // the same voxels, kept
  const Image want = test::render_gpu(fresh, s, render::RenderPath::Fragment);
  const render::ResidentVolume& gv = residency.acquire(e, *test::gpu().caster);
  EXPECT_TRUE(e->volume->has_voxels()) << "probes read the host voxels after the upload";
  if (test::cpu_backend()) EXPECT_EQ(gv.resident_bytes(), 0u) << "no second copy of integer voxels";
  EXPECT_EQ(e->volume->byte_size(), v->byte_size()) << "metadata must stay";
  EXPECT_EQ(e->volume->min_value, v->min_value);
  EXPECT_EQ(e->volume->histogram, v->histogram);
  for (const char* filter : {"trilinear", "tricubic"}) {
    const Image got = test::render_gpu(gv, scene(*e->volume, filter), render::RenderPath::Fragment);
    const Image ref = test::render_gpu(fresh, scene(*v, filter), render::RenderPath::Fragment);
    EXPECT_EQ(got.rgba, ref.rgba) << filter;
  }
  EXPECT_EQ(&residency.acquire(e, *test::gpu().caster), &gv) << "a second frame must reuse the copy";
  EXPECT_EQ(test::render_gpu(gv, s, render::RenderPath::Fragment).rgba, want.rgba);
  auto dropped = test::make_volume(GeneratorKind::Blobs, {8, 8, 8}, SourceType::U8);
  dropped->drop_voxels();
  try {
    test::TestVolume again(dropped);
    ADD_FAILURE() << "a resident volume was made from a volume without voxels";
  } catch (const std::invalid_argument& err) {
    EXPECT_NE(std::string(err.what()).find("voxels were dropped"), std::string::npos) << err.what();
  }
}

namespace peakcast {
namespace {

// Each backend draws only its own resident volumes, and says so (no cast of a texture handle to
// host voxels or back); an unknown backend name is refused naming the choices, and a bad
// PEAKCAST_BACKEND names the variable.
TEST(Backends, RefuseAnotherBackendsVolumeAndUnknownNames) {
  auto v = test::make_volume(GeneratorKind::Blobs, {24, 20, 16}, SourceType::U8);
  const ResolvedScene s = test::make_scene(*v, nlohmann::json::object());
  cpu::CpuRenderer cpu_renderer;
  auto cpu_volume = cpu_renderer.make_resident(v);
  if (!test::cpu_backend()) {
    gpu::GlRenderer& gl = *test::gpu().gl;
    auto gl_volume = gl.make_resident(v);
    try {
      gl.render(*cpu_volume, s);
      ADD_FAILURE() << "the GL renderer drew a CPU volume";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("GPU volumes only"), std::string::npos) << e.what();
    }
    try {
      cpu_renderer.render(*gl_volume, s);
      ADD_FAILURE() << "the CPU renderer drew a GPU volume";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("CPU volumes only"), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(cpu_renderer.render(*cpu_volume, s).rgba.size(), 0u);
  EXPECT_EQ(render::parse_backend("cpu"), render::Backend::Cpu);
  EXPECT_EQ(render::parse_backend("gl"), render::Backend::Gl);
  EXPECT_EQ(render::requested_backend("auto"), render::Backend::Auto);
  try {
    render::parse_backend("vulkan");
    ADD_FAILURE() << "an unknown backend was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("choose auto, gl or cpu"), std::string::npos) << e.what();
  }
  setenv("PEAKCAST_BACKEND", "vulkan", 1);
  try {
    render::requested_backend();
    ADD_FAILURE() << "a bad PEAKCAST_BACKEND was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("PEAKCAST_BACKEND"), std::string::npos) << e.what();
  }
  unsetenv("PEAKCAST_BACKEND");
  // A forced cpu backend opens no EGL display at all.
  render::RenderBackend b = render::open_backend(render::Backend::Cpu);
  EXPECT_EQ(b.backend, render::Backend::Cpu);
  EXPECT_EQ(b.device, nullptr);
  EXPECT_EQ(std::string(b.renderer->backend()), "cpu");
}

}  // namespace
}  // namespace peakcast
