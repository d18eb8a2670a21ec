#include "dist/mpi_renderer.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/volume_io.h"
#include "dist/brick_frame.h"
#include "dist/icet_compositor.h"
#include "dist/kd_split.h"
#include "encode/png.h"

namespace peakcast::dist {
namespace {

enum Command : int64_t { kLoad = 1, kRender = 2, kQuit = 3, kBackend = 4 };

// One rank's brick of one volume.
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

[[noreturn]] void abort_job(const char* what) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::fprintf(stderr, "peakcast: error on rank %d of %d: %s\n", world_rank(), size, what);
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort();
}

// Rank 0 fills cmd, id, payload and drops; the others receive them.
void broadcast(int64_t& cmd, int64_t& id, std::string& payload, std::vector<int64_t>& drops) {
  int64_t head[4] = {cmd, id, int64_t(payload.size()), int64_t(drops.size())};
  MPI_Bcast(head, 4, MPI_INT64_T, 0, MPI_COMM_WORLD);
  cmd = head[0];
  id = head[1];
  payload.resize(size_t(head[2]));
  drops.resize(size_t(head[3]));
  if (!payload.empty()) MPI_Bcast(payload.data(), int(payload.size()), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (!drops.empty()) MPI_Bcast(drops.data(), int(drops.size()), MPI_INT64_T, 0, MPI_COMM_WORLD);
}

// Every rank: its brick of the file, with the whole volume's value range.
BrickSet load_bricks(const nlohmann::json& j, render::Renderer& renderer) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const std::string path = j.at("path");
  LoadOptions one;
  one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
  const Volume head = load_volume(path, one);
  BrickSet b;
  b.box = VolumeBox{head.source_dims, head.spacing, head.origin, j.at("lo"), j.at("hi")};
  b.dims = {head.source_dims[0], head.source_dims[1], head.source_dims[2]};
  b.ghost = j.at("ghost");
  b.split = kd_split(b.dims, size, b.ghost);
  b.mine = b.split.bricks[size_t(rank)];
  LoadOptions region;
  region.region = VoxelRegion{b.mine.read_lo, b.mine.read_hi};
  // NaN/Inf voxels take the whole volume's finite extremes, as in one process: its value range
  // (rank 0 read it whole, replacing them with those extremes, which therefore bound it).
  region.nonfinite = NonFinitePolicy::Keep;
  auto v = std::make_shared<Volume>(load_volume(path, region));
  replace_nonfinite(*v, float(b.box.min_value - v->value_offset), float(b.box.max_value - v->value_offset));
  v->min_value = b.box.min_value;
  v->max_value = b.box.max_value;
  b.brick = renderer.make_resident(std::move(v));
  return b;
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
  const Image layer = renderer.render_brick(*b.brick, rs, frame_brick(b.mine, b.dims), &c.stats, rect);
  const glm::dvec3 eye = (rs.camera.eye - b.box.origin) / b.box.spacing;
  const glm::dvec3 dir = glm::normalize((rs.camera.center - rs.camera.eye) / b.box.spacing);
  CompositeTiming t;
  c.rgba = icet.composite(layer.rgba, layer.width, layer.height, visibility_order(b.split, eye, dir, rs.camera.orthographic), &t);
  c.composite_ms = t.ms;
  if (samples) {
    std::vector<float> mine(layer.samples.size());
    for (size_t k = 0; k < mine.size(); ++k) mine[k] = std::max(layer.samples[k], 0.f);
    if (world_rank() == 0) c.samples.resize(mine.size());
    MPI_Reduce(mine.data(), c.samples.data(), int(mine.size()), MPI_FLOAT, MPI_SUM, 0, MPI_COMM_WORLD);
  }
  return c;
}

ResolvedScene scene_of(const nlohmann::json& j, const VolumeBox& box) {
  ResolvedScene rs = resolve_scene(parse_scene(j.at("scene")), box);
  rs.step = j.at("step");  // interactive frames take a longer step than the scene's
  return rs;
}

render::PixelRect rect_of(const nlohmann::json& j) {
  const auto& r = j.at("rect");
  return render::PixelRect{r[0], r[1], r[2], r[3]};
}

}  // namespace

struct MpiRenderer::Impl {
  explicit Impl(std::unique_ptr<render::Renderer> local) : local(std::move(local)), renderer(*this->local), icet(MPI_COMM_WORLD, 0) {}
  std::unique_ptr<render::Renderer> local;
  render::Renderer& renderer;
  IceTCompositor icet;
  int64_t next_id = 1;
};

class MpiRenderer::Resident : public render::ResidentVolume {
 public:
  Resident(MpiRenderer& owner, int64_t id, std::shared_ptr<const Volume> whole, VolumeMacrocells cells, BrickSet b)
      : ResidentVolume(std::move(whole), std::move(cells)), owner_(owner), id_(id), bricks(std::move(b)) {}
  ~Resident() override { owner_.forget(id_); }
  size_t resident_bytes() const override { return bricks.brick->volume().byte_size(); }
  bool drop_host_voxels() override {  // the bricks are the copy; the whole volume need not stay
    if (!has_both_grids() || !volume_->has_voxels()) return false;
    volume_->drop_voxels();
    return true;
  }
  int64_t id() const { return id_; }

  MpiRenderer& owner_;
  int64_t id_;
  BrickSet bricks;
};

MpiRenderer::MpiRenderer(int ranks, std::unique_ptr<render::Renderer> local)
    : ranks_(ranks), impl_(std::make_unique<Impl>(std::move(local))) {
  // Every rank must draw with the same backend: the CPU and GL ray casters round a point's
  // position differently, so a face between their bricks could draw a point twice or never.
  int64_t cmd = kBackend, id = 0;
  std::string payload = impl_->renderer.backend();
  std::vector<int64_t> drops;
  broadcast(cmd, id, payload, drops);
}

const char* MpiRenderer::backend() const { return impl_->renderer.backend(); }

MpiRenderer::~MpiRenderer() {
  int64_t cmd = kQuit, id = 0;
  std::string payload;
  std::vector<int64_t> drops;
  broadcast(cmd, id, payload, drops);
}

std::string MpiRenderer::description() const {
  return impl_->renderer.description() + " per rank, " + std::to_string(ranks_) + " ranks (MPI, IceT)";
}

void MpiRenderer::forget(int64_t id) {
  std::lock_guard lock(forgotten_m_);
  forgotten_.push_back(id);
}

std::vector<int64_t> MpiRenderer::take_forgotten() {
  std::lock_guard lock(forgotten_m_);
  return std::exchange(forgotten_, {});
}

std::unique_ptr<render::ResidentVolume> MpiRenderer::make_resident(std::shared_ptr<const Volume> volume,
                                                                   VolumeMacrocells cells) {
  if (volume->source_path.empty())
    throw std::invalid_argument("distributed rendering reads each rank's brick from the volume's file; this volume has none");
  // Ghosts for the widest filter, shading and an interactive frame's doubled step; a scene
  // that needs more re-reads the bricks (render).
  const int ghost = ghost_voxels(true, true) + 2;
  // What would fail on a rank fails here first, before any rank is asked (a failure after the
  // broadcast ends the job): a file whose regions cannot be read (TIFF stacks), one changed
  // since the server read it, a volume with fewer cells than ranks.
  {
    LoadOptions one;
    one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
    const Volume head = load_volume(volume->source_path, one);
    if (head.source_dims != volume->dims())
      throw std::runtime_error(volume->source_path + ": the file changed since it was read (its dims differ)");
    kd_split({head.source_dims[0], head.source_dims[1], head.source_dims[2]}, ranks_, ghost);
  }
  int64_t cmd = kLoad, id = impl_->next_id++;
  std::string payload =
      nlohmann::json{{"path", volume->source_path}, {"lo", volume->min_value}, {"hi", volume->max_value}, {"ghost", ghost}}
          .dump();
  std::vector<int64_t> drops = take_forgotten();
  broadcast(cmd, id, payload, drops);
  BrickSet b;
  try {
    b = load_bricks(nlohmann::json::parse(payload), impl_->renderer);
  } catch (const std::exception& e) {
    abort_job(e.what());  // the other ranks are reading theirs: the job cannot go on without this one
  }
  return std::make_unique<Resident>(*this, id, std::move(volume), std::move(cells), std::move(b));
}

render::RenderResult MpiRenderer::render(const render::ResidentVolume& v, const ResolvedScene& s,
                                         const render::RenderRequest& req, render::RenderStats* stats) {
  auto* res = dynamic_cast<const Resident*>(&v);
  if (!res) throw std::invalid_argument("the MPI renderer draws its own volumes only");
  render::check_brick_scene(s);  // before any rank is asked
  const render::PixelRect rect = req.tile.value_or(render::PixelRect{0, 0, s.scene.width, s.scene.height});
  render::check_rect(rect, s.scene.width, s.scene.height);
  auto& bricks = const_cast<Resident*>(res)->bricks;
  const auto t0 = std::chrono::steady_clock::now();
  const bool want_samples = req.output == render::RenderOutput::Float || req.sample_stats;
  try {
    if (const int need = brick_ghost(s); need > bricks.ghost) {  // a longer step than the bricks were read for
      // With headroom: a differential step grows as the camera backs away, and a re-read on
      // every frame of a slow zoom-out would cost more than the wider ghosts.
      const int ghost = need + std::max(4, need / 2);
      int64_t cmd = kLoad, id = res->id();
      std::string payload = nlohmann::json{{"path", res->volume().source_path}, {"lo", bricks.box.min_value},
                                            {"hi", bricks.box.max_value}, {"ghost", ghost}}
                                .dump();
      std::vector<int64_t> drops = take_forgotten();
      broadcast(cmd, id, payload, drops);
      bricks = load_bricks(nlohmann::json::parse(payload), impl_->renderer);
    }
    int64_t cmd = kRender, id = res->id();
    std::string payload = nlohmann::json{{"scene", scene_to_json(s.scene)}, {"step", s.step},
                                         {"rect", {rect.x, rect.y, rect.w, rect.h}}, {"samples", want_samples}}
                              .dump();
    std::vector<int64_t> drops = take_forgotten();
    broadcast(cmd, id, payload, drops);
    Composited c = render_composite(bricks, s, rect, want_samples, impl_->renderer, impl_->icet);
    Image img = finish_composite(c.rgba, rect.w, rect.h, s.scene.background);
    render::RenderResult out;
    out.rect = rect;
    if (stats) {
      *stats = c.stats;
      stats->variant = c.stats.variant + "+" + std::to_string(ranks_) + "ranks";
      stats->render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      stats->samples_total = stats->samples_max = 0;
      stats->rays_hit = 0;
      for (float n : c.samples) {
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
      img.samples = std::move(c.samples);
      out.image = std::move(img);
    }
    return out;
  } catch (const std::exception& e) {
    abort_job(e.what());  // the workers wait in a collective: no frame can be finished without this rank
  }
}

Image MpiRenderer::render_bare(const render::ResidentVolume&, const ResolvedScene&, render::GpuPath, const Image&,
                               render::RenderStats*) {
  throw std::invalid_argument("the bare sampling loop is not measured under MPI");
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
    IceTCompositor icet(MPI_COMM_WORLD, 0);
    std::map<int64_t, BrickSet> volumes;
    for (;;) {
      int64_t cmd = 0, id = 0;
      std::string payload;
      std::vector<int64_t> drops;
      broadcast(cmd, id, payload, drops);
      for (int64_t d : drops) volumes.erase(d);
      if (cmd == kQuit) return;
      if (cmd == kBackend) {
        if (payload != renderer.backend())
          throw std::runtime_error("this rank renders with the " + std::string(renderer.backend()) +
                                   " backend and rank 0 with " + payload +
                                   ": every rank needs the same (pass --backend gl or --backend cpu)");
        continue;
      }
      const nlohmann::json j = nlohmann::json::parse(payload);
      if (cmd == kLoad) {
        volumes[id] = load_bricks(j, renderer);
      } else if (cmd == kRender) {
        BrickSet& b = volumes.at(id);
        render_composite(b, scene_of(j, b.box), rect_of(j), j.at("samples"), renderer, icet);
      } else {
        throw std::runtime_error("unknown command " + std::to_string(cmd) + " from rank 0");
      }
    }
  } catch (const std::exception& e) {
    abort_job(e.what());
  }
}

}  // namespace peakcast::dist
