#include "core/ray_texture.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/json_fields.h"

namespace peakcast {
namespace {

using json = nlohmann::json;
using namespace json_fields;

struct Range {
  double lo, hi;
};
Range channel_range(RayChannel c) {
  switch (c) {
    case RayChannel::Step: return {kMinStepMultiplier, kMaxStepMultiplier};
    case RayChannel::Termination: return {0.0, 1.0};
    case RayChannel::Blend: return {-1.0, 1.0};
  }
  return {0.0, 1.0};
}

const char* channel_name(RayChannel c) {
  switch (c) {
    case RayChannel::Step: return "step";
    case RayChannel::Termination: return "termination";
    case RayChannel::Blend: return "blend";
  }
  return "?";
}

const char* mode_name(StrokeMode m) {
  switch (m) {
    case StrokeMode::Set: return "set";
    case StrokeMode::Add: return "add";
    case StrokeMode::Multiply: return "multiply";
  }
  return "?";
}

// 1 inside (1 - falloff) x radius, falling smoothly to 0 at the radius.
double brush_weight(double r, double falloff) {
  if (r >= 1.0) return 0.0;
  const double inner = 1.0 - falloff;
  if (r <= inner) return 1.0;
  const double x = (r - inner) / falloff;
  return 1.0 - x * x * (3.0 - 2.0 * x);
}

uint64_t new_lineage() {
  static std::atomic<uint64_t> next{1};
  return next++;
}

}  // namespace

void TexelRect::merge(const TexelRect& r) {
  if (r.empty()) return;
  if (empty()) {
    *this = r;
    return;
  }
  x0 = std::min(x0, r.x0), y0 = std::min(y0, r.y0), x1 = std::max(x1, r.x1), y1 = std::max(y1, r.y1);
}

Stroke parse_stroke(const json& j, const std::string& where) {
  only_keys(j, where, {"channel", "center", "radius", "falloff", "value", "mode", "level"});
  Stroke s;
  if (!j.contains("channel")) fail(where + ".channel", "is required (step, termination or blend)");
  s.channel = choice<RayChannel>(
      j["channel"], where + ".channel",
      {{"step", RayChannel::Step}, {"termination", RayChannel::Termination}, {"blend", RayChannel::Blend}});
  if (!j.contains("center")) fail(where + ".center", "is required ([u, v] in [0, 1])");
  const json& c = j["center"];
  if (!c.is_array() || c.size() != 2) fail(where + ".center", "must be [u, v]");
  s.u = number(c[0], where + ".center[0]");
  s.v = number(c[1], where + ".center[1]");
  if (s.u < 0 || s.u > 1 || s.v < 0 || s.v > 1) fail(where + ".center", "must lie in [0, 1]");
  if (!j.contains("radius")) fail(where + ".radius", "is required (in (0, 1])");
  s.radius = number(j["radius"], where + ".radius");
  if (!(s.radius > 0 && s.radius <= 1)) fail(where + ".radius", "must be in (0, 1]");
  if (j.contains("falloff")) {
    s.falloff = number(j["falloff"], where + ".falloff");
    if (s.falloff < 0 || s.falloff > 1) fail(where + ".falloff", "must be in [0, 1]");
  }
  if (j.contains("mode"))
    s.mode =
        choice<StrokeMode>(j["mode"], where + ".mode",
                           {{"set", StrokeMode::Set}, {"add", StrokeMode::Add}, {"multiply", StrokeMode::Multiply}});
  if (!j.contains("value")) fail(where + ".value", "is required");
  s.value = number(j["value"], where + ".value");
  const Range r = channel_range(s.channel);
  const std::string ch = channel_name(s.channel);
  if (s.mode == StrokeMode::Set && (s.value < r.lo || s.value > r.hi))
    fail(where + ".value", "must be in [" + std::to_string(r.lo) + ", " + std::to_string(r.hi) + "] for " + ch);
  if (s.mode == StrokeMode::Add && std::abs(s.value) > r.hi - r.lo)
    fail(where + ".value", "must add at most " + std::to_string(r.hi - r.lo) + " to " + ch);
  if (s.mode == StrokeMode::Multiply && !(s.value >= 1.0 / 64 && s.value <= 64))
    fail(where + ".value", "must multiply by a factor in [1/64, 64]");
  if (j.contains("level")) s.level = integer(j["level"], where + ".level", 0, kMaxStrokeLevel);
  return s;
}

RayTextureSpec parse_ray_texture(const json& j, const std::string& where) {
  only_keys(j, where, {"mapping", "size", "strokes", "png"});
  RayTextureSpec spec;
  spec.lineage = new_lineage();
  if (!j.contains("mapping")) fail(where + ".mapping", "is required (view or volume)");
  spec.mapping = choice<RayTextureMapping>(j["mapping"], where + ".mapping",
                                           {{"view", RayTextureMapping::View}, {"volume", RayTextureMapping::Volume}});
  if (j.contains("png")) {
    if (j.contains("size")) fail(where, "takes either png or size, not both (a PNG has its own size)");
    if (!j["png"].is_string() || j["png"].get<std::string>().empty()) fail(where + ".png", "must be a file path");
    spec.png = j["png"].get<std::string>();
    if (spec.png.size() > 4096) fail(where + ".png", "is longer than 4096 characters");
  } else {
    if (!j.contains("size")) fail(where + ".size", "is required ([width, height]) unless png is given");
    const json& size = j["size"];
    if (!size.is_array() || size.size() != 2) fail(where + ".size", "must be [width, height]");
    spec.width = integer(size[0], where + ".size[0]", 1, kMaxRayTextureSide);
    spec.height = integer(size[1], where + ".size[1]", 1, kMaxRayTextureSide);
  }
  if (j.contains("strokes")) {
    const json& strokes = j["strokes"];
    if (!strokes.is_array()) fail(where + ".strokes", "must be an array");
    if (strokes.size() > kMaxRayTextureStrokes)
      fail(where + ".strokes",
           "holds " + std::to_string(strokes.size()) + " strokes; at most " + std::to_string(kMaxRayTextureStrokes));
    for (size_t i = 0; i < strokes.size(); ++i)
      spec.strokes.push_back(parse_stroke(strokes[i], where + ".strokes[" + std::to_string(i) + "]"));
  }
  count_work(spec, where + ".strokes");
  return spec;
}

json to_json(const Stroke& s) {
  json j = {{"channel", channel_name(s.channel)},
            {"center", {s.u, s.v}},
            {"radius", s.radius},
            {"falloff", s.falloff},
            {"value", s.value},
            {"mode", mode_name(s.mode)}};
  if (s.level) j["level"] = s.level;
  return j;
}

json to_json(const RayTextureSpec& s) {
  json j = {{"mapping", s.mapping == RayTextureMapping::View ? "view" : "volume"}};
  if (!s.png.empty())
    j["png"] = s.png;
  else
    j["size"] = {s.width, s.height};
  j["strokes"] = json::array();
  for (const auto& st : s.strokes) j["strokes"].push_back(to_json(st));
  return j;
}

uint64_t stroke_texels(const Stroke& s, int width, int height) {
  const double block = double(1 << std::clamp(s.level, 0, kMaxStrokeLevel));
  const double d = 2.0 * s.radius * std::max(width, height) + 2.0 * block;  // the box, rounded out to blocks
  return uint64_t(std::min(d, double(width))) * uint64_t(std::min(d, double(height)));
}

void count_work(RayTextureSpec& spec, const std::string& where) {
  uint64_t work = 0;
  for (const auto& s : spec.strokes) work += stroke_texels(s, spec.width, spec.height);
  if (work > kMaxRayTextureWork)
    throw SceneError(where + ": the strokes touch " + std::to_string(work) + " texels in all (their bounding boxes), " +
                     "more than " + std::to_string(kMaxRayTextureWork) +
                     ": use a smaller texture, smaller or fewer strokes, or clear the texture");
  spec.work = work;
}

std::shared_ptr<const RayTextureSpec> with_stroke(const RayTextureSpec& spec, const Stroke& s) {
  if (spec.strokes.size() >= kMaxRayTextureStrokes)
    throw SceneError("stroke: the ray texture holds " + std::to_string(spec.strokes.size()) +
                     " strokes already, the most it takes (clear it or send it anew without strokes)");
  const uint64_t work = spec.work + stroke_texels(s, spec.width, spec.height);
  if (work > kMaxRayTextureWork)
    throw SceneError("stroke: the ray texture's strokes would touch " + std::to_string(work) +
                     " texels in all, more than " + std::to_string(kMaxRayTextureWork) +
                     " (clear it, or paint smaller)");
  // The strokes are copied (specs are immutable: frames in flight read the older one); at the
  // stroke cap that is 5.6 MB per stroke, under the message rate limit.
  auto next = std::make_shared<RayTextureSpec>(spec);
  next->strokes.push_back(s);
  next->work = work;
  return next;
}

RayTexture::RayTexture(const RayTextureImage& image)
    : width_(image.width), height_(image.height), default_termination_(1.0f), texels_(image.texels) {
  if (width_ < 1 || height_ < 1 || width_ > kMaxRayTextureSide || height_ > kMaxRayTextureSide ||
      texels_.size() != size_t(width_) * size_t(height_) * 3)
    throw SceneError("render.ray_texture: image of " + std::to_string(width_) + "x" + std::to_string(height_) +
                     " texels does not fit the limits or its data");
}

RayTexture::RayTexture(int width, int height, double termination)
    : width_(std::clamp(width, 1, kMaxRayTextureSide)),
      height_(std::clamp(height, 1, kMaxRayTextureSide)),
      default_termination_(float(std::clamp(termination, 0.0, 1.0))),
      texels_(size_t(width_) * size_t(height_) * 3) {
  for (size_t i = 0; i < texels_.size(); i += 3) {
    texels_[i] = 1.0f;
    texels_[i + 1] = default_termination_;
    texels_[i + 2] = 0.0f;
  }
}

TexelRect RayTexture::apply(const Stroke& s) {
  const int block = 1 << std::clamp(s.level, 0, kMaxStrokeLevel);
  const double side = std::max(width_, height_);
  const Range range = channel_range(s.channel);
  const int c = int(s.channel);
  // Blocks (texels at level 0) whose centre can lie inside the disk.
  const double rx = s.radius * side, ry = s.radius * side;  // in level-0 texels
  const int bx0 = std::max(0, int(std::floor((s.u * width_ - rx) / block)));
  const int bx1 = std::min((width_ + block - 1) / block, int(std::floor((s.u * width_ + rx) / block)) + 1);
  const int by0 = std::max(0, int(std::floor((s.v * height_ - ry) / block)));
  const int by1 = std::min((height_ + block - 1) / block, int(std::floor((s.v * height_ + ry) / block)) + 1);
  TexelRect dirty;
  for (int by = by0; by < by1; ++by)
    for (int bx = bx0; bx < bx1; ++bx) {
      const int x0 = bx * block, y0 = by * block, x1 = std::min(width_, x0 + block), y1 = std::min(height_, y0 + block);
      // The block's centre, in texels; distance in units of the larger side.
      const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
      const double dx = (cx - s.u * width_) / side, dy = (cy - s.v * height_) / side;
      const double w = brush_weight(std::sqrt(dx * dx + dy * dy) / s.radius, s.falloff);
      if (w <= 0.0) continue;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          float& t = texels_[(size_t(y) * size_t(width_) + size_t(x)) * 3 + size_t(c)];
          double v = t;
          switch (s.mode) {
            case StrokeMode::Set: v += w * (s.value - v); break;
            case StrokeMode::Add: v += w * s.value; break;
            case StrokeMode::Multiply: v *= std::pow(s.value, w); break;
          }
          t = float(std::clamp(v, range.lo, range.hi));
        }
      dirty.merge({x0, y0, x1, y1});
    }
  return dirty;
}

std::array<float, 3> RayTexture::at(int x, int y) const {
  const size_t i = (size_t(std::clamp(y, 0, height_ - 1)) * size_t(width_) + size_t(std::clamp(x, 0, width_ - 1))) * 3;
  return {texels_[i], texels_[i + 1], texels_[i + 2]};
}

bool RayTexture::is_identity() const {
  for (size_t i = 0; i < texels_.size(); i += 3)
    if (texels_[i] != 1.0f || texels_[i + 1] != default_termination_ || texels_[i + 2] != 0.0f) return false;
  return true;
}

RayTexture build_ray_texture(const RayTextureSpec& spec, double termination) {
  if (!spec.png.empty() && !spec.image)
    throw SceneError("render.ray_texture.png: " + spec.png + " was not read (internal: no PNG loader on this path)");
  RayTexture t = spec.image ? RayTexture(*spec.image) : RayTexture(spec.width, spec.height, termination);
  for (const auto& s : spec.strokes) t.apply(s);
  return t;
}

}  // namespace peakcast
