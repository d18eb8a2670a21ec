#include "render/variant.h"

#include <sstream>

#include "core/transfer_function.h"
#include "render/shader_interface.h"

namespace peakcast::render {

std::vector<std::string> interface_defines() {
  std::ostringstream no_peak;
  no_peak.precision(9);
  no_peak << std::showpoint << kNoPeakTexel;
  return {"UNIT_VOLUME " + std::to_string(kUnitVolume),
          "UNIT_TF " + std::to_string(kUnitTf),
          "UNIT_PEAK_TABLE " + std::to_string(kUnitPeakTable),
          "UNIT_PREINT " + std::to_string(kUnitPreint),
          "UNIT_RAY_TEXTURE " + std::to_string(kUnitRayTexture),
          "IMAGE_COLOR " + std::to_string(kImageColor),
          "IMAGE_SAMPLES " + std::to_string(kImageSamples),
          "UBO_RAY " + std::to_string(kUboRay),
          "SSBO_TF_POINTS " + std::to_string(kSsboTfPoints),
          "SSBO_CELL_DISTANCE " + std::to_string(kSsboCellDistance),
          "SSBO_CELL_STRIDE " + std::to_string(kSsboCellStride),
          "SSBO_FRONT_OPACITY " + std::to_string(kSsboFrontOpacity),
          "SSBO_CELL_RANGE " + std::to_string(kSsboCellRange),
          "NO_PEAK_TEXEL " + no_peak.str(),
          "TF_TABLE_SIZE " + std::to_string(TransferFunction::kTableSize)};
}

// The variant's switches, then the host interface (the program file, .frag or .comp, is
// chosen by the path: no define for it).
std::vector<std::string> VariantKey::defines() const {
  std::vector<std::string> d;
  if (tricubic) d.push_back("TRICUBIC");
  if (shading) d.push_back("SHADING");
  if (space_skipping) d.push_back("SPACE_SKIPPING");
  if (orthographic) d.push_back("ORTHOGRAPHIC");
  if (differential) d.push_back("DIFFERENTIAL");
  if (adaptive) d.push_back("ADAPTIVE");
  if (virtual_samples) d.push_back("VIRTUAL_SAMPLES " + std::to_string(virtual_samples));
  if (peaks) {
    d.push_back("PEAKS");
    if (peak_mode == PeakMode::Xor) d.push_back("PEAK_XOR");
    if (peak_mode == PeakMode::PeaksOnly) d.push_back("PEAKS_ONLY");
  }
  if (preintegration) d.push_back("PREINTEGRATION");
  if (projection) d.push_back("PROJECTION " + std::to_string(projection));
  if (rgb8) d.push_back("RGB8_OUTPUT");
  if (ray_texture) d.push_back("RAY_TEXTURE");
  if (brick) d.push_back("BRICK");
  if (ray_texture_volume) d.push_back("RAY_TEXTURE_VOLUME");
  for (auto& i : interface_defines()) d.push_back(std::move(i));
  return d;
}

std::string VariantKey::name() const {
  std::string n = cpu ? "cpu" : path == RenderPath::Compute ? "comp" : "frag";
  n += tricubic ? "+tricubic" : "+trilinear";
  if (peaks) n += std::string("+peaks:") + to_string(peak_mode);
  if (preintegration) n += "+preint";
  if (projection) n += projection == 1 ? "+mip" : projection == 2 ? "+minip" : "+average";
  if (shading) n += "+shade";
  if (space_skipping) n += "+skip";
  if (orthographic) n += "+ortho";
  if (differential) n += "+diff";
  if (adaptive) n += "+adaptive";
  if (virtual_samples) n += "+vs" + std::to_string(virtual_samples);
  if (rgb8) n += "+rgb8";
  if (brick) n += "+brick";
  if (ray_texture) n += ray_texture_volume ? "+raytex:volume" : "+raytex:view";
  return n;
}

nlohmann::json capabilities() {
  return {
      {"classification", {"post", "preint", "peaks", "mip", "minip", "average"}},
      {"peak_mode", {"dvr+peaks", "xor", "peaks_only", "dvr_only"}},
      {"max_peaks", {1, 2, 3, 4}},
      {"sampling", {"uniform", "differential"}},
      {"filter", {"trilinear", "tricubic"}},
      {"virtual_samples", {0, 3, 7}},
      {"shading", true},
      {"space_skipping", true},
      {"adaptive", true},
      {"ray_texture",
       {{"mappings", {"view", "volume"}},
        {"channels", {{"step", {kMinStepMultiplier, kMaxStepMultiplier}}, {"termination", {0, 1}}, {"blend", {-1, 1}}}},
        {"modes", {"set", "add", "multiply"}},
        {"max_size", kMaxRayTextureSide},
        {"max_level", kMaxStrokeLevel},
        {"max_strokes", kMaxRayTextureStrokes}}},
      {"still_formats", {"jpeg", "png"}}};
}

VariantKey choose_variant(const ResolvedScene& s, int64_t empty_cells, RenderPath path, size_t peak_count) {
  VariantKey k;
  k.path = path;
  k.tricubic = s.scene.render.filter == Filter::Tricubic;
  const Classification c = s.scene.render.classification;
  k.projection = c == Classification::Mip ? 1 : c == Classification::Minip ? 2 : c == Classification::Average ? 3 : 0;
  // A projection composites one TF value per ray, unshaded; the TF's empty cells may hold its
  // maximum or minimum, so the TF's space skipping is off (a maximum or minimum skips by values:
  // VariantKey::projection_skips).
  k.shading = s.scene.render.shading && !k.projection;
  // Virtual samples skip cells too: their cells' ranges are joined over the Catmull-Rom
  // window's reach and widened by Lee's (M - m)/8 (GlRenderer::prepare).
  k.space_skipping = s.scene.render.space_skipping && empty_cells > 0 && !k.projection;
  k.orthographic = s.camera.orthographic;
  k.differential = s.scene.render.sampling == Sampling::Differential && !s.camera.orthographic;
  k.adaptive = s.scene.render.adaptive;
  k.virtual_samples = s.scene.render.virtual_samples;
  const RenderSettings& r = s.scene.render;
  // dvr_only, or a TF without peaks, leaves the peak-finding code out (plain postclassification).
  k.peaks = r.classification == Classification::Peaks && r.peak_mode != PeakMode::DvrOnly &&
            (peak_count > 0 || r.peak_mode == PeakMode::PeaksOnly);
  k.peak_mode = r.peak_mode;
  k.preintegration = r.classification == Classification::Preint;
  k.ray_texture = s.ray_texture != nullptr;
  k.ray_texture_volume = k.ray_texture && s.ray_texture->mapping == RayTextureMapping::Volume;
  return k;
}

}  // namespace peakcast::render
