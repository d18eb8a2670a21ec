// `mpirun -np N peakcast serve` (docs/distributed.md): rank 0 runs the server, whose
// render thread draws through MpiRenderer; ranks 1..N-1 run serve_worker. For every volume the
// server makes resident, each rank reads its k-d brick of the volume's file; for every frame,
// rank 0 broadcasts the scene, every rank renders its brick (CPU backend or GL), IceT composites
// the layers in visibility order and rank 0 gets the image, which the server encodes and sends
// as it would its own. Rank 0's MPI calls come from the render thread and the volume loader,
// one command at a time (distributed/coordinator.h).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace peakcast::distributed {

class Coordinator;

class MpiRenderer : public render::Renderer {
 public:
  // MPI is initialised; this is rank 0, sending through `coord` (shared with the server's
  // volume loader). `local`: what draws this rank's brick (the CPU backend or the GL ray
  // caster, whose context is current on the calling thread).
  MpiRenderer(std::shared_ptr<Coordinator> coord, std::unique_ptr<render::Renderer> local);
  ~MpiRenderer() override;               // tells the workers to stop
  const char* backend() const override;  // the local renderer's
  std::string description() const override;
  // A volume from Coordinator::load (the server's): its bricks, read then, made resident. Any
  // other volume read from a file (the CLI, tests): every rank reads its brick of
  // volume->source_path now, and the whole volume's voxels on this rank may then go
  // (drop_host_voxels). Throws std::invalid_argument for a volume not read from a file.
  std::unique_ptr<render::ResidentVolume> make_resident(std::shared_ptr<const Volume> volume,
                                                        VolumeMacrocells cells = {}) override;
  // Refuses (std::invalid_argument, before any rank is asked) what bricks cannot draw; re-reads
  // every brick with wider ghosts when a scene needs them (a longer step).
  render::RenderResult render(const render::ResidentVolume& volume, const ResolvedScene& scene,
                              const render::RenderRequest& request, render::RenderStats* stats = nullptr) override;
  Image render_brick(const render::ResidentVolume&, const ResolvedScene&, const render::Brick&,
                     render::RenderStats* = nullptr, std::optional<render::PixelRect> = std::nullopt) override;
  int sample_cap(const render::VariantKey& key) const override;
  int ranks() const { return ranks_; }

  class Resident;

 private:
  int ranks_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Ranks 1..N-1 of `mpirun peakcast serve`: load, render and composite what rank 0 asks, until
// it stops. Errors end the job (MPI_Abort) with this rank's reason.
void serve_worker(render::Renderer& renderer);

}  // namespace peakcast::distributed
