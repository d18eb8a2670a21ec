#include "distributed/coordinator.h"

#include <mpi.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace peakcast::distributed {

void broadcast(CommandMessage& m) {
  int64_t head[4] = {m.cmd, m.id, int64_t(m.payload.size()), int64_t(m.drops.size())};
  MPI_Bcast(head, 4, MPI_INT64_T, 0, MPI_COMM_WORLD);
  m.cmd = head[0];
  m.id = head[1];
  m.payload.resize(size_t(head[2]));
  m.drops.resize(size_t(head[3]));
  if (!m.payload.empty()) MPI_Bcast(m.payload.data(), int(m.payload.size()), MPI_CHAR, 0, MPI_COMM_WORLD);
  if (!m.drops.empty()) MPI_Bcast(m.drops.data(), int(m.drops.size()), MPI_INT64_T, 0, MPI_COMM_WORLD);
}

void abort_job(const char* what) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  std::fprintf(stderr, "peakcast: error on rank %d of %d: %s\n", rank, size, what);
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort();
}

int default_ghost() { return ghost_voxels(true, true) + 2; }

void Coordinator::send(const std::unique_lock<std::mutex>& held, int64_t cmd, int64_t id, std::string payload) {
  if (!held.owns_lock() || held.mutex() != &m_) throw std::logic_error("Coordinator::send without the lock");
  if (closed_) throw std::runtime_error("the distributed renderer has stopped (the workers are gone)");
  prune_locked();  // volumes loaded but dropped before they were drawn (a budget refusal)
  CommandMessage m{cmd, id, std::move(payload), {}};
  {
    std::lock_guard lock(forgotten_m_);
    m.drops = std::exchange(forgotten_, {});
  }
  broadcast(m);
}

void Coordinator::close(const std::unique_lock<std::mutex>& held) {
  if (!held.owns_lock() || held.mutex() != &m_) throw std::logic_error("Coordinator::close without the lock");
  closed_ = true;
  loaded_.clear();
}

void Coordinator::forget(int64_t id) {
  std::lock_guard lock(forgotten_m_);
  forgotten_.push_back(id);
}

void Coordinator::prune_locked() {
  for (auto it = loaded_.begin(); it != loaded_.end();) {
    if (it->second.whole.expired()) {
      forget(it->first);
      it = loaded_.erase(it);
    } else {
      ++it;
    }
  }
}

BrickRead Coordinator::read_bricks(const std::unique_lock<std::mutex>& held, int64_t id, const BrickLoadRequest& req) {
  send(held, kLoad, id, req.to_json().dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  BrickRead b;
  try {
    b = read_brick(req);
  } catch (const std::exception& e) {
    abort_job(e.what());  // not a read error (those the ranks agree on): the ranks are out of step
  }
  if (b.failed) throw VolumeError(req.path, "cannot be read as bricks: " + b.error);
  return b;
}

void Coordinator::check_split(const std::filesystem::path& path, const Dims& dims, int ghost) const {
  try {
    kd_split({dims[0], dims[1], dims[2]}, ranks_, ghost);
  } catch (const std::invalid_argument& e) {
    throw VolumeError(path, e.what());
  }
}

LoadedVolume Coordinator::load(const std::filesystem::path& path, const LoadOptions& options) {
  // What would fail on a rank fails here first, before any rank is asked (a failure after the
  // broadcast ends the job): a file whose regions cannot be read (TIFF stacks), too many voxels,
  // fewer cells than ranks.
  const Volume head = read_head(path.string(), options.time_point);  // refuses a time point not there
  const Dims dims = head.source_dims;
  if (dims[0] * dims[1] * dims[2] > options.max_voxels)
    throw VolumeError(path, std::to_string(dims[0] * dims[1] * dims[2]) + " voxels exceeds the limit of " +
                                std::to_string(options.max_voxels));
  BrickLoadRequest req;
  req.path = path.string();
  req.time_point = options.time_point;
  req.ghost = default_ghost();
  req.refuse_nonfinite = options.nonfinite == NonFinitePolicy::Refuse;
  check_split(path, dims, req.ghost);
  auto held = lock();
  if (closed_) throw VolumeError(path, "the server is shutting down");
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t id = new_id();
  BrickRead b = read_bricks(held, id, req);
  if (b.refused)  // every rank knows and kept nothing
    throw VolumeError(path, std::to_string(b.nonfinite) + " NaN/Inf voxels (policy: refuse)");
  struct ForgetUnlessKept {  // the workers hold bricks under `id` from here on
    Coordinator& c;
    int64_t id;
    bool kept = false;
    ~ForgetUnlessKept() {
      if (!kept) c.forget(id);
    }
  } guard{*this, id};
  VolumeHeader h;
  h.dims = dims;
  h.spacing = head.spacing;
  h.origin = head.origin;
  h.unit = head.unit;
  h.source = head.source_type();
  h.time_point = head.time_point;
  h.time_points = head.time_points;
  auto whole = std::make_shared<Volume>(Volume::header_only(h));
  whole->min_value = b.box.min_value;
  whole->max_value = b.box.max_value;
  whole->histogram = std::move(b.histogram);
  whole->border_histogram = std::move(b.border_histogram);
  whole->nonfinite_replaced = b.nonfinite;
  whole->name = head.name;
  whole->source_path = head.source_path;
  whole->load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  whole->statistics_ms = b.statistics_ms;
  const int64_t bytes = b.max_brick_bytes;
  loaded_[id] = Loaded{whole, std::move(b)};
  guard.kept = true;
  return LoadedVolume{whole, bytes};
}

std::optional<std::pair<int64_t, BrickRead>> Coordinator::take_loaded(const std::unique_lock<std::mutex>& held,
                                                                      const Volume* whole) {
  if (!held.owns_lock() || held.mutex() != &m_) throw std::logic_error("Coordinator::take_loaded without the lock");
  prune_locked();
  for (auto it = loaded_.begin(); it != loaded_.end(); ++it)
    if (auto w = it->second.whole.lock(); w.get() == whole) {
      std::pair<int64_t, BrickRead> out{it->first, std::move(it->second.read)};
      loaded_.erase(it);
      return out;
    }
  return std::nullopt;
}

}  // namespace peakcast::distributed
