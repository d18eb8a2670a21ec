// The command channel of `mpirun peakcast serve`: rank 0 broadcasts a command (load
// a volume's bricks, render a frame, stop) and every rank then takes part in the collectives
// that command implies. Rank 0 sends from two threads, the loader pool (volumes) and the render
// thread (frames): the Coordinator's lock holds one command and its collectives together (MPI
// is initialised MPI_THREAD_SERIALIZED).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/volume_io.h"
#include "distributed/brick_load.h"

namespace peakcast::distributed {

enum Command : int64_t { kLoad = 1, kRender = 2, kQuit = 3, kBackend = 4 };

struct CommandMessage {
  int64_t cmd = 0, id = 0;
  std::string payload;
  std::vector<int64_t> drops;  // volumes whose bricks the ranks free first
};

// Rank 0 fills `m`; the other ranks receive it.
void broadcast(CommandMessage& m);

// Ends the job with this rank's reason (the others may wait in a collective for it).
[[noreturn]] void abort_job(const char* what);

// Ghost voxels bricks are first read with: the widest filter, shading and an interactive
// frame's doubled step. A scene that needs more re-reads them (MpiRenderer::render).
int default_ghost();

class Coordinator {
 public:
  explicit Coordinator(int ranks) : ranks_(ranks) {}
  int ranks() const { return ranks_; }

  // Held from send() until the command's collectives are done.
  std::unique_lock<std::mutex> lock() { return std::unique_lock(m_); }
  // Broadcasts cmd with the volumes forgotten since the last command. The lock must be held.
  void send(const std::unique_lock<std::mutex>& held, int64_t cmd, int64_t id, std::string payload = {});
  int64_t new_id() { return next_id_++; }  // under the lock
  // Sends kLoad for `id` and reads this rank's brick with the others. A read any rank failed
  // throws VolumeError naming the file (every rank dropped it alike: the job goes on); any
  // other error ends the job (the ranks would be out of step). The lock must be held.
  BrickRead read_bricks(const std::unique_lock<std::mutex>& held, int64_t id, const BrickLoadRequest& request);
  // Refuses (VolumeError), before any rank is asked, a volume of `dims` that cannot be cut
  // into one brick per rank with `ghost` voxels.
  void check_split(const std::filesystem::path& path, const Dims& dims, int ghost) const;
  void forget(int64_t id);  // any thread: that volume's bricks go with the next command
  // After the last command (kQuit): send() and load() refuse from then on, so a load queued on
  // the loader pool during shutdown cannot wait for workers that are gone. The lock must be held.
  void close(const std::unique_lock<std::mutex>& held);

  // Loader pool (a VolumeLoader): every rank reads its brick and the whole volume's statistics
  // are reduced; rank 0 returns a volume without voxels (Volume::header_only) carrying them.
  // Refusals (a file bricks cannot read by region, non-finite voxels under Refuse, too many
  // voxels, fewer cells than ranks, a rank that cannot read its part, shutdown) throw
  // VolumeError before any rank is asked, or after the ranks agreed; the job goes on.
  LoadedVolume load(const std::filesystem::path& path, const LoadOptions& options);
  // Render thread: the brick load() read for `whole`, with its command id; nothing when `whole`
  // did not come from load().
  std::optional<std::pair<int64_t, BrickRead>> take_loaded(const std::unique_lock<std::mutex>& held,
                                                           const Volume* whole);

 private:
  void prune_locked();  // loaded volumes gone before they were drawn: forget their bricks
  const int ranks_;
  std::mutex m_;
  bool closed_ = false;  // under m_
  int64_t next_id_ = 1;
  std::mutex forgotten_m_;
  std::vector<int64_t> forgotten_;
  struct Loaded {
    std::weak_ptr<const Volume> whole;
    BrickRead read;
  };
  std::map<int64_t, Loaded> loaded_;  // under m_
};

}  // namespace peakcast::distributed
