// Shader programs ready before they are needed: kept on disk as driver binaries (a later
// ShaderCache, like a later process, loads instead of compiling; a damaged or foreign file is
// compiled again and rewritten; a folder that cannot be written costs nothing but the saving),
// and built on a background thread with a shared context when prefetched.
#include <filesystem>
#include <fstream>

#include "gpu/gpu_fixture.h"
#include "unit/test_util.h"

using namespace peakcast;
namespace fs = std::filesystem;

namespace {

const fs::path kShaders = fs::path(PEAKCAST_SOURCE_DIR) / "shaders";

// A real variant of the ray caster: big enough that compiling it costs something.
render::VariantKey variant(bool shading) {
  render::VariantKey k;
  k.shading = shading;
  k.peaks = true;
  k.tricubic = true;
  return k;
}

const gpu::Program& get(gpu::ShaderCache& cache, const render::VariantKey& k) {
  return cache.get(k.name(), {"fullscreen.vert", "raycast.frag"}, k.defines());
}

std::vector<fs::path> files(const fs::path& dir) {
  std::vector<fs::path> out;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path());
  return out;
}

}  // namespace

TEST(ProgramCache, ALaterCacheLoadsWhatAnEarlierOneCompiled) {
  PEAKCAST_GL_ONLY();
  test::gpu();
  test::TempDir dir;
  const fs::path bins = dir / "programs";
  {
    gpu::ShaderCache first(kShaders, bins);
    get(first, variant(true));
    EXPECT_EQ(first.compiles(), 1u);
    EXPECT_EQ(first.loads(), 0u);
  }
  const auto saved = files(bins);
  if (saved.empty()) GTEST_SKIP() << "this driver keeps no program binaries (GL_NUM_PROGRAM_BINARY_FORMATS 0)";
  ASSERT_EQ(saved.size(), 1u);
  {
    gpu::ShaderCache later(kShaders, bins);
    get(later, variant(true));
    EXPECT_EQ(later.compiles(), 0u) << "compiled again instead of loading " << saved[0];
    EXPECT_EQ(later.loads(), 1u);
    // Another variant is another file.
    get(later, variant(false));
    EXPECT_EQ(later.compiles(), 1u);
    EXPECT_EQ(files(bins).size(), 2u);
  }
  // A damaged file (cut short) and a foreign one (another driver's bytes) are compiled again
  // and rewritten whole.
  const auto size = fs::file_size(saved[0]);
  fs::resize_file(saved[0], size / 2);
  {
    gpu::ShaderCache damaged(kShaders, bins);
    get(damaged, variant(true));
    EXPECT_EQ(damaged.compiles(), 1u);
    EXPECT_EQ(damaged.loads(), 0u);
  }
  EXPECT_EQ(fs::file_size(saved[0]), size);
  {
    std::fstream f(saved[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(16);
    const std::string junk(256, '\x5a');
    f.write(junk.data(), std::streamsize(junk.size()));
  }
  {
    gpu::ShaderCache foreign(kShaders, bins);
    EXPECT_NO_THROW(get(foreign, variant(true)));
    EXPECT_EQ(foreign.compiles(), 1u);
  }
}

TEST(ProgramCache, AFolderThatCannotBeWrittenOnlyCostsTheSaving) {
  PEAKCAST_GL_ONLY();
  test::gpu();
  test::TempDir dir;
  std::ofstream(dir / "a-file") << "x";  // a file where the folder should be
  gpu::ShaderCache cache(kShaders, dir / "a-file" / "programs");
  EXPECT_NO_THROW(get(cache, variant(true)));
  EXPECT_EQ(cache.compiles(), 1u);
}

TEST(ProgramCache, PrefetchBuildsOnAnotherThreadAndGetWaitsForIt) {
  PEAKCAST_GL_ONLY();
  auto& g = test::gpu();
  gpu::ShaderCache cache(kShaders, {}, g.context.get());
  const render::VariantKey k = variant(true);
  cache.prefetch(k.name(), {"fullscreen.vert", "raycast.frag"}, k.defines());
  cache.prefetch(k.name(), {"fullscreen.vert", "raycast.frag"}, k.defines());  // once is enough
  for (int i = 0; i < 600 && !cache.ready(k.name()); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(cache.ready(k.name()));
  const gpu::Program& p = get(cache, k);
  EXPECT_NE(p.id(), 0u);
  EXPECT_EQ(cache.compiles(), 0u) << "the render thread compiled what the background had built";
  EXPECT_EQ(cache.background_builds(), 1u);
  // A program the background built draws here: the shared context's program in this one.
  GLint linked = 0;
  glGetProgramiv(p.id(), GL_LINK_STATUS, &linked);
  EXPECT_EQ(linked, GL_TRUE);
  // get() right after prefetch: it waits for the build or builds itself, never twice.
  const render::VariantKey other = variant(false);
  cache.prefetch(other.name(), {"fullscreen.vert", "raycast.frag"}, other.defines());
  get(cache, other);
  EXPECT_EQ(cache.compiles() + cache.background_builds(), 2u);
}

TEST(ProgramCache, APrefetchedShaderThatFailsThrowsWhereItIsUsed) {
  PEAKCAST_GL_ONLY();
  auto& g = test::gpu();
  test::TempDir dir;
  std::ofstream(dir / "bad.frag") << "out vec4 c;\nvoid main() { c = nonsense; }\n";
  gpu::ShaderCache cache(dir.path(), {}, g.context.get());
  cache.prefetch("bad", {"bad.frag"}, {});
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // most likely failed by now
  EXPECT_FALSE(cache.ready("bad"));
  try {
    cache.get("bad", {"bad.frag"}, {});
    FAIL() << "a broken shader was used";
  } catch (const gpu::ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.frag:2"), std::string::npos) << e.what();
  }
}
