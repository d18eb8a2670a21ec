// Shader loading: #line markers make errors name file and line; programs are cached by key;
// the std140 block matches render/ray_uniforms.h; the variant key follows the scene.
#include <fstream>

#include "gpu/gpu_fixture.h"
#include "gpu/uniform_layout.h"
#include "render/ray_uniforms.h"
#include "unit/test_util.h"

using namespace peakcast;

namespace {

TEST(ShaderCache, CompileErrorNamesFileAndLine) {
  test::gpu();
  test::TempDir dir;
  std::ofstream(dir / "main.frag") << "#include \"helper.glsl\"\nout vec4 c;\nvoid main() { c = helper(); }\n";
  std::ofstream(dir / "helper.glsl") << "vec4 helper() {\n  return vec4(1.0);\n  this is not glsl;\n}\n";
  gpu::ShaderCache cache(dir.path());
  try {
    cache.get("broken", {"main.frag"}, {});
    FAIL() << "compiled a broken shader";
  } catch (const gpu::ShaderError& e) {
    EXPECT_NE(std::string(e.what()).find("helper.glsl:3"), std::string::npos) << e.what();
  }
}

TEST(ShaderCache, ProgramsAreCachedByKey) {
  auto& g = test::gpu();
  render::VariantKey k;
  const auto& a = g.gl->program(k);  // compiled now or by an earlier test
  const size_t compiles = g.shaders->compiles(), size = g.shaders->size();
  const auto& b = g.gl->program(k);
  EXPECT_EQ(a.id(), b.id());
  EXPECT_EQ(g.shaders->compiles(), compiles) << "a second get() of the same key must not compile again";
  EXPECT_EQ(g.shaders->size(), size);
  // A new key compiles exactly once.
  render::VariantKey other = k;
  other.shading = !k.shading;
  other.tricubic = !k.tricubic;
  const auto& c = g.gl->program(other);
  const size_t after_other = g.shaders->compiles();
  EXPECT_LE(after_other, compiles + 1);
  EXPECT_EQ(g.gl->program(other).id(), c.id());
  EXPECT_EQ(g.shaders->compiles(), after_other);
}

TEST(ShaderCache, UniformBlockOffsetsMatchTheHostStruct) {
  auto& g = test::gpu();
  for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute}) {
    render::VariantKey k;
    k.path = path;
    k.space_skipping = k.shading = k.tricubic = true;
    const auto offsets = gpu::uniform_offsets(g.gl->program(k));
    const auto host = render::host_uniform_offsets();
    ASSERT_EQ(offsets.size(), host.size());
    for (const auto& [name, off] : host) {
      ASSERT_TRUE(offsets.count(name)) << name;
      EXPECT_EQ(offsets.at(name), off) << name;
    }
    EXPECT_EQ(gpu::uniform_block_size(g.gl->program(k)), sizeof(ray::RayUniforms));
  }
}

TEST(Variant, ChosenFromTheScene) {
  auto v = test::make_volume(GeneratorKind::Blobs, {20, 20, 20}, SourceType::U8);
  ResolvedScene s = test::make_scene(*v, {{"render", {{"filter", "tricubic"}, {"shading", true}}}});
  auto k = render::choose_variant(s, 0, render::RenderPath::Fragment);
  EXPECT_TRUE(k.tricubic);
  EXPECT_TRUE(k.shading);
  EXPECT_FALSE(k.space_skipping) << "dense volume: no macrocell loop";
  EXPECT_TRUE(render::choose_variant(s, 5, render::RenderPath::Fragment).space_skipping);
  s.scene.render.space_skipping = false;
  EXPECT_FALSE(render::choose_variant(s, 5, render::RenderPath::Fragment).space_skipping);
  EXPECT_EQ(k.name(), "frag+tricubic+shade");
}

}  // namespace
