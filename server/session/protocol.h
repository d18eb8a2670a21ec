// The WebSocket protocol (proto/messages.md): client messages parsed and validated into typed
// structs, server messages built, and the binary frame header. No sockets here: the whole
// protocol is testable in memory.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/scene.h"

namespace peakcast::protocol {

// A refusal: `code` is one of the error codes in proto/messages.md.
class ProtocolError : public std::runtime_error {
 public:
  ProtocolError(std::string code, const std::string& message) : std::runtime_error(message), code(std::move(code)) {}
  std::string code;
};

struct Viewport {
  int width = 0, height = 0;  // CSS pixels
  double dpr = 1.0;
  int pixel_width() const;  // width * dpr, rounded, at least 1
  int pixel_height() const;
};

// Partial scene state carried by hello and by camera/tf/render messages.
struct StatePatch {
  std::optional<Camera> camera;
  std::optional<TransferFunction> tf;
  double opacity_unit = 0.0;
  std::optional<nlohmann::json> render;  // validated render settings object, merged over the current ones
  std::optional<glm::dvec3> background;
  int64_t time = 0;  // a time series' time point (a share link's)
};

struct Hello {
  std::string token, volume;
  Viewport viewport;
  StatePatch state;
};
struct CameraMsg {
  Camera camera;
};
struct TfMsg {
  TransferFunction tf;
  double opacity_unit = 0.0;
  uint32_t version = 0;
};
struct RenderMsg {
  nlohmann::json render;
};
struct QualityMsg {
  std::optional<double> interactive_scale;                // 0.1..1
  std::optional<double> interactive_ms;                   // 0..1000; 0: a fixed interactive scale
  std::optional<int> interactive_quality, final_quality;  // 10..100
  std::optional<std::string> final_format;                // jpeg | png
  std::optional<std::string> codec;  // interactive frames: jpeg, or a video codec this server encodes
  std::optional<int> kbps;           // the stream's bit-rate ceiling (capped by --max-kbps)
};
// A video client lost or could not decode a frame: the next interactive frame is a key frame.
struct KeyframeMsg {};
struct ViewportMsg {
  Viewport viewport;
};
struct VolumeMsg {
  std::string volume;
};
// A time series' time point to show (docs/scenes.md, "Time"); camera and TF stay.
struct TimeMsg {
  int64_t time = 0;
};
struct AckMsg {
  uint32_t frame = 0;
};
struct PingMsg {
  std::string id;
};
// One ray-texture stroke as it is painted; `seq` is the client's number for it, echoed in the
// stroke_ack that says the stroke is in the session's texture.
struct StrokeMsg {
  uint32_t seq = 0;
  Stroke stroke;
};

// What lies under a pixel of the view (device pixels of the viewport, from the top left):
// answered by a probe message with the same id (reference::probe_reference).
struct ProbeMsg {
  uint32_t id = 0;
  int x = 0, y = 0;
  std::string pick = "surface";  // "surface" | "half" (reference::ProbePick)
};
using ClientMessage = std::variant<Hello, CameraMsg, TfMsg, RenderMsg, QualityMsg, ViewportMsg, VolumeMsg, AckMsg,
                                   PingMsg, StrokeMsg, ProbeMsg, KeyframeMsg, TimeMsg>;

// Throws ProtocolError (bad_json, too_large, bad_message, unknown_type).
ClientMessage parse_client_message(const std::string& text);

// Server -> client text messages (proto/server_messages.schema.json), built here only.
std::string error_message(const std::string& code, const std::string& message);
std::string pong_message(const std::string& id);
// A stroke is in the session's ray texture, which now holds `strokes` strokes.
std::string stroke_ack_message(uint32_t seq, size_t strokes);
// A probe's answer: {"hit", "position", "value", "distance", "opacity", "pick"} (position and
// value null without a hit; pick: which point answered, "surface" or "half"), the body of POST /api/probe too; the
// message adds type and id.
nlohmann::json probe_json(bool hit, const glm::dvec3& position, double value, double distance, double opacity,
                          const char* pick);
// Reads a probe's optional "pick": "surface" (the default) or "half"; ProtocolError naming `where`.
std::string parse_pick(const nlohmann::json& j, const std::string& where);
std::string probe_message(uint32_t id, const nlohmann::json& answer);
// Reads "pixel": [x, y] (non-negative integers) of a probe message or REST body.
std::pair<int, int> parse_pixel(const nlohmann::json& j, const std::string& where);
// A volume being read for this client (hello or volume message): the fraction read so far.
std::string loading_message(const std::string& volume, double fraction);
// The view at rest being drawn at a pyramid's finest level, brick by brick: the share done.
std::string refining_message(double fraction, int bricks);
// A volume switch: the new volume's info (with histogram) and the session's reset state.
std::string volume_message(const nlohmann::json& volume_info, const nlohmann::json& state);
struct Welcome {
  std::string session, gl_renderer, backend;
  nlohmann::json volume, volumes, state, capabilities, limits;
};
std::string welcome_message(const Welcome& w);
// Per-frame stats: `render_stats` is RenderStats' JSON form (the same keys the CLI writes).
std::string stats_message(uint32_t frame, bool final, int width, int height, const nlohmann::json& render_stats,
                          double encode_ms, size_t bytes);

// Binary frame: this header, then the image bytes (JPEG, or PNG for a final frame when asked), or
// for a video session's interactive frames one access unit of its codec (kVideo; kKey: a key frame).
struct FrameHeader {
  static constexpr uint32_t kMagic = 0x31464350;  // "PCF1" little-endian
  static constexpr uint16_t kVersion = 1;
  static constexpr uint16_t kSize = 64;
  enum Flags : uint32_t { kFinal = 1, kInteractive = 2, kPng = 4, kVideo = 8, kKey = 16 };
  uint32_t frame_id = 0;
  uint32_t flags = 0;
  uint32_t camera_version = 0, tf_version = 0, render_version = 0;
  uint32_t width = 0, height = 0, quality = 0;
  uint64_t t_input_us = 0, t_render_done_us = 0, t_encode_done_us = 0;  // server steady clock
};

std::vector<uint8_t> encode_frame(const FrameHeader& h, const std::vector<uint8_t>& image);
// Throws ProtocolError("bad_frame") when the bytes are not a frame.
FrameHeader decode_frame_header(const uint8_t* data, size_t size);

}  // namespace peakcast::protocol
