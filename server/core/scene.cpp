#include "core/scene.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/auto_tf.h"
#include "core/json_fields.h"
#include "core/length_unit.h"
#include "core/peaks.h"
#include "core/preintegration.h"

namespace peakcast {
namespace {

using json = nlohmann::json;
using namespace json_fields;

Camera parse_camera(const json& j) {
  only_keys(j, "camera", {"eye", "center", "up", "fov_y", "projection", "height"});
  Camera c;
  if (!j.contains("eye") || !j.contains("center")) fail("camera", "needs eye and center");
  c.eye = vec3(j["eye"], "camera.eye");
  c.center = vec3(j["center"], "camera.center");
  if (j.contains("up")) c.up = vec3(j["up"], "camera.up");
  if (j.contains("fov_y")) c.fov_y = number(j["fov_y"], "camera.fov_y");
  if (j.contains("projection"))
    c.orthographic =
        choice<bool>(j["projection"], "camera.projection", {{"perspective", false}, {"orthographic", true}});
  if (j.contains("height")) c.height = number(j["height"], "camera.height");
  if (c.orthographic && !j.contains("height")) fail("camera.height", "required with an orthographic projection");
  try {
    validate_camera(c);
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
  return c;
}

TransferFunction parse_tf(const json& j, double& opacity_unit) {
  only_keys(j, "tf", {"points", "opacity_unit"});
  TransferFunction tf;
  if (!j.contains("points")) fail("tf.points", "required");
  const json& pts = j["points"];
  if (!pts.is_array() || pts.empty()) fail("tf.points", "must be a non-empty array of [value, r, g, b, a]");
  if (pts.size() > kMaxTfPoints) fail("tf.points", "more than " + std::to_string(kMaxTfPoints) + " points");
  for (size_t i = 0; i < pts.size(); ++i) {
    const std::string key = "tf.points[" + std::to_string(i) + "]";
    if (!pts[i].is_array() || pts[i].size() != 5) fail(key, "must be [value, r, g, b, a]");
    TfPoint p{number(pts[i][0], key + "[0]"), number(pts[i][1], key + "[1]"), number(pts[i][2], key + "[2]"),
              number(pts[i][3], key + "[3]"), number(pts[i][4], key + "[4]")};
    for (double c : {p.r, p.g, p.b, p.a})
      if (c < 0 || c > 1) fail(key, "colour and opacity must lie in [0, 1]");
    if (!tf.points.empty() && p.value < tf.points.back().value) fail(key, "values must be sorted ascending");
    if (tf.points.size() >= 2 && p.value == tf.points.back().value && p.value == tf.points[tf.points.size() - 2].value)
      fail(key, "at most two points may share a value");
    tf.points.push_back(p);
  }
  if (j.contains("opacity_unit")) {
    opacity_unit = number(j["opacity_unit"], "tf.opacity_unit");
    if (!(opacity_unit > 0)) fail("tf.opacity_unit", "must be > 0");
  }
  return tf;
}

RenderSettings parse_render(const json& j) {
  only_keys(j, "render",
            {"classification", "peak_mode", "max_peaks", "peak_table_bins", "secant_iterations", "preint_table_size",
             "preint_method", "sampling", "step", "s_k", "filter", "virtual_samples", "shading", "early_termination",
             "space_skipping", "adaptive", "clip", "ray_texture"});
  RenderSettings r;
  if (j.contains("classification"))
    r.classification = choice<Classification>(j["classification"], "render.classification",
                                              {{"post", Classification::Post},
                                               {"preint", Classification::Preint},
                                               {"peaks", Classification::Peaks},
                                               {"mip", Classification::Mip},
                                               {"minip", Classification::Minip},
                                               {"average", Classification::Average}});
  if (j.contains("peak_mode"))
    r.peak_mode = choice<PeakMode>(j["peak_mode"], "render.peak_mode",
                                   {{"dvr+peaks", PeakMode::DvrPlusPeaks},
                                    {"xor", PeakMode::Xor},
                                    {"peaks_only", PeakMode::PeaksOnly},
                                    {"dvr_only", PeakMode::DvrOnly}});
  if (j.contains("max_peaks")) r.max_peaks = integer(j["max_peaks"], "render.max_peaks", 1, 4);
  if (j.contains("peak_table_bins"))
    r.peak_table_bins = integer(j["peak_table_bins"], "render.peak_table_bins", 64, 1024);
  if (j.contains("secant_iterations"))
    r.secant_iterations = integer(j["secant_iterations"], "render.secant_iterations", 0, 16);
  if (j.contains("preint_table_size"))
    r.preint_table_size = integer(j["preint_table_size"], "render.preint_table_size", 16, 1024);
  if (j.contains("preint_method"))
    r.preint_method = choice<std::string>(j["preint_method"], "render.preint_method",
                                          {{"integral", std::string("integral")}, {"exact", std::string("exact")}});
  if (j.contains("sampling"))
    r.sampling = choice<Sampling>(j["sampling"], "render.sampling",
                                  {{"uniform", Sampling::Uniform}, {"differential", Sampling::Differential}});
  if (j.contains("step")) {
    r.step = number(j["step"], "render.step");
    if (!(r.step > 0)) fail("render.step", "must be > 0");
  }
  if (j.contains("s_k")) {
    r.s_k = number(j["s_k"], "render.s_k");
    if (!(r.s_k > 0)) fail("render.s_k", "must be > 0");
  }
  if (j.contains("filter"))
    r.filter = choice<Filter>(j["filter"], "render.filter",
                              {{"trilinear", Filter::Trilinear}, {"tricubic", Filter::Tricubic}});
  if (j.contains("virtual_samples")) {
    r.virtual_samples = integer(j["virtual_samples"], "render.virtual_samples", 0, 7);
    if (r.virtual_samples != 0 && r.virtual_samples != 3 && r.virtual_samples != 7)
      fail("render.virtual_samples", "must be 0, 3 or 7");
  }
  if (j.contains("shading")) r.shading = boolean(j["shading"], "render.shading");
  if (j.contains("early_termination")) {
    r.early_termination = number(j["early_termination"], "render.early_termination");
    if (!(r.early_termination > 0 && r.early_termination <= 1)) fail("render.early_termination", "must be in (0, 1]");
  }
  if (j.contains("space_skipping")) r.space_skipping = boolean(j["space_skipping"], "render.space_skipping");
  if (j.contains("adaptive")) r.adaptive = boolean(j["adaptive"], "render.adaptive");
  if (j.contains("clip")) r.clip = parse_clip(j["clip"]);
  if (j.contains("ray_texture")) {
    r.ray_texture = std::make_shared<const RayTextureSpec>(parse_ray_texture(j["ray_texture"]));
  }
  return r;
}

}  // namespace

Scene parse_scene(const json& j) {
  only_keys(j, "", {"volume", "camera", "image", "tf", "background", "render", "units", "time"});
  Scene s;
  if (!j.contains("volume") || !j["volume"].is_string() || j["volume"].get<std::string>().empty())
    fail("volume", "required: a volume id or path");
  s.volume = j["volume"].get<std::string>();
  if (j.contains("camera")) s.camera = parse_camera(j["camera"]);
  if (j.contains("image")) {
    only_keys(j["image"], "image", {"width", "height"});
    if (j["image"].contains("width")) s.width = integer(j["image"]["width"], "image.width", 1, kMaxImageSide);
    if (j["image"].contains("height")) s.height = integer(j["image"]["height"], "image.height", 1, kMaxImageSide);
    if (int64_t(s.width) * s.height > kMaxImagePixels)
      fail("image", "more than " + std::to_string(kMaxImagePixels) + " pixels");
  }
  if (j.contains("tf")) s.tf = parse_tf(j["tf"], s.opacity_unit);
  if (j.contains("background")) {
    s.background = vec3(j["background"], "background");
    for (int c = 0; c < 3; ++c)
      if (s.background[c] < 0 || s.background[c] > 1) fail("background", "components must lie in [0, 1]");
  }
  if (j.contains("render")) s.render = parse_render(j["render"]);
  if (j.contains("time")) s.time = integer(j["time"], "time", 0, 1000000);
  if (j.contains("units")) {
    if (!j["units"].is_string()) fail("units", "must be a unit of length such as \"µm\"");
    try {
      s.units = length_symbol(j["units"].get<std::string>(), "units");
    } catch (const std::invalid_argument& e) {
      throw SceneError(e.what());
    }
  }
  return s;
}

Scene parse_scene_text(const std::string& text) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse errors and number overflow (1e999)
    throw SceneError(std::string("scene is not valid JSON: ") + e.what());
  }
  return parse_scene(j);
}

PreintegrationMethod preint_method(const RenderSettings& r) {
  return r.preint_method == "integral" ? PreintegrationMethod::Integral : PreintegrationMethod::Exact;
}

bool is_projection(Classification c) {
  return c == Classification::Mip || c == Classification::Minip || c == Classification::Average;
}

const char* to_string(Classification c) {
  switch (c) {
    case Classification::Post: return "post";
    case Classification::Preint: return "preint";
    case Classification::Peaks: return "peaks";
    case Classification::Mip: return "mip";
    case Classification::Minip: return "minip";
    case Classification::Average: return "average";
  }
  return "post";
}
const char* to_string(PeakMode m) {
  static const char* n[] = {"dvr+peaks", "xor", "peaks_only", "dvr_only"};
  return n[int(m)];
}
const char* to_string(Sampling s) { return s == Sampling::Uniform ? "uniform" : "differential"; }
const char* to_string(Filter f) { return f == Filter::Trilinear ? "trilinear" : "tricubic"; }

json scene_to_json(const Scene& s) {
  json j;
  j["volume"] = s.volume;
  if (s.camera) {
    const Camera& c = *s.camera;
    j["camera"] = {{"eye", {c.eye.x, c.eye.y, c.eye.z}},
                   {"center", {c.center.x, c.center.y, c.center.z}},
                   {"up", {c.up.x, c.up.y, c.up.z}}};
    if (c.orthographic) {
      j["camera"]["projection"] = "orthographic";
      j["camera"]["height"] = c.height;
    } else {
      j["camera"]["fov_y"] = c.fov_y;
    }
  }
  j["image"] = {{"width", s.width}, {"height", s.height}};
  if (s.tf) {
    json pts = json::array();
    for (const auto& p : s.tf->points) pts.push_back({p.value, p.r, p.g, p.b, p.a});
    j["tf"] = {{"points", pts}};
    if (s.opacity_unit > 0) j["tf"]["opacity_unit"] = s.opacity_unit;
  }
  j["background"] = {s.background.x, s.background.y, s.background.z};
  if (!s.units.empty()) j["units"] = s.units;
  if (s.time > 0) j["time"] = s.time;
  const RenderSettings& r = s.render;
  j["render"] = {{"classification", to_string(r.classification)},
                 {"peak_mode", to_string(r.peak_mode)},
                 {"max_peaks", r.max_peaks},
                 {"peak_table_bins", r.peak_table_bins},
                 {"secant_iterations", r.secant_iterations},
                 {"preint_table_size", r.preint_table_size},
                 {"preint_method", r.preint_method},
                 {"sampling", to_string(r.sampling)},
                 {"s_k", r.s_k},
                 {"filter", to_string(r.filter)},
                 {"virtual_samples", r.virtual_samples},
                 {"shading", r.shading},
                 {"early_termination", r.early_termination},
                 {"space_skipping", r.space_skipping},
                 {"adaptive", r.adaptive}};
  if (r.step > 0) j["render"]["step"] = r.step;
  if (r.clip.active()) j["render"]["clip"] = to_json(r.clip);
  if (r.ray_texture) j["render"]["ray_texture"] = to_json(*r.ray_texture);
  return j;
}

std::string Scene::to_string() const {
  return "Scene" + scene_to_json(*this).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {

// Peak finding draws surfaces at the TF's opacity peaks: without one inside the data's range
// the frame is plain DVR (or, peaks only, empty), which the user should hear about.
void check_peaks(ResolvedScene& r, double lo, double hi) {
  const RenderSettings& rs = r.scene.render;
  if (rs.classification != Classification::Peaks || rs.peak_mode == PeakMode::DvrOnly) return;
  const std::vector<Peak> peaks = find_peaks(r.tf);
  if (peaks.empty()) {
    r.warnings.push_back(
        "classification peaks: the TF has no opacity peak (a point more opaque than both its neighbours), so peak "
        "finding finds no surface and the frame shows only the DVR part");
    return;
  }
  for (const Peak& p : peaks)
    if (p.value >= lo && p.value <= hi) return;
  r.warnings.push_back("classification peaks: every opacity peak of the TF lies outside the data's range [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "], so no ray crosses one");
}

ResolvedScene resolve(const Scene& s, const VolumeBox& v, const std::vector<uint64_t>* histogram,
                      const std::vector<uint64_t>* border) {
  ResolvedScene r;
  r.scene = s;
  for (int a = 0; a < 3; ++a)
    if (v.dims[a] < 2)
      throw SceneError("volume: every dimension must be >= 2 to render (got " + std::to_string(v.dims[0]) + "x" +
                       std::to_string(v.dims[1]) + "x" + std::to_string(v.dims[2]) +
                       ": a single voxel, line or slice has no box to ray cast)");
  r.box_min = v.origin;
  r.box_max = v.origin + glm::dvec3(v.dims[0] - 1, v.dims[1] - 1, v.dims[2] - 1) * v.spacing;
  r.camera = s.camera ? *s.camera : default_camera(r.box_min, r.box_max);
  const double min_spacing = std::min({v.spacing.x, v.spacing.y, v.spacing.z});
  // The opacity unit and the automatic TF's ray length follow level 0 of a pyramid: a coarser
  // level is the same volume drawn with fewer samples, not a thicker one.
  const glm::dvec3 unit = v.full_spacing.x > 0 ? v.full_spacing : v.spacing;
  const double unit_spacing = std::min({unit.x, unit.y, unit.z});
  if (s.tf) {
    r.tf = *s.tf;
  } else {
    AutoTfInput in;
    in.histogram = histogram && !histogram->empty() ? histogram : nullptr;
    in.border_histogram = border && !border->empty() ? border : nullptr;
    in.lo = v.min_value;
    in.hi = v.max_value;
    const glm::dvec3 extent = r.box_max - r.box_min;
    in.ray_length = (extent.x + extent.y + extent.z) / 3.0 / unit_spacing;
    in.with_peak = s.render.classification == Classification::Peaks;
    r.tf = derive_transfer_function(in);
    r.tf_derived = true;
  }
  r.tf.opacity_unit = s.opacity_unit > 0 ? s.opacity_unit : unit_spacing;
  r.step = s.render.step > 0 ? s.render.step : min_spacing;
  r.min_spacing = min_spacing;
  if (s.render.ray_texture) {
    if (!s.render.ray_texture->png.empty() && !s.render.ray_texture->image)
      throw SceneError("render.ray_texture.png: " + s.render.ray_texture->png + " was not read (load_ray_texture_png)");
    r.ray_texture = s.render.ray_texture;
  }
  if (r.step < kMinStepFraction * min_spacing)
    throw SceneError("render.step: " + std::to_string(r.step) + " is below " + std::to_string(kMinStepFraction) +
                     " x the smallest spacing");
  check_peaks(r, v.min_value, v.max_value);
  return r;
}

}  // namespace

std::string time_refusal(int64_t time, int64_t times) {
  if (time >= 0 && time < times) return "";
  return "time: time point " + std::to_string(time) + " is outside the volume's " +
         (times == 1 ? std::string("one time point (0)") : "0.." + std::to_string(times - 1));
}

ResolvedScene resolve_scene(const Scene& s, const Volume& v) {
  if (const std::string why = time_refusal(s.time, v.time_points); !why.empty()) throw SceneError(why);
  if (s.time != v.time_point)  // a caller's slip: the scene asks for another time point than it was given
    throw SceneError("time: time point " + std::to_string(s.time) + " asked, " + std::to_string(v.time_point) +
                     " held");
  return resolve(s, VolumeBox{v.dims(), v.spacing, v.origin, v.min_value, v.max_value, {}, {}, v.full_spacing},
                 &v.histogram, &v.border_histogram);
}

ResolvedScene resolve_scene(const Scene& s, const VolumeBox& v) {
  return resolve(s, v, &v.histogram, &v.border_histogram);
}

}  // namespace peakcast
