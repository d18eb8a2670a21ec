// The render thread (DESIGN §2): owns the one GL context and every GL object; picks the next
// session with work (latest state wins), renders, and hands the image to the encode pool,
// whose threads deliver to the session's connection. REST stills go through the same thread.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/metrics.h"
#include "encode/encode_pool.h"
#include "session/session.h"
#include "session/volume_store.h"

namespace peakcast {

struct RenderServiceOptions {
  std::filesystem::path shader_dir;
  int encode_threads = 2;
  double max_fps = 60.0;
  std::chrono::milliseconds still_delay{150};
};

struct StillResult {
  std::vector<uint8_t> bytes;
  std::string content_type;
  double render_ms = 0, encode_ms = 0, samples_per_ray = 0;
  std::string variant, error;  // error: the job failed (message for the client)
};

struct StillJob {
  std::shared_ptr<VolumeEntry> volume;
  ResolvedScene scene;
  bool png = true;
  int quality = 95;
  std::function<void(StillResult)> done;  // called on an encode thread
};

class RenderService {
 public:
  RenderService(VolumeStore& volumes, Metrics& metrics, RenderServiceOptions options);
  ~RenderService();

  // Creates the GL context on the render thread; throws if that fails.
  void start();
  void stop();
  std::string gl_renderer() const;

  void add_session(const std::shared_ptr<Session>& s);
  void remove_session(const std::string& id);
  void notify();  // some session's state or acks changed
  void submit_still(StillJob job);
  size_t session_count() const;

 private:
  struct Impl;
  void loop();
  VolumeStore& volumes_;
  Metrics& metrics_;
  RenderServiceOptions options_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::map<std::string, std::weak_ptr<Session>> sessions_;
  std::deque<StillJob> stills_;
  bool stopping_ = false, wake_ = false;
  std::string gl_renderer_;
  std::unique_ptr<encode::EncodePool> pool_;
  std::unique_ptr<Impl> thread_impl_;  // touched only by the render thread
  std::thread thread_;
};

}  // namespace peakcast
