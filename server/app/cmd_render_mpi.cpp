// `mpirun -np N peakcast render SCENE -o out.png [--stats s.json]` (docs/distributed.md):
// the volume cut into N k-d bricks with ghosts, each rank reading only its brick (a region of
// the file), rendering it on the whole volume's lattice (CpuRenderer::render_brick), IceT
// compositing the ranks' layers in visibility order, rank 0 writing the image and the stats.
// Any rank's error ends the whole job (MPI_Abort) with the rank and the reason, never a hang.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/cmd_render_mpi.h"
#include "app/scene_file.h"
#include "core/parallel.h"
#include "core/volume_io.h"
#include "cpu/cpu_renderer.h"
#include "distributed/brick_frame.h"
#include "distributed/icet_compositor.h"
#include "distributed/kd_split.h"
#include "distributed/coordinator.h"
#include "distributed/mpi_renderer.h"
#include "distributed/opacity_chain.h"
#include "encode/png.h"
#include "render/backend.h"

namespace peakcast::app {
namespace {

double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Peak resident memory of this process (VmHWM), MiB; 0 where /proc is not there.
double peak_rss_mib() {
  std::ifstream in("/proc/self/status");
  std::string key;
  while (in >> key) {
    if (key == "VmHWM:") {
      double kib = 0;
      in >> kib;
      return kib / 1024.0;
    }
    std::getline(in, key);
  }
  return 0.0;
}

// The node's cores shared among its ranks (one GPU or core set per rank, docs/distributed.md).
int rank_threads() {
  int local_ranks = 1;
  if (const char* l = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE")) local_ranks = std::max(1, std::atoi(l));
  return std::max(1, hardware_threads() / local_ranks);
}

// This rank's renderer: the CPU backend with the rank's share of the node's cores, or the GL ray
// caster on the rank's own GPU (EglContext's "auto" starts at the device of the local rank).
struct RankRenderer {
  render::RenderBackend gl;  // the GL ray caster with its context and shaders
  std::unique_ptr<render::Renderer> cpu;
  render::Renderer& get() { return cpu ? *cpu : *gl.renderer; }
};

RankRenderer open_rank_renderer(const std::string& backend, const std::string& egl_device = "") {
  RankRenderer r;
  const render::Backend want = render::requested_backend(backend);
  if (want != render::Backend::Cpu) {
    r.gl = render::open_backend(want, egl_device);
    if (r.gl.backend == render::Backend::Gl) return r;
    r.gl = render::RenderBackend{};  // auto chose the CPU backend (a software rasteriser only)
  }
  r.cpu = std::make_unique<cpu::CpuRenderer>(rank_threads());
  return r;
}

struct RankFigures {  // gathered on rank 0, one row per rank
  double lo[3], hi[3], read_lo[3], read_hi[3];
  double voxels_read, load_ms, render_ms, composite_ms, rss_mib, samples_mean;
};

// This rank's brick, read, and the scene resolved against the whole volume's box.
struct RankBrick {
  distributed::Index3 dims{};  // the whole volume's
  int ghost = 0;
  double load_ms = 0;
  distributed::BrickRead read;
  ResolvedScene scene;
};

// Reads the file's header, then this rank's brick with its ghosts; the whole volume's range,
// histogram and macrocell grids come reduced from the bricks.
RankBrick read_rank_brick(const ParsedSceneFile& parsed) {
  RankBrick b;
  // The file's header: every rank reads one voxel of it, which tells the whole volume's box.
  const Volume head = distributed::read_head(parsed.volume.string(), parsed.scene.time);
  if (const std::string why = time_refusal(parsed.scene.time, head.time_points); !why.empty()) throw SceneError(why);
  VolumeBox box{head.source_dims, head.spacing, head.origin, 0.0, 1.0, {}};
  b.dims = distributed::Index3{box.dims[0], box.dims[1], box.dims[2]};
  // Ghosts depend on the step, filter and shading, not on the value range.
  b.ghost = distributed::brick_ghost(resolve_scene(parsed.scene, box));

  // Every rank reads its brick; the whole volume's range, histogram and macrocell grids are
  // reduced from the bricks (distributed/brick_load.h).
  const auto t_load = std::chrono::steady_clock::now();
  distributed::BrickLoadRequest request;
  request.path = parsed.volume.string();
  request.time_point = parsed.scene.time;
  request.ghost = b.ghost;
  b.read = distributed::read_brick(request);
  if (b.read.failed) throw std::runtime_error(b.read.error);  // names the file (and the rank that failed)
  b.load_ms = ms_between(t_load, std::chrono::steady_clock::now());
  b.scene = resolve_scene(parsed.scene, b.read.box);
  return b;
}

// Every rank must draw with the same backend (auto may pick the GL one on a node with a GPU
// and the CPU one on another): the two round a point's position differently at brick faces.
void check_same_backend(render::Renderer& renderer) {
  int gl = std::string(renderer.backend()) == "gl", all_gl = 0, any_gl = 0;
  MPI_Allreduce(&gl, &all_gl, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&gl, &any_gl, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (all_gl != any_gl)
    throw std::invalid_argument(
        "the ranks chose different backends (gl on some, cpu on others): pass --backend gl or "
        "--backend cpu");
}

// This rank's row of figures, for rank 0 to gather.
RankFigures rank_figures(const distributed::Brick& mine, const Volume& brick, double load_ms,
                         const render::RenderStats& st, const distributed::CompositeTiming& timing) {
  RankFigures fig{};
  for (int k = 0; k < 3; ++k) {
    fig.lo[k] = double(mine.lo[k]);
    fig.hi[k] = double(mine.hi[k]);
    fig.read_lo[k] = double(mine.read_lo[k]);
    fig.read_hi[k] = double(mine.read_hi[k]);
  }
  fig.voxels_read = double(brick.voxel_count());
  fig.load_ms = load_ms;
  fig.render_ms = st.render_ms;
  fig.composite_ms = timing.ms;
  fig.rss_mib = peak_rss_mib();
  fig.samples_mean = st.samples_mean;
  return fig;
}

// What rank 0 reports of the whole job.
struct JobSummary {
  int ranks = 0, ghost = 0;
  double wall_ms = 0, render_max = 0, composite_max = 0;  // the maxima: the slowest rank's
  nlohmann::json per_rank = nlohmann::json::array();
};

// The slowest rank's render and composite times, and one row of the stats per rank.
void summarize_ranks(const std::vector<RankFigures>& all, size_t voxel_size, JobSummary& s) {
  for (int r = 0; r < s.ranks; ++r) {
    const RankFigures& f = all[size_t(r)];
    s.render_max = std::max(s.render_max, f.render_ms);
    s.composite_max = std::max(s.composite_max, f.composite_ms);
    auto ivec = [](const double* v) { return nlohmann::json::array({int64_t(v[0]), int64_t(v[1]), int64_t(v[2])}); };
    s.per_rank.push_back({{"rank", r},
                          {"brick", {{"lo", ivec(f.lo)}, {"hi", ivec(f.hi)}}},
                          {"read", {{"lo", ivec(f.read_lo)}, {"hi", ivec(f.read_hi)}}},
                          {"voxels", int64_t(f.voxels_read)},
                          {"voxel_bytes", int64_t(f.voxels_read) * int64_t(voxel_size)},
                          {"load_ms", f.load_ms},
                          {"render_ms", f.render_ms},
                          {"composite_ms", f.composite_ms},
                          {"peak_rss_mib", f.rss_mib},
                          {"samples_per_ray", f.samples_mean}});
  }
}

// Rank 0: the line on stdout and, with --stats, the stats file.
void report_job(const MpiRenderArgs& a, const JobSummary& s, const Image& img, render::Renderer& renderer,
                const std::string& variant, const distributed::Index3& dims) {
  std::printf(
      "wrote %s: %dx%d, %d ranks (k-d bricks, ghost %d), render %.1f ms (slowest rank), composite %.1f ms "
      "(IceT), %.0f ms in all, %s\n",
      a.out.c_str(), img.width, img.height, s.ranks, s.ghost, s.render_max, s.composite_max, s.wall_ms,
      renderer.description().c_str());
  if (!a.stats.empty()) {
    nlohmann::json j = {{"ranks", s.ranks},
                        {"ghost", s.ghost},
                        {"render_ms", s.render_max},
                        {"composite_ms", s.composite_max},
                        {"wall_ms", s.wall_ms},
                        {"variant", variant},
                        {"backend", renderer.backend()},
                        {"renderer", renderer.description()},
                        {"volume_dims", {dims[0], dims[1], dims[2]}},
                        {"per_rank", s.per_rank}};
    std::ofstream(a.stats) << j.dump(2) << "\n";
  }
}

int run(const MpiRenderArgs& a, int rank, int size) {
  const auto t_start = std::chrono::steady_clock::now();
  ParsedSceneFile parsed = parse_scene_file(a.scene);
  const RankBrick b = read_rank_brick(parsed);
  const distributed::BrickRead& read = b.read;
  const distributed::Brick& mine = read.mine;
  std::shared_ptr<Volume> brick = read.voxels;
  const VolumeBox& box = read.box;
  const ResolvedScene& scene = b.scene;

  // Fault injection for the tests (label mpi): this rank dies as a crashed process would.
  if (const char* kill = std::getenv("PEAKCAST_TEST_KILL_RANK"); kill && std::atoi(kill) == rank) std::raise(SIGKILL);

  RankRenderer rank_renderer = open_rank_renderer(a.backend);
  render::Renderer& renderer = rank_renderer.get();
  check_same_backend(renderer);
  auto resident = renderer.make_resident(brick, read.cells);
  const glm::dvec3 eye = (scene.camera.eye - box.origin) / box.spacing;
  const glm::dvec3 dir = glm::normalize((scene.camera.center - scene.camera.eye) / box.spacing);
  const std::vector<int> order = distributed::visibility_order(read.split, eye, dir, scene.camera.orthographic);
  render::Brick frame = distributed::frame_brick(mine, b.dims);
  // A ray texture's termination: the ranks draw in turn, front to back (distributed/opacity_chain.h).
  const size_t pixels = size_t(scene.scene.width) * size_t(scene.scene.height);
  if (scene.ray_texture) frame.front_opacity = distributed::receive_front_opacity(order, pixels);
  render::RenderStats st;
  const Image layer = renderer.render_brick(*resident, scene, frame, &st);
  if (scene.ray_texture) distributed::send_opacity_behind(order, frame.front_opacity.get(), layer);
  distributed::IceTCompositor compositor(MPI_COMM_WORLD, 0);
  distributed::CompositeTiming timing;
  const std::vector<float> composed = compositor.composite(layer.rgba, layer.width, layer.height, order, &timing);

  RankFigures mine_fig = rank_figures(mine, *brick, b.load_ms, st, timing);
  constexpr int kFields = int(sizeof(RankFigures) / sizeof(double));
  std::vector<RankFigures> all(rank == 0 ? size_t(size) : 0);
  MPI_Gather(&mine_fig, kFields, MPI_DOUBLE, all.data(), kFields, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  if (rank != 0) return 0;

  const Image img = distributed::finish_composite(composed, layer.width, layer.height, scene.scene.background);
  encode::write_png(img, a.out);
  JobSummary s;
  s.ranks = size;
  s.ghost = b.ghost;
  s.wall_ms = ms_between(t_start, std::chrono::steady_clock::now());
  summarize_ranks(all, voxel_bytes(brick->type()), s);
  report_job(a, s, img, renderer, st.variant, b.dims);
  return 0;
}

}  // namespace

int mpi_serve(const std::string& backend, const std::string& egl_device,
              const std::function<int(MpiServeHooks)>& serve) {
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int code = 0;
  try {
    if (provided < MPI_THREAD_SERIALIZED)
      throw std::runtime_error("this MPI cannot be called from the render thread (MPI_THREAD_SERIALIZED)");
    if (rank == 0) {
      auto coord = std::make_shared<distributed::Coordinator>(size);
      MpiServeHooks hooks;
      hooks.wrap = [coord](std::unique_ptr<render::Renderer> local) -> std::unique_ptr<render::Renderer> {
        // The server's own renderer draws rank 0's brick; on the CPU, with the rank's cores.
        if (std::string(local->backend()) == "cpu") local = std::make_unique<cpu::CpuRenderer>(rank_threads());
        return std::make_unique<distributed::MpiRenderer>(coord, std::move(local));
      };
      hooks.loader = [coord](const std::filesystem::path& path, const LoadOptions& options) {
        return coord->load(path, options);
      };
      hooks.ranks = size;
      code = serve(std::move(hooks));
    } else {
      RankRenderer r = open_rank_renderer(backend, egl_device);
      distributed::serve_worker(r.get());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peakcast: error on rank %d of %d: %s\n", rank, size, e.what());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, dynamic_cast<const std::invalid_argument*>(&e) ? kExitBadInput : kExitFailure);
  }
  MPI_Finalize();
  return code;
}

int mpi_render(const MpiRenderArgs& a) {
  MPI_Init(nullptr, nullptr);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int code = 0;
  try {
    code = run(a, rank, size);
  } catch (const std::exception& e) {
    // One rank's error ends every rank: the others may wait in a collective for it.
    std::fprintf(stderr, "peakcast: error on rank %d of %d: %s\n", rank, size, e.what());
    std::fflush(stderr);
    const bool bad_input = dynamic_cast<const VolumeError*>(&e) || dynamic_cast<const SceneError*>(&e) ||
                           dynamic_cast<const std::invalid_argument*>(&e);
    MPI_Abort(MPI_COMM_WORLD, bad_input ? kExitBadInput : kExitFailure);
  }
  MPI_Finalize();
  return code;
}

}  // namespace peakcast::app
