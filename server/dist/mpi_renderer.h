// `mpirun -np N peakcast serve` (issue 16, docs/distributed.md): rank 0 runs the server, whose
// render thread draws through MpiRenderer; ranks 1..N-1 run serve_worker. For every volume the
// server makes resident, each rank reads its k-d brick of the volume's file; for every frame,
// rank 0 broadcasts the scene, every rank renders its brick (CPU backend or GL), IceT composites
// the layers in visibility order and rank 0 gets the image, which the server encodes and sends
// as it would its own. All MPI calls come from rank 0's render thread (MPI_THREAD_SERIALIZED).
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace peakcast::dist {

class MpiRenderer : public render::Renderer {
 public:
  // MPI is initialised; this is rank 0 of `ranks`. `local`: what draws this rank's brick (the
  // CPU backend or the GL ray caster, whose context is current on the calling thread).
  MpiRenderer(int ranks, std::unique_ptr<render::Renderer> local);
  ~MpiRenderer() override;  // tells the workers to stop
  const char* backend() const override;  // the local renderer's
  std::string description() const override;
  // Every rank reads its brick of volume->source_path; the whole volume's voxels on this rank
  // may then go (drop_host_voxels). Throws std::invalid_argument for a volume not read from a
  // file (bricks are read from it).
  std::unique_ptr<render::ResidentVolume> make_resident(std::shared_ptr<const Volume> volume,
                                                        VolumeMacrocells cells = {}) override;
  // Refuses (std::invalid_argument, before any rank is asked) what bricks cannot draw; re-reads
  // every brick with wider ghosts when a scene needs them (a longer step).
  render::RenderResult render(const render::ResidentVolume& volume, const ResolvedScene& scene,
                              const render::RenderRequest& request, render::RenderStats* stats = nullptr) override;
  Image render_bare(const render::ResidentVolume&, const ResolvedScene&, render::GpuPath, const Image&,
                    render::RenderStats* = nullptr) override;
  Image render_brick(const render::ResidentVolume&, const ResolvedScene&, const render::Brick&,
                     render::RenderStats* = nullptr, std::optional<render::PixelRect> = std::nullopt) override;
  int sample_cap(const render::VariantKey& key) const override;
  int ranks() const { return ranks_; }

  class Resident;

 private:
  friend class Resident;
  void forget(int64_t id);  // a resident volume gone: its bricks go with the next command
  std::vector<int64_t> take_forgotten();

  int ranks_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::mutex forgotten_m_;
  std::vector<int64_t> forgotten_;
};

// Ranks 1..N-1 of `mpirun peakcast serve`: load, render and composite what rank 0 asks, until
// it stops. Errors end the job (MPI_Abort) with this rank's reason.
void serve_worker(render::Renderer& renderer);

}  // namespace peakcast::dist
