#include "distributed/mpi_renderer.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/volume_io.h"
#include "distributed/brick_frame.h"
#include "render/brick.h"
#include "distributed/opacity_chain.h"
#include "distributed/ray_texture_sync.h"
#include "distributed/coordinator.h"
#include "distributed/icet_compositor.h"
#include "distributed/kd_split.h"
#include "encode/png.h"

namespace peakcast::distributed {
namespace {

// One rank's brick of one volume, made resident for its renderer.
struct BrickSet {
  VolumeBox box;
  Index3 dims{};
  int ghost = 0;
  KdSplit split;
  Brick mine;
  std::unique_ptr<render::ResidentVolume> brick;
};

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

BrickSet make_set(BrickRead&& r, render::Renderer& renderer) {
  BrickSet b;
  b.box = r.box;
  b.dims = r.dims;
  b.ghost = r.ghost;
  b.split = std::move(r.split);
  b.mine = r.mine;
  b.brick = renderer.make_resident(std::move(r.voxels), std::move(r.cells));
  return b;
}

// A re-read of every brick of `volume`'s file (its time point) with the range already known (no
// statistics reduced).
BrickLoadRequest reread(const Volume& volume, const VolumeBox& box, int ghost) {
  BrickLoadRequest r;
  r.path = volume.source_path;
  r.time_point = volume.time_point;
  r.ghost = ghost;
  r.have_range = true;
  r.lo = box.min_value;
  r.hi = box.max_value;
  return r;
}

struct Composited {
  std::vector<float> rgba;     // rank 0: the composite of the rect, premultiplied
  std::vector<float> samples;  // rank 0: samples per pixel summed over the ranks (when asked)
  render::RenderStats stats;   // this rank's brick
  double composite_ms = 0.0;
};

// Every rank: its brick's layer of `rect`, composited by IceT onto rank 0.
Composited render_composite(BrickSet& b, const ResolvedScene& rs, const render::PixelRect& rect, bool samples,
                            render::Renderer& renderer, IceTCompositor& icet) {
  Composited c;
  const glm::dvec3 eye = (rs.camera.eye - b.box.origin) / b.box.spacing;
  const glm::dvec3 dir = glm::normalize((rs.camera.center - rs.camera.eye) / b.box.spacing);
  const std::vector<int> order = visibility_order(b.split, eye, dir, rs.camera.orthographic);
  render::Brick brick = frame_brick(b.mine, b.dims);
  if (rs.ray_texture) brick.front_opacity = receive_front_opacity(order, size_t(rect.w) * size_t(rect.h));
  const Image layer = renderer.render_brick(*b.brick, rs, brick, &c.stats, rect);
  if (rs.ray_texture) send_opacity_behind(order, brick.front_opacity.get(), layer);
  CompositeTiming t;
  c.rgba = icet.composite(layer.rgba, layer.width, layer.height, order, &t);
  c.composite_ms = t.ms;
  if (samples) {
    std::vector<float> mine(layer.samples.size());
    for (size_t k = 0; k < mine.size(); ++k) mine[k] = std::max(layer.samples[k], 0.f);
    if (world_rank() == 0) c.samples.resize(mine.size());
    MPI_Reduce(mine.data(), c.samples.data(), int(mine.size()), MPI_FLOAT, MPI_SUM, 0, MPI_COMM_WORLD);
  }
  return c;
}

// A render command's payload (CBOR: a ray texture's PNG texels go as binary): the scene without
// its ray texture, which goes as what the workers lack of it (distributed/ray_texture_sync.h).
std::string render_command(const ResolvedScene& s, const render::PixelRect& rect, bool samples,
                           RayTextureSender& textures) {
  Scene bare = s.scene;
  bare.render.ray_texture = nullptr;  // not its strokes every frame
  // The TF and camera as resolved here: a derived TF comes from the whole volume's histogram,
  // which only this rank holds.
  bare.tf = s.tf;
  bare.opacity_unit = s.tf.opacity_unit;
  bare.camera = s.camera;
  nlohmann::json j = {{"scene", scene_to_json(bare)},
                      {"step", s.step},
                      {"rect", {rect.x, rect.y, rect.w, rect.h}},
                      {"samples", samples}};
  if (s.ray_texture) j["ray_texture"] = textures.message(*s.ray_texture);
  const std::vector<uint8_t> cbor = nlohmann::json::to_cbor(j);
  return std::string(cbor.begin(), cbor.end());
}

ResolvedScene scene_of(const nlohmann::json& j, const VolumeBox& box, RayTextureReceiver& textures) {
  Scene scene = parse_scene(j.at("scene"));
  if (j.contains("ray_texture")) scene.render.ray_texture = textures.apply(j.at("ray_texture"));
  ResolvedScene rs = resolve_scene(scene, box);
  rs.step = j.at("step");  // interactive frames take a longer step than the scene's
  return rs;
}

render::PixelRect rect_of(const nlohmann::json& j) {
  const auto& r = j.at("rect");
  return render::PixelRect{r[0], r[1], r[2], r[3]};
}

}  // namespace

// IceT's context duplicates the communicator (a collective): every rank makes it on its first
// render command, in the same place of the command sequence, not at start-up, where rank 0's
// loader may already be in a volume load's collectives.
static IceTCompositor& icet_of(std::unique_ptr<IceTCompositor>& icet) {
  if (!icet) icet = std::make_unique<IceTCompositor>(MPI_COMM_WORLD, 0);
  return *icet;
}

struct MpiRenderer::Impl {
  Impl(std::shared_ptr<Coordinator> c, std::unique_ptr<render::Renderer> local)
      : coord(std::move(c)), local(std::move(local)), renderer(*this->local) {}
  std::shared_ptr<Coordinator> coord;
  std::unique_ptr<render::Renderer> local;
  render::Renderer& renderer;
  std::unique_ptr<IceTCompositor> icet;  // icet_of
  RayTextureSender ray_textures;         // under the coordinator's lock, as every send
};

class MpiRenderer::Resident : public render::ResidentVolume {
 public:
  Resident(std::shared_ptr<Coordinator> coord, int64_t id, std::shared_ptr<const Volume> whole, BrickSet b)
      : ResidentVolume(std::move(whole), {}, VoxelsElsewhere{}),
        coord_(std::move(coord)),
        id_(id),
        bricks(std::move(b)) {}
  ~Resident() override { coord_->forget(id_); }
  size_t resident_bytes() const override { return bricks.brick->volume().byte_size(); }
  bool drop_host_voxels() override {  // the bricks are the copy; the whole volume need not stay
    if (!volume_->has_voxels()) return false;
    volume_->drop_voxels();
    return true;
  }
  int64_t id() const { return id_; }

  std::shared_ptr<Coordinator> coord_;
  int64_t id_;
  BrickSet bricks;
};

MpiRenderer::MpiRenderer(std::shared_ptr<Coordinator> coord, std::unique_ptr<render::Renderer> local)
    : ranks_(coord->ranks()), impl_(std::make_unique<Impl>(std::move(coord), std::move(local))) {
  // Every rank must draw with the same backend: the CPU and GL ray casters round a point's
  // position differently, so a face between their bricks could draw a point twice or never.
  auto held = impl_->coord->lock();
  impl_->coord->send(held, kBackend, 0, impl_->renderer.backend());
}

const char* MpiRenderer::backend() const { return impl_->renderer.backend(); }

MpiRenderer::~MpiRenderer() {
  auto held = impl_->coord->lock();
  impl_->coord->send(held, kQuit, 0);
  impl_->coord->close(held);  // a load queued during shutdown is refused, not sent to no one
  impl_->icet.reset();        // frees its communicator: an MPI call, under the lock
}

std::string MpiRenderer::description() const {
  return impl_->renderer.description() + " per rank, " + std::to_string(ranks_) + " ranks (MPI, IceT)";
}

std::unique_ptr<render::ResidentVolume> MpiRenderer::make_resident(std::shared_ptr<const Volume> volume,
                                                                   VolumeMacrocells) {
  if (volume->source_path.empty())
    throw std::invalid_argument(
        "distributed rendering reads each rank's brick from the volume's file; this volume has none");
  Coordinator& c = *impl_->coord;
  auto held = c.lock();
  if (auto loaded = c.take_loaded(held, volume.get())) {  // the server's volumes: read by Coordinator::load
    try {
      return std::make_unique<Resident>(impl_->coord, loaded->first, std::move(volume),
                                        make_set(std::move(loaded->second), impl_->renderer));
    } catch (...) {
      c.forget(loaded->first);  // this rank's copy failed (an upload): the workers' bricks go too
      throw;
    }
  }
  // A volume read whole (the CLI, tests): every rank reads its brick with the range known.
  // What would fail on a rank fails here first, before any rank is asked: a file whose regions
  // cannot be read (TIFF stacks), one changed since it was read, fewer cells than ranks.
  const Volume head = read_head(volume->source_path, volume->time_point);
  if (head.source_dims != volume->dims())
    throw std::runtime_error(volume->source_path + ": the file changed since it was read (its dims differ)");
  c.check_split(volume->source_path, head.source_dims, default_ghost());
  const VolumeBox box{volume->dims(),    volume->spacing,   volume->origin,          volume->min_value,
                      volume->max_value, volume->histogram, volume->border_histogram};
  const int64_t id = c.new_id();
  BrickRead r = c.read_bricks(held, id, reread(*volume, box, default_ghost()));
  try {
    return std::make_unique<Resident>(impl_->coord, id, std::move(volume), make_set(std::move(r), impl_->renderer));
  } catch (...) {
    c.forget(id);
    throw;
  }
}

render::RenderResult MpiRenderer::render(const render::ResidentVolume& v, const ResolvedScene& s,
                                         const render::RenderRequest& req, render::RenderStats* stats) {
  auto* res = dynamic_cast<const Resident*>(&v);
  if (!res) throw std::invalid_argument("the MPI renderer draws its own volumes only");
  const render::PixelRect rect = req.tile.value_or(render::PixelRect{0, 0, s.scene.width, s.scene.height});
  render::check_rect(rect, s.scene.width, s.scene.height);
  render::check_bricks_draw(s);  // before any rank is asked: a throw after that aborts the job
  auto& bricks = const_cast<Resident*>(res)->bricks;
  Coordinator& c = *impl_->coord;
  auto held = c.lock();  // against a volume load on the loader pool
  const auto t0 = std::chrono::steady_clock::now();
  const bool want_samples = req.output == render::RenderOutput::Float || req.sample_stats;
  if (const int need = brick_ghost(s); need > bricks.ghost) {  // a longer step than the bricks were read for
    // With headroom: a differential step grows as the camera backs away, and a re-read on
    // every frame of a slow zoom-out would cost more than the wider ghosts.
    // A read any rank failed throws: every rank keeps its bricks, this frame fails, the job goes on.
    BrickRead wider = c.read_bricks(held, res->id(), reread(res->volume(), bricks.box, need + std::max(4, need / 2)));
    try {
      bricks = make_set(std::move(wider), impl_->renderer);
    } catch (const std::exception& e) {
      abort_job(e.what());  // the workers hold the wider bricks; this rank's copy failed
    }
  }
  try {
    c.send(held, kRender, res->id(), render_command(s, rect, want_samples, impl_->ray_textures));
    Composited comp = render_composite(bricks, s, rect, want_samples, impl_->renderer, icet_of(impl_->icet));
    Image img = finish_composite(comp.rgba, rect.w, rect.h, s.scene.background);
    render::RenderResult out;
    out.rect = rect;
    if (stats) {
      *stats = comp.stats;
      stats->variant = comp.stats.variant + "+" + std::to_string(ranks_) + "ranks";
      stats->render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      stats->samples_total = stats->samples_max = 0;
      stats->rays_hit = 0;
      for (float n : comp.samples) {
        if (n <= 0) continue;
        stats->samples_total += n;
        stats->samples_max = std::max<double>(stats->samples_max, n);
        stats->rays_hit++;
      }
      stats->samples_mean = stats->rays_hit ? stats->samples_total / double(stats->rays_hit) : 0.0;
      stats->has_samples = want_samples;
    }
    if (req.output == render::RenderOutput::Rgb8) {
      out.rgb8 = render::Rgb8Image(rect.w, rect.h);
      out.rgb8.rgb = encode::to_rgb8(img);
    } else {
      img.samples = std::move(comp.samples);
      out.image = std::move(img);
    }
    return out;
  } catch (const std::exception& e) {
    abort_job(e.what());  // the workers wait in a collective: no frame can be finished without this rank
  }
}

Image MpiRenderer::render_brick(const render::ResidentVolume&, const ResolvedScene&, const render::Brick&,
                                render::RenderStats*, std::optional<render::PixelRect>) {
  throw std::invalid_argument("an MPI renderer draws whole frames: its ranks render the bricks");
}

int MpiRenderer::sample_cap(const render::VariantKey& key) const { return impl_->renderer.sample_cap(key); }

void serve_worker(render::Renderer& renderer) {
  // mpirun passes SIGTERM/SIGINT to every rank: rank 0 shuts the server down and then tells the
  // workers to stop, so they wait for that rather than die mid-frame.
  std::signal(SIGTERM, SIG_IGN);
  std::signal(SIGINT, SIG_IGN);
  try {
    std::unique_ptr<IceTCompositor> icet;  // icet_of
    std::map<int64_t, BrickSet> volumes;
    RayTextureReceiver ray_textures;
    for (;;) {
      CommandMessage m;
      broadcast(m);
      for (int64_t d : m.drops) volumes.erase(d);
      if (m.cmd == kQuit) return;
      if (m.cmd == kBackend) {
        if (m.payload != renderer.backend())
          throw std::runtime_error("this rank renders with the " + std::string(renderer.backend()) +
                                   " backend and rank 0 with " + m.payload +
                                   ": every rank needs the same (pass --backend gl or --backend cpu)");
        continue;
      }
      const nlohmann::json j =
          m.cmd == kRender ? nlohmann::json::from_cbor(m.payload) : nlohmann::json::parse(m.payload);
      if (m.cmd == kLoad) {
        BrickRead r = read_brick(BrickLoadRequest::from_json(j));
        if (!r.refused && !r.failed) volumes[m.id] = make_set(std::move(r), renderer);  // else rank 0 says why
      } else if (m.cmd == kRender) {
        BrickSet& b = volumes.at(m.id);
        render_composite(b, scene_of(j, b.box, ray_textures), rect_of(j), j.at("samples"), renderer, icet_of(icet));
      } else {
        throw std::runtime_error("unknown command " + std::to_string(m.cmd) + " from rank 0");
      }
    }
  } catch (const std::exception& e) {
    abort_job(e.what());
  }
}

}  // namespace peakcast::distributed
