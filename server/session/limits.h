// Every limit at the edge of the server, with its unit. The serve command can
// override the ones marked (cfg).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>

namespace peakcast::limits {

constexpr size_t kMaxWsMessageBytes =
    256 * 1024;  // one WebSocket text message (a 1024-point TF fits); larger: error reply
constexpr size_t kMaxWsReadBytes = 4 * 1024 * 1024;  // larger than this is not even read: the socket closes (1009)
constexpr int kTimeReadAhead = 8;  // time points read ahead of a viewer stepping a series (within the budget)
constexpr size_t kMaxHttpBodyBytes = 1024 * 1024;      // one REST request body
constexpr size_t kMaxHttpHeaderBytes = 16 * 1024;      // request line + headers
constexpr int kMaxViewportSide = 8192;                 // pixels, after the device pixel ratio
constexpr int64_t kMaxViewportPixels = 4096ll * 4096;  // pixels per streamed frame
constexpr double kMinDpr = 0.25, kMaxDpr = 4.0;        // device pixel ratio
constexpr int kMaxFramesInFlight = 2;                  // un-acknowledged frames per client
constexpr int kMaxConnections = 256;           // open TCP connections (HTTP + WebSocket); beyond: closed at accept
constexpr int kMaxConnectionsPerAddress = 32;  // of those, from one client address: one host cannot take them all
constexpr double kMaxMessagesPerSecond =
    250;  // per WebSocket client, sustained; faster senders are read more slowly (TCP backpressure)
constexpr double kMessageBurst = 500;  // messages a client may send at once before the rate applies
constexpr std::chrono::seconds kWsWriteTimeout{
    30};  // one frame or message not written in this time: the client is too slow, closed
constexpr size_t kMaxQueuedTextMessages = 64;             // per client; beyond, the client is too slow: closed
constexpr int kDefaultMaxSessions = 16;                   // (cfg) concurrent WebSocket sessions
constexpr std::chrono::seconds kDefaultIdleTimeout{600};  // (cfg) no message from the client for this long
constexpr std::chrono::seconds kHandshakeTimeout{10};     // HTTP request / WebSocket handshake
constexpr std::chrono::seconds kHttpWriteTimeout{60};     // writing one HTTP response (a large still to a slow client)
constexpr std::chrono::milliseconds kStillDelay{150};     // input quiet this long -> one final frame
constexpr double kDefaultMaxFps = 60.0;                   // (cfg) frames per second per session
constexpr int64_t kDefaultGpuBudgetBytes = int64_t(4) << 30;  // (cfg) volume bytes resident on the GPU
constexpr int kMaxPingIdLength = 64;                          // characters
constexpr size_t kMaxTokenLength = 256;        // characters of an access token (hello.token, ?token=, Bearer)
constexpr size_t kMaxVolumeNameLength = 1024;  // characters of a volume name (hello.volume, volume, REST)
constexpr int kMinJpegQuality = 10, kMaxJpegQuality = 100;  // JPEG quality, streamed frames and stills
constexpr int kMinKbps = 100, kMaxKbps = 200000;            // a video stream's bit-rate ceiling, kbit/s
constexpr int kDefaultMaxKbps = 8000;          // (cfg) the ceiling a session starts with and may not exceed
constexpr size_t kDefaultMaxQueuedStills = 4;  // (cfg) REST stills waiting or rendering; beyond: 503 + Retry-After
constexpr double kDefaultMaxStillSamples =
    8e9;  // (cfg) estimated samples (pixels x samples per ray) of one still; beyond: 422
constexpr double kStillBandSamples =
    1.5e7;  // estimated samples per band of a still: bounds a viewer's wait (~50-100 ms on llvmpipe)
constexpr std::chrono::seconds kStillRetryAfter{5};               // Retry-After of a 503 for a full still queue
constexpr int64_t kDefaultMaxUploadBytes = int64_t(4) << 30;      // (cfg) one volume upload's body
constexpr int64_t kDefaultUploadBudgetBytes = int64_t(16) << 30;  // (cfg) every upload kept, in all
constexpr int kDefaultMaxConcurrentUploads = 2;                   // (cfg) uploads being received at once; beyond: 503
constexpr double kUploadsPerMinutePerClient = 60;  // (cfg) per client address, sustained (a burst of 10); beyond: 429
constexpr double kUploadBurst = 10;
constexpr std::chrono::seconds kDefaultUploadIdleTimeout{30};  // (cfg) no upload bytes for this long: the upload ends
constexpr size_t kMaxUploadNameLength = 200;                   // bytes of an upload's name (UTF-8, cut at a character)
constexpr double kDefaultUploadMinBytesPerSecond =
    16 * 1024;  // (cfg) an upload's average rate after its first idle timeout
constexpr std::chrono::seconds kDefaultUploadDeadline{3600};  // (cfg) the whole body of one upload
// SIGTERM -> forced exit, if the graceful path has not finished. Sanitizer builds wait longer: a
// report being written (stacks symbolized, seconds on a loaded machine) must not be cut off.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr std::chrono::milliseconds kShutdownGrace{30000};
#else
constexpr std::chrono::milliseconds kShutdownGrace{4000};
#endif
constexpr std::chrono::milliseconds kCloseFlush{1000};  // SIGTERM: time given to WebSocket close frames and answers

}  // namespace peakcast::limits
