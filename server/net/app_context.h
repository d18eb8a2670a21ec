// What every connection shares: configuration, volumes, the render service, metrics.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/thread_pool.hpp>

#include "core/metrics.h"
#include "core/ray_texture_png.h"
#include "net/access.h"
#include "net/connection_slot.h"
#include "net/http_text.h"
#include "net/static_files.h"
#include "net/session_registry.h"
#include "session/chunked_upload.h"
#include "session/residency.h"
#include "session/limits.h"
#include "session/render_service.h"
#include "session/upload_store.h"
#include "session/volume_store.h"

namespace peakcast::net {

struct ServerConfig {
  std::string bind = "127.0.0.1";
  uint16_t port = 8080;
  std::vector<std::filesystem::path> data_dirs;
  std::vector<std::filesystem::path> volumes;  // preloaded; the first is the default
  std::string token;                           // the admin token; empty (and no user_tokens): no authentication
  std::vector<UserToken> user_tokens;          // --user-token-file: view, render, upload, delete their own uploads
  std::vector<std::string> allow_origins;      // besides the server's own origin
  std::vector<std::string> allowed_hosts;      // Host names besides the bind address and loopback ("*": any)
  int max_sessions = limits::kDefaultMaxSessions;
  std::chrono::seconds idle_timeout = limits::kDefaultIdleTimeout;
  double max_fps = limits::kDefaultMaxFps;
  int max_kbps = limits::kDefaultMaxKbps;  // a video session's bit-rate ceiling (docs/streaming.md)
  int64_t gpu_budget_bytes = limits::kDefaultGpuBudgetBytes;
  int64_t memory_budget_bytes = 0;            // host memory for one volume's voxels (0: none); LoadOptions
  int64_t preview_voxels = int64_t(1) << 24;  // a pyramid's first look (VolumeStore::set_preview); 0: off
  size_t max_queued_stills = limits::kDefaultMaxQueuedStills;
  double max_still_samples = limits::kDefaultMaxStillSamples;
  double still_band_samples = limits::kStillBandSamples;
  int io_threads = 2;
  int encode_threads = 2;
  std::filesystem::path web_dir, shader_dir;
  std::string egl_device;     // "auto" | "surfaceless" | a device index; empty: PEAKCAST_EGL_DEVICE, else auto
  std::string backend;        // "auto" | "gl" | "cpu" (render/backend.h); empty: PEAKCAST_BACKEND, else auto
  std::string program_cache;  // GL program binaries: "auto", "off" or a folder (render/backend.h)
  // mpirun peakcast serve: RenderServiceOptions::wrap_renderer and ranks.
  std::function<std::unique_ptr<render::Renderer>(std::unique_ptr<render::Renderer>)> wrap_renderer;
  int ranks = 1;
  // mpirun peakcast serve: reads volumes as bricks on every rank (VolumeStore); empty: whole.
  VolumeLoader volume_loader;
  // Uploads (POST /api/volumes): their folder (empty: off) and limits.
  std::filesystem::path upload_dir;
  UploadLimits upload_limits;
};

// Where the server reads (core/file_roots.h): the data directories, the upload folder and the
// preloaded volumes' folders. AppContext confines the process to them before anything is read.
std::vector<std::filesystem::path> read_roots(const ServerConfig& c);

struct AppContext {
  ServerConfig config;
  Metrics metrics;
  Residency residency;  // the GPU budget's one owner
  VolumeStore volumes;
  UploadStore uploads;
  ChunkedUploads chunked_uploads;  // arrays sent chunk by chunk (session/chunked_upload.h)
  RenderService render;
  SessionRegistry ws_sessions;
  ConnectionCounter connections{limits::kMaxConnections, limits::kMaxConnectionsPerAddress};
  std::atomic<bool> stopping{false};  // graceful shutdown under way: refuse new work
  std::atomic<uint64_t> next_session{1};
  Access access;      // who a token is (net/access.h)
  HostCheck hosts;    // which Host headers are answered (DNS rebinding)
  StaticFiles files;  // the client's files and docs: a fixed list made at start-up
  // The data-directory browser's listings: apart from the loader, so that no volume load (a
  // pyramid's metadata, a slow disk) holds up a listing.
  boost::asio::thread_pool listing{1};

  // Volume loads run here, never on an io thread (an 800 MB stack takes seconds). Declared last:
  // joined first on destruction, while the volumes it fills still exist.
  boost::asio::thread_pool loader{1};
  // A pyramid's long reads (its finest level's statistics, the level within the budget after a
  // preview): apart from the loader, so that minutes of reading hold up no load, PNG or probe.
  boost::asio::thread_pool pyramid{1};
  // A time series' next time points, read ahead of a viewer stepping through them: apart from the
  // loader, so that a volume asked for waits for no read-ahead.
  boost::asio::thread_pool ahead{1};
  // Chunked uploads: their chunks written to disk, and their pyramids built (minutes for
  // gigabytes), each apart from the io threads and every other pool.
  boost::asio::thread_pool chunk_writes{1};
  boost::asio::thread_pool builds{1};

  explicit AppContext(ServerConfig c);
  // Ray-texture PNGs, like volumes given by path, are read only from inside the data directories.
  PngLocator png_locator() const;
};

}  // namespace peakcast::net
