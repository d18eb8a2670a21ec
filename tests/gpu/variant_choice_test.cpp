// "Leave out what a scene does not need" (docs/architecture.md): over a table of scenes,
// the variant chosen holds exactly the code the scene uses, and where code is left out that
// could have run (peak finding for a TF without peaks, the macrocell loop when every cell is
// visible), putting it back changes no pixel by more than 1/255.
#include <cmath>
#include <functional>

#include "gpu/gpu_fixture.h"
#include "render/renderer_seam.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

struct VariantCase {
  const char* name;
  json scene;                           // merged over a 48x48 view of Marschner-Lobb 41^3
  std::vector<const char*> has, lacks;  // parts of the variant's name
  std::function<void(render::VariantKey&)> put_back;  // the omitted code, forced in (or null)
};

void PrintTo(const VariantCase& c, std::ostream* os) { *os << c.name; }

const json kSmooth = {{"points", {{0.0, 0.1, 0.2, 0.8, 0.02}, {0.5, 0.9, 0.6, 0.2, 0.2}, {1.0, 1.0, 1.0, 1.0, 0.4}}}};
const json kSparse = {{"points", {{0.0, 0, 0, 0, 0}, {0.6, 0, 0, 0, 0}, {0.8, 0.9, 0.6, 0.2, 0.5}, {1.0, 1, 1, 1, 0.5}}}};
const json kPeak = {{"points", {{0.0, 0.1, 0.2, 0.8, 0.02}, {0.5 - 1e-4, 0.1, 0.2, 0.8, 0.02}, {0.5, 1, 0.3, 0.1, 0.9},
                                {0.5 + 1e-4, 0.1, 0.2, 0.8, 0.02}, {1.0, 0.1, 0.2, 0.8, 0.02}}}};
const json kOrtho = {{"eye", {100, 60, 80}}, {"center", {20, 20, 20}}, {"up", {0, 1, 0}}, {"projection", "orthographic"},
                     {"height", 60}};
const json kTexture = {{"mapping", "view"},
                       {"size", {32, 32}},
                       {"strokes", {{{"channel", "step"}, {"center", {0.5, 0.5}}, {"radius", 0.3}, {"value", 0.5}}}}};

const VariantCase kCases[] = {
    // A smooth TF seen whole: nothing to skip, no peaks, plain trilinear postclassification.
    {"smooth_tf_dense", {{"tf", kSmooth}}, {"+trilinear"},
     {"+peaks", "+skip", "+diff", "+shade", "+tricubic", "+vs", "+raytex", "+preint", "+adaptive"},
     [](render::VariantKey& k) { k.space_skipping = true; }},
    // Peak classification of a TF without peaks: the peak code is left out.
    {"peaks_asked_tf_without_peaks", {{"tf", kSmooth}, {"render", {{"classification", "peaks"}}}}, {}, {"+peaks"},
     [](render::VariantKey& k) { k.peaks = true; }},
    // dvr_only never compiles peak finding, even with peaks in the TF.
    {"peaks_dvr_only", {{"tf", kPeak}, {"render", {{"classification", "peaks"}, {"peak_mode", "dvr_only"}}}}, {}, {"+peaks"},
     nullptr},
    {"peaks_used", {{"tf", kPeak}, {"render", {{"classification", "peaks"}}}}, {"+peaks:dvr+peaks"}, {"+preint"}, nullptr},
    {"preintegration", {{"tf", kSmooth}, {"render", {{"classification", "preint"}}}}, {"+preint"}, {"+peaks"}, nullptr},
    // A TF that hides most cells: the macrocell loop is in.
    {"sparse_tf_skips", {{"tf", kSparse}}, {"+skip"}, {"+peaks"}, nullptr},
    {"skipping_switched_off", {{"tf", kSparse}, {"render", {{"space_skipping", false}}}}, {}, {"+skip"}, nullptr},
    // Orthographic: "differential" is uniform at the footprint, with no differential code (that
    // code grows the step with the perspective footprint, which an orthographic view has not:
    // forced in, it renders a different lattice, so it has no put_back here).
    {"ortho_differential", {{"tf", kSmooth}, {"camera", kOrtho}, {"render", {{"sampling", "differential"}}}}, {"+ortho"},
     {"+diff"}, nullptr},
    {"perspective_differential", {{"tf", kSmooth}, {"render", {{"sampling", "differential"}}}}, {"+diff"}, {"+ortho"}, nullptr},
    {"shading_on", {{"tf", kSmooth}, {"render", {{"shading", true}}}}, {"+shade"}, {}, nullptr},
    {"tricubic_on", {{"tf", kSmooth}, {"render", {{"filter", "tricubic"}}}}, {"+tricubic"}, {"+trilinear"}, nullptr},
    {"virtual_samples_3", {{"tf", kSmooth}, {"render", {{"virtual_samples", 3}}}}, {"+vs3"}, {}, nullptr},
    {"adaptive_on", {{"tf", kSmooth}, {"render", {{"adaptive", true}}}}, {"+adaptive"}, {}, nullptr},
    {"ray_texture_view", {{"tf", kSmooth}, {"render", {{"ray_texture", kTexture}}}}, {"+raytex:view"}, {}, nullptr},
};

class Variants : public ::testing::TestWithParam<VariantCase> {};

TEST_P(Variants, HoldOnlyWhatTheSceneUsesAndOmissionsChangeNoPixel) {
  const VariantCase& c = GetParam();
  static auto v = test::make_volume(GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32);
  static test::TestVolume gv(v);
  json j = {{"image", {{"width", 48}, {"height", 48}}},
            {"camera", {{"eye", {75, 60, 110}}, {"center", {20, 20, 20}}, {"up", {0, 1, 0}}, {"fov_y", 30}}}};
  j.merge_patch(c.scene);
  const ResolvedScene s = test::make_scene(*v, j);
  render::RenderStats st;
  const Image chosen = test::render_gpu(gv, s, render::GpuPath::Fragment, &st);
  EXPECT_EQ(st.variant.rfind(test::cpu_backend() ? "cpu+" : "frag+", 0), 0u) << st.variant << ": the backend's name first";
  for (const char* part : c.has) EXPECT_NE(st.variant.find(part), std::string::npos) << st.variant << " lacks " << part;
  for (const char* part : c.lacks) EXPECT_EQ(st.variant.find(part), std::string::npos) << st.variant << " has " << part;
  if (!c.put_back) return;
  auto& caster = *test::gpu().caster;
  render::RendererSeam::force_variant(caster, c.put_back);
  render::RenderStats full_st;
  const Image full = test::render_gpu(gv, s, render::GpuPath::Fragment, &full_st);
  render::RendererSeam::force_variant(caster, nullptr);
  ASSERT_NE(full_st.variant, st.variant) << "nothing was put back";
  float worst = 0;
  for (size_t i = 0; i < chosen.rgba.size(); ++i) worst = std::max(worst, std::abs(chosen.rgba[i] - full.rgba[i]));
  std::printf("%-30s %-28s vs %-34s max diff %.2e\n", c.name, st.variant.c_str(), full_st.variant.c_str(), worst);
  EXPECT_LE(worst, 1.0f / 255.0f) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Scenes, Variants, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<VariantCase>& i) { return std::string(i.param.name); });

}  // namespace
}  // namespace peakcast
