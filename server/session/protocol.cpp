#include "session/protocol.h"
#include "core/public_text.h"
#include "core/utf8.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "encode/video.h"
#include "session/limits.h"

namespace peakcast::protocol {
namespace {

using json = nlohmann::json;

[[noreturn]] void bad(const std::string& message) { throw ProtocolError("bad_message", message); }

void only_keys(const json& j, const char* type, std::initializer_list<const char*> allowed) {
  for (auto& [k, _] : j.items()) {
    bool ok = k == "type";
    for (const char* a : allowed) ok = ok || k == a;
    if (!ok) bad(std::string(type) + "." + k + ": unknown key");
  }
}

// The scene parser validates camera/tf/render/background exactly as for scene files.
Scene validate_parts(const json& parts) {
  json scene = parts;
  scene["volume"] = "x";
  try {
    return parse_scene(scene);
  } catch (const SceneError& e) {
    bad(e.what());
  }
}

int int_in(const json& j, const std::string& key, int lo, int hi) {
  if (!j.is_number_integer()) bad(key + ": must be an integer");
  const auto v = j.get<int64_t>();
  if (v < lo || v > hi) bad(key + ": must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return int(v);
}

double number_in(const json& j, const std::string& key, double lo, double hi) {
  if (!j.is_number()) bad(key + ": must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi)
    bad(key + ": must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

std::string string_of(const json& j, const std::string& key, size_t max_len) {
  if (!j.is_string()) bad(key + ": must be a string");
  auto s = j.get<std::string>();
  if (s.size() > max_len) bad(key + ": longer than " + std::to_string(max_len) + " characters");
  return s;
}

Viewport parse_viewport(const json& j, const std::string& where) {
  Viewport v;
  if (!j.is_object()) bad(where + ": must be an object");
  for (auto& [k, _] : j.items())
    if (k != "width" && k != "height" && k != "dpr") bad(where + "." + k + ": unknown key");
  if (!j.contains("width") || !j.contains("height")) bad(where + ": needs width and height");
  v.width = int_in(j["width"], where + ".width", 1, limits::kMaxViewportSide);
  v.height = int_in(j["height"], where + ".height", 1, limits::kMaxViewportSide);
  if (j.contains("dpr")) v.dpr = number_in(j["dpr"], where + ".dpr", limits::kMinDpr, limits::kMaxDpr);
  if (v.pixel_width() > limits::kMaxViewportSide || v.pixel_height() > limits::kMaxViewportSide ||
      int64_t(v.pixel_width()) * v.pixel_height() > limits::kMaxViewportPixels)
    bad(where + ": " + std::to_string(v.pixel_width()) + "x" + std::to_string(v.pixel_height()) +
        " device pixels exceeds the frame cap");
  return v;
}

StatePatch parse_state(const json& j) {
  if (!j.is_object()) bad("hello.state: must be an object");
  for (auto& [k, _] : j.items())
    if (k != "camera" && k != "tf" && k != "render" && k != "background" && k != "time")
      bad("hello.state." + k + ": unknown key");
  Scene s = validate_parts(j);
  StatePatch p;
  p.camera = s.camera;
  p.tf = s.tf;
  p.opacity_unit = s.opacity_unit;
  if (j.contains("render")) p.render = j["render"];
  if (j.contains("background")) p.background = s.background;
  if (j.contains("time")) p.time = int_in(j["time"], "hello.state.time", 0, 1000000);
  return p;
}

// One parser per message type, each given the whole message (its "type" already read).
ClientMessage hello_message(const json& j) {
  only_keys(j, "hello", {"token", "volume", "viewport", "state"});
  Hello h;
  if (j.contains("token")) h.token = string_of(j["token"], "hello.token", limits::kMaxTokenLength);
  if (j.contains("volume")) h.volume = string_of(j["volume"], "hello.volume", limits::kMaxVolumeNameLength);
  if (!j.contains("viewport")) bad("hello.viewport: required");
  h.viewport = parse_viewport(j["viewport"], "hello.viewport");
  if (j.contains("state")) h.state = parse_state(j["state"]);
  return h;
}

ClientMessage camera_message(const json& j) {
  only_keys(j, "camera", {"camera"});
  if (!j.contains("camera")) bad("camera.camera: required");
  return CameraMsg{*validate_parts({{"camera", j["camera"]}}).camera};
}

ClientMessage tf_message(const json& j) {
  only_keys(j, "tf", {"tf", "version"});
  if (!j.contains("tf")) bad("tf.tf: required");
  Scene s = validate_parts({{"tf", j["tf"]}});
  TfMsg m{*s.tf, s.opacity_unit, 0};
  if (j.contains("version")) {
    if (!j["version"].is_number_unsigned() || j["version"].get<uint64_t>() > 0xffffffffull)
      bad("tf.version: must be an unsigned 32-bit integer");
    m.version = j["version"].get<uint32_t>();
  }
  return m;
}

ClientMessage stroke_message(const json& j) {
  only_keys(j, "stroke", {"seq", "stroke"});
  if (!j.contains("seq") || !j["seq"].is_number_unsigned() || j["seq"].get<uint64_t>() > 0xffffffffull)
    bad("stroke.seq: required, an unsigned 32-bit integer");
  if (!j.contains("stroke")) bad("stroke.stroke: required");
  StrokeMsg m;
  m.seq = j["seq"].get<uint32_t>();
  try {
    m.stroke = parse_stroke(j["stroke"], "stroke.stroke");
  } catch (const SceneError& e) {
    bad(e.what());
  }
  return m;
}

ClientMessage render_message(const json& j) {
  only_keys(j, "render", {"render"});
  if (!j.contains("render")) bad("render.render: required");
  if (!j["render"].is_object()) bad("render.render: must be an object");
  json present = j["render"];  // null removes a setting (JSON merge patch): validate the rest
  for (auto it = j["render"].begin(); it != j["render"].end(); ++it)
    if (it.value().is_null()) present.erase(it.key());
  validate_parts({{"render", present}});
  return RenderMsg{j["render"]};
}

ClientMessage quality_message(const json& j) {
  only_keys(
      j, "quality",
      {"interactive_scale", "interactive_ms", "interactive_quality", "final_quality", "final_format", "codec", "kbps"});
  QualityMsg q;
  if (j.contains("interactive_scale"))
    q.interactive_scale = number_in(j["interactive_scale"], "quality.interactive_scale", 0.1, 1.0);
  if (j.contains("interactive_ms"))
    q.interactive_ms = number_in(j["interactive_ms"], "quality.interactive_ms", 0.0, 1000.0);
  if (j.contains("interactive_quality"))
    q.interactive_quality = int_in(j["interactive_quality"], "quality.interactive_quality", limits::kMinJpegQuality,
                                   limits::kMaxJpegQuality);
  if (j.contains("final_quality"))
    q.final_quality =
        int_in(j["final_quality"], "quality.final_quality", limits::kMinJpegQuality, limits::kMaxJpegQuality);
  if (j.contains("final_format")) {
    q.final_format = string_of(j["final_format"], "quality.final_format", 8);
    if (*q.final_format != "jpeg" && *q.final_format != "png") bad("quality.final_format: jpeg or png");
  }
  if (j.contains("codec")) {
    q.codec = string_of(j["codec"], "quality.codec", 16);
    if (!encode::codec_available(*q.codec)) {
      std::string known;
      for (const auto& c : encode::available_codecs()) known += (known.empty() ? "" : ", ") + c;
      bad("quality.codec: '" + *q.codec + "' is not a codec this server encodes (" + known + ")");
    }
  }
  if (j.contains("kbps")) q.kbps = int_in(j["kbps"], "quality.kbps", limits::kMinKbps, limits::kMaxKbps);
  return q;
}

ClientMessage viewport_message(const json& j) {
  only_keys(j, "viewport", {"width", "height", "dpr"});
  json v = j;
  v.erase("type");
  return ViewportMsg{parse_viewport(v, "viewport")};
}

ClientMessage volume_message(const json& j) {
  only_keys(j, "volume", {"volume"});
  if (!j.contains("volume")) bad("volume.volume: required");
  return VolumeMsg{string_of(j["volume"], "volume.volume", limits::kMaxVolumeNameLength)};
}

ClientMessage time_message(const json& j) {
  only_keys(j, "time", {"time"});
  if (!j.contains("time")) bad("time.time: required");
  return TimeMsg{int_in(j["time"], "time.time", 0, 1000000)};
}

ClientMessage ack_message(const json& j) {
  only_keys(j, "ack", {"frame"});
  if (!j.contains("frame") || !j["frame"].is_number_unsigned() || j["frame"].get<uint64_t>() > 0xffffffffull)
    bad("ack.frame: must be an unsigned 32-bit integer");
  return AckMsg{j["frame"].get<uint32_t>()};
}

ClientMessage keyframe_message(const json& j) {
  only_keys(j, "keyframe", {});
  return KeyframeMsg{};
}

ClientMessage ping_message(const json& j) {
  only_keys(j, "ping", {"id"});
  PingMsg p;
  if (j.contains("id")) p.id = string_of(j["id"], "ping.id", limits::kMaxPingIdLength);
  return p;
}

ClientMessage probe_message(const json& j) {
  only_keys(j, "probe", {"id", "pixel", "pick"});
  ProbeMsg m;
  if (j.contains("id")) {
    if (!j["id"].is_number_unsigned() || j["id"].get<uint64_t>() > 0xffffffffull)
      bad("probe.id: must be an unsigned 32-bit integer");
    m.id = j["id"].get<uint32_t>();
  }
  if (!j.contains("pixel")) bad("probe.pixel: required");
  std::tie(m.x, m.y) = parse_pixel(j["pixel"], "probe.pixel");
  m.pick = parse_pick(j, "probe.pick");
  return m;
}

}  // namespace

int Viewport::pixel_width() const { return std::max(1, int(std::lround(width * dpr))); }
int Viewport::pixel_height() const { return std::max(1, int(std::lround(height * dpr))); }

ClientMessage parse_client_message(const std::string& text) {
  if (text.size() > limits::kMaxWsMessageBytes)
    throw ProtocolError("too_large", "message of " + std::to_string(text.size()) + " bytes exceeds " +
                                         std::to_string(limits::kMaxWsMessageBytes));
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw ProtocolError("bad_json", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) bad("a message must be a JSON object");
  if (!j.contains("type") || !j["type"].is_string()) bad("type: required string");
  const std::string type = j["type"];
  static const std::pair<const char*, ClientMessage (*)(const json&)> kParsers[] = {
      {"hello", hello_message},       {"camera", camera_message}, {"tf", tf_message},
      {"stroke", stroke_message},     {"render", render_message}, {"quality", quality_message},
      {"viewport", viewport_message}, {"volume", volume_message}, {"ack", ack_message},
      {"keyframe", keyframe_message}, {"ping", ping_message},     {"probe", probe_message},
      {"time", time_message}};
  for (const auto& [name, parse] : kParsers)
    if (type == name) return parse(j);
  throw ProtocolError("unknown_type", "unknown message type '" + clean_utf8(type, 64) + "'");
}

std::string error_message(const std::string& code, const std::string& message) {
  return json{{"type", "error"}, {"code", code}, {"message", public_text(message)}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string pong_message(const std::string& id) {
  return json{{"type", "pong"}, {"id", id}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string stroke_ack_message(uint32_t seq, size_t strokes) {
  return json{{"type", "stroke_ack"}, {"seq", seq}, {"strokes", strokes}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string loading_message(const std::string& volume, double fraction) {
  return json{{"type", "loading"}, {"volume", volume}, {"fraction", std::clamp(fraction, 0.0, 1.0)}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string refining_message(double fraction, int bricks) {
  return json{{"type", "refining"}, {"fraction", std::clamp(fraction, 0.0, 1.0)}, {"bricks", bricks}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::pair<int, int> parse_pixel(const json& p, const std::string& where) {
  auto coordinate = [](const json& c) { return c.is_number_unsigned() && c.get<uint64_t>() <= 1u << 20; };
  if (!p.is_array() || p.size() != 2 || !coordinate(p[0]) || !coordinate(p[1]))
    bad(where + ": must be [x, y], whole pixels counted from the top left");
  return {p[0].get<int>(), p[1].get<int>()};
}

std::string parse_pick(const json& j, const std::string& where) {
  if (!j.contains("pick")) return "surface";
  const json& p = j["pick"];
  if (!p.is_string() || (p != "surface" && p != "half"))
    bad(where +
        ": must be \"surface\" (the first sample the TF gives opacity >= 0.05) or \"half\" (where the ray's "
        "opacity passes one half)");
  return p.get<std::string>();
}

json probe_json(bool hit, const glm::dvec3& position, double value, double distance, double opacity, const char* pick) {
  json j = {{"hit", hit},          {"position", nullptr}, {"value", nullptr},
            {"distance", nullptr}, {"opacity", opacity},  {"pick", pick}};
  if (hit) {
    j["position"] = {position.x, position.y, position.z};
    j["value"] = value;
    j["distance"] = distance;
  }
  return j;
}

std::string probe_message(uint32_t id, const json& answer) {
  json j = answer;
  j["type"] = "probe";
  j["id"] = id;
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string volume_message(const json& volume_info, const json& state) {
  return json{{"type", "volume"}, {"volume", volume_info}, {"state", state}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string welcome_message(const Welcome& w) {
  return json{
      {"type", "welcome"}, {"session", w.session},           {"volume", w.volume},           {"volumes", w.volumes},
      {"state", w.state},  {"capabilities", w.capabilities}, {"gl_renderer", w.gl_renderer}, {"backend", w.backend},
      {"limits", w.limits}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string stats_message(uint32_t frame, bool final, int width, int height, const json& render_stats, double encode_ms,
                          size_t bytes) {
  json m = render_stats;
  m["type"] = "stats";
  m["frame"] = frame;
  m["final"] = final;
  m["width"] = width;
  m["height"] = height;
  m["encode_ms"] = encode_ms;
  m["bytes"] = bytes;
  return m.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

namespace {
template <typename T>
void put(std::vector<uint8_t>& out, size_t off, T v) {
  for (size_t b = 0; b < sizeof(T); ++b) out[off + b] = uint8_t(uint64_t(v) >> (8 * b));
}
template <typename T>
T get(const uint8_t* p, size_t off) {
  uint64_t v = 0;
  for (size_t b = 0; b < sizeof(T); ++b) v |= uint64_t(p[off + b]) << (8 * b);
  return T(v);
}
}  // namespace

std::vector<uint8_t> encode_frame(const FrameHeader& h, const std::vector<uint8_t>& image) {
  std::vector<uint8_t> out(FrameHeader::kSize + image.size());
  put<uint32_t>(out, 0, FrameHeader::kMagic);
  put<uint16_t>(out, 4, FrameHeader::kVersion);
  put<uint16_t>(out, 6, FrameHeader::kSize);
  put<uint32_t>(out, 8, h.frame_id);
  put<uint32_t>(out, 12, h.flags);
  put<uint32_t>(out, 16, h.camera_version);
  put<uint32_t>(out, 20, h.tf_version);
  put<uint32_t>(out, 24, h.render_version);
  put<uint32_t>(out, 28, h.width);
  put<uint32_t>(out, 32, h.height);
  put<uint32_t>(out, 36, h.quality);
  put<uint64_t>(out, 40, h.t_input_us);
  put<uint64_t>(out, 48, h.t_render_done_us);
  put<uint64_t>(out, 56, h.t_encode_done_us);
  std::memcpy(out.data() + FrameHeader::kSize, image.data(), image.size());
  return out;
}

FrameHeader decode_frame_header(const uint8_t* p, size_t size) {
  if (size < FrameHeader::kSize || get<uint32_t>(p, 0) != FrameHeader::kMagic)
    throw ProtocolError("bad_frame", "not a peakcast frame");
  if (get<uint16_t>(p, 4) != FrameHeader::kVersion) throw ProtocolError("bad_frame", "unknown frame version");
  FrameHeader h;
  h.frame_id = get<uint32_t>(p, 8);
  h.flags = get<uint32_t>(p, 12);
  h.camera_version = get<uint32_t>(p, 16);
  h.tf_version = get<uint32_t>(p, 20);
  h.render_version = get<uint32_t>(p, 24);
  h.width = get<uint32_t>(p, 28);
  h.height = get<uint32_t>(p, 32);
  h.quality = get<uint32_t>(p, 36);
  h.t_input_us = get<uint64_t>(p, 40);
  h.t_render_done_us = get<uint64_t>(p, 48);
  h.t_encode_done_us = get<uint64_t>(p, 56);
  return h;
}

}  // namespace peakcast::protocol
