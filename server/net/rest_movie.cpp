#include "net/rest_movie.h"

#include <map>
#include <mutex>

#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include "core/log.h"
#include "distributed/brick_sequence.h"
#include "net/rest_still.h"
#include "session/movie_path.h"

namespace asio = boost::asio;

namespace peakcast::net {
namespace {

// What waits for a slow client before the next frame is rendered; frames rendered or rendering
// at once (the next draws while this one is encoded).
constexpr size_t kMaxQueuedMovieBytes = size_t(8) << 20;
constexpr int kMovieFramesInFlight = 2;
constexpr auto kQueueFullRetry = std::chrono::milliseconds(50);

// A frame's volume: the entry of its time point, and for a pyramid held coarser than its finest
// level the finest level's statistics (the frame is drawn by bricks, as a still).
struct FrameVolume {
  std::shared_ptr<VolumeEntry> entry;
  std::shared_ptr<const distributed::SequenceStatistics> full;
  int64_t time = -1;
};

// On the loader pool (it may read the volume, and a pyramid's statistics).
FrameVolume frame_volume(AppContext& app, const Scene& scene, bool finest) {
  FrameVolume v;
  v.entry = app.volumes.at_time(scene.volume, scene.time);
  v.time = scene.time;
  if (v.entry->full && finest) {
    v.full = v.entry->full->statistics();
    if (!v.full) v.full = VolumeStore::full_statistics(*v.entry, app.stopping);
  }
  return v;
}

ResolvedScene resolve_for(const Scene& scene, const FrameVolume& v) {
  return v.full ? resolve_scene(scene, v.full->box) : resolve_scene(scene, *v.entry->volume);
}

// One movie being made: frames submitted to the render thread as stills (kMovieFramesInFlight at
// once), encoded in order as they come back (on the encode pool), the file's bytes streamed.
struct Movie : std::enable_shared_from_this<Movie> {
  Movie(AppContext& a, MovieRequest r, std::vector<Scene> f, bool fin)
      : app(a), request(std::move(r)), frames(std::move(f)), finest(fin) {}

  AppContext& app;
  MovieRequest request;
  std::vector<Scene> frames;
  bool finest;
  FrameVolume volume;  // the time point being drawn (only the loader pool changes it)
  std::unique_ptr<encode::MovieWriter> writer;
  std::shared_ptr<ResponseStream> stream;
  std::shared_ptr<std::atomic<bool>> cancelled;
  std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
  std::mutex m;
  int next_submit = 0, next_write = 0, in_flight = 0;
  std::map<int, std::vector<uint8_t>> ready;
  bool over = false;

  void pump() {
    std::unique_lock lock(m);
    while (!over && in_flight < kMovieFramesInFlight && next_submit < int(frames.size())) {
      if (stream->queued_bytes() > kMaxQueuedMovieBytes) {  // a slow client: wait for it
        lock.unlock();
        return stream->when_drained([self = shared_from_this()] { self->pump(); });
      }
      const int i = next_submit++;
      ++in_flight;
      lock.unlock();
      submit(i);
      lock.lock();
    }
  }

  // Frame i to the render thread; a frame of another time point reads it on the loader first.
  void submit(int i) {
    if (cancelled->load()) return finish_with_error("the client went away");
    std::shared_ptr<VolumeEntry> entry;
    {
      std::lock_guard lock(m);
      if (volume.time == frames[size_t(i)].time) entry = volume.entry;
    }
    if (!entry)
      return asio::post(app.loader, [self = shared_from_this(), i] {
        try {
          FrameVolume v = frame_volume(self->app, self->frames[size_t(i)], self->finest);
          std::lock_guard lock(self->m);
          self->volume = std::move(v);
        } catch (const std::exception& e) {
          return self->finish_with_error(e.what());
        }
        self->submit(i);
      });
    StillJob job;
    try {
      std::lock_guard lock(m);
      job.scene = resolve_for(frames[size_t(i)], volume);
      job.volume = volume.entry;
      job.full_statistics = volume.full;
    } catch (const std::exception& e) {
      return finish_with_error(e.what());
    }
    job.png = false;
    job.raw_rgb = true;
    job.cancelled = cancelled;
    job.done = [self = shared_from_this(), i](StillResult r) { self->on_frame(i, std::move(r)); };
    if (app.render.submit_still(std::move(job))) return;
    if (app.stopping.load()) return finish_with_error("the server is shutting down");
    // The still queue is full (other scripts' stills): this frame waits its turn, never fails. A
    // timer of its own: both frames in flight may wait at once.
    auto timer = std::make_shared<asio::steady_timer>(app.loader.get_executor(), kQueueFullRetry);
    timer->async_wait([self = shared_from_this(), i, timer](const boost::system::error_code& ec) {
      if (!ec) self->submit(i);
    });
  }

  // On the encode pool: frame i drawn. Frames are encoded in order (two may finish out of it).
  void on_frame(int i, StillResult r) {
    {
      std::lock_guard lock(m);
      --in_flight;
      if (over) return;
      if (!r.error.empty()) return end_locked(r.error_code + ": " + r.error);
      ready[i] = std::move(r.bytes);
      try {
        for (auto it = ready.find(next_write); it != ready.end(); it = ready.find(next_write)) {
          stream->write(writer->add(it->second.data()));
          ready.erase(it);
          ++next_write;
        }
        if (next_write == int(frames.size())) {
          stream->write(writer->finish());
          return end_locked("");
        }
      } catch (const std::exception& e) {
        return end_locked(e.what());
      }
    }
    pump();
  }

  void finish_with_error(const std::string& why) {
    std::lock_guard lock(m);
    end_locked(why);
  }

  // The end: the last chunk, or (an error after the header was sent) a body cut short.
  void end_locked(const std::string& error) {
    if (over) return;
    over = true;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    const char* outcome = error.empty() ? "ok" : cancelled->load() ? "cancelled" : "failed";
    app.metrics.add("peakcast_movies_total", std::string("outcome=\"") + outcome + "\"", 1);
    log::info("movie", {{"volume", request.scene.volume},
                        {"frames", next_write},
                        {"of", frames.size()},
                        {"format", encode::to_string(request.format)},
                        {"seconds", seconds},
                        {"error", error}});
    if (error.empty()) return stream->end();
    stream->abort();
  }
};

// The header sent before the first frame: what the file is, and what the scene will get.
StreamHeader movie_header(const Request& req, const Movie& mv, const ResolvedScene& first) {
  const MovieRequest& m = mv.request;
  StreamHeader h{http::status::ok, req.version()};
  h.set(http::field::content_type, encode::content_type(m.format));
  h.set(http::field::cache_control, "no-store");
  std::string name = m.scene.volume.substr(m.scene.volume.find_last_of('/') + 1);
  for (char& c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  h.set(http::field::content_disposition,
        "attachment; filename=\"" + name.substr(0, 100) + "." + encode::file_extension(m.format) + "\"");
  h.set("X-Frames", std::to_string(mv.frames.size()));
  h.set("X-Fps", std::to_string(m.fps));
  h.set("X-Format", encode::to_string(m.format));
  h.set("X-Encoder", mv.writer->encoder_name());
  h.set("X-Width", std::to_string(m.scene.width));
  h.set("X-Height", std::to_string(m.scene.height));
  h.set("X-Level", std::to_string(mv.volume.full ? 0 : mv.volume.entry->volume->pyramid_level));
  h.set("X-TF-Source", first.tf_derived ? "auto" : "scene");
  for (const std::string& w : first.warnings) h.insert("X-Warning", w);
  h.keep_alive(req.keep_alive());
  return h;
}

// What the request asks that this build or these limits refuse before any work ("" if none).
std::string format_refusal(const MovieRequest& m) {
  if (!encode::movie_format_available(m.format))
    return std::string("this server was built without ") + encode::to_string(m.format) +
           " (libavcodec/libavformat): formats png-zip and rgb work everywhere";
  return "";
}

void refuse_movie(AppContext& app, const Request& req, const std::function<void(Response)>& send, http::status status,
                  const char* code, const std::string& message) {
  count(app, "movie", status);
  send(error_response(req, status, code, message));
}

}  // namespace

void movie(AppContext& app, const Request& req, std::function<void(Response)> send,
           std::shared_ptr<std::atomic<bool>> cancelled, OpenStream open_stream) {
  auto refuse = [&app, &send](const Request& r, http::status status, const char* code, const std::string& message) {
    refuse_movie(app, r, send, status, code, message);
  };
  if (req.method() != http::verb::post)
    return refuse(req, http::status::method_not_allowed, "bad_request", "POST a scene with \"path\"");
  if (app.stopping.load())
    return refuse(req, http::status::service_unavailable, "shutting_down", "the server is shutting down");
  MovieRequest m;
  try {
    m = parse_movie_text(req.body());
    const bool video = m.format == encode::MovieFormat::Mp4 || m.format == encode::MovieFormat::Webm;
    if (video && (m.scene.width % 2 || m.scene.height % 2))
      throw SceneError("image: an " + std::string(encode::to_string(m.format)) +
                       " movie needs an even width and height (" + "4:2:0 video), not " +
                       std::to_string(m.scene.width) + "x" + std::to_string(m.scene.height));
  } catch (const SceneError& e) {
    return refuse(req, http::status::bad_request, "bad_scene", e.what());
  }
  if (const std::string why = format_refusal(m); !why.empty())
    return refuse(req, http::status::unprocessable_entity, "not_supported", why);
  const std::string resolution = query_param(std::string(req.target()), "resolution");
  if (!resolution.empty() && resolution != "full" && resolution != "held")
    return refuse(req, http::status::bad_request, "bad_request", "resolution must be full or held");
  auto stream = open_stream ? open_stream() : nullptr;  // on this strand, before anything is posted
  if (!stream) return refuse(req, http::status::internal_server_error, "internal", "this connection cannot stream");
  asio::post(
      app.loader, [&app, req, m = std::move(m), finest = resolution != "held", send, cancelled, stream]() mutable {
        auto refuse = [&](const Request& r, http::status status, const char* code, const std::string& message) {
          refuse_movie(app, r, send, status, code, message);
        };
        try {
          m.scene.render.ray_texture = load_ray_texture_png(m.scene.render.ray_texture, app.png_locator());
          FrameVolume v = frame_volume(app, m.scene, finest);
          const ResolvedScene first = resolve_for(m.scene, v);
          if (const std::string why = still_cost_refusal(app, first); !why.empty())
            return refuse(req, http::status::unprocessable_entity, "too_costly", why);
          std::vector<Scene> frames = movie_frames(m, first);
          for (Scene& s : frames) {
            if (const std::string why = time_refusal(s.time, v.entry->volume->time_points); !why.empty())
              throw SceneError(why);
            if (!s.tf) s.tf = first.tf, s.opacity_unit = first.tf.opacity_unit;  // derived once, not per frame
            validate_camera(*s.camera);
          }
          const double most = double(m.scene.width) * m.scene.height * 3.0 * double(frames.size()) + 1e6;
          if (m.format == encode::MovieFormat::PngZip && most > 4.0e9)
            return refuse(req, http::status::unprocessable_entity, "too_large",
                          "a png-zip movie stays under 4 GB: this one could take " + std::to_string(int(most / 1e9)) +
                              " GB; use mp4 or webm, or fewer or smaller frames");
          auto mv = std::make_shared<Movie>(app, std::move(m), std::move(frames), finest);
          mv->volume = std::move(v);
          mv->writer = encode::open_movie_writer({mv->request.format, mv->request.scene.width, mv->request.scene.height,
                                                  mv->request.fps, mv->request.quality});
          mv->stream = stream;
          mv->cancelled = cancelled;
          count(app, "movie", http::status::ok);
          stream->begin(movie_header(req, *mv, first));
          mv->pump();
        } catch (const SceneError& e) {
          refuse(req, http::status::bad_request, "bad_scene", e.what());
        } catch (const std::invalid_argument& e) {  // a camera the path turned degenerate
          refuse(req, http::status::bad_request, "bad_scene", e.what());
        } catch (const VolumeError& e) {
          refuse(req, http::status::not_found, "volume_error", e.what());
        } catch (const std::exception& e) {
          refuse(req, http::status::internal_server_error, "internal", e.what());
        }
      });
}

}  // namespace peakcast::net
