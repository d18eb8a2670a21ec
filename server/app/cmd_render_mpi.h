// `peakcast render` under mpirun (cmd_render_mpi.cpp, built where MPI and IceT are found;
// mpi_world_size_hint is in cmd_render.cpp, built always).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "app/commands.h"
#include "core/volume_io.h"
#include "render/renderer.h"

namespace peakcast::app {

struct MpiRenderArgs {
  std::string scene, out, stats, backend;
};

// The world size the launcher (mpirun, srun) announces in the environment; 1 outside one.
int mpi_world_size_hint();
// Every rank: initialises MPI, renders its brick, composites; rank 0 writes `out` (and the
// stats). Returns the exit code; a failing rank aborts the job with its reason.
int mpi_render(const MpiRenderArgs& a);

// mpirun peakcast serve: initialises MPI (serialized threads); rank 0 calls `serve` with the
// hooks below, the others render what it asks (distributed::serve_worker). An error on rank 0 before
// it serves ends the job.
using RendererWrap = std::function<std::unique_ptr<render::Renderer>(std::unique_ptr<render::Renderer>)>;
struct MpiServeHooks {
  RendererWrap wrap;    // puts distributed::MpiRenderer over the server's own renderer
  VolumeLoader loader;  // every rank reads its brick; rank 0 keeps no voxels (distributed::Coordinator)
  int ranks = 1;
};
// backend, egl_device: the server's options, for the other ranks' renderers.
int mpi_serve(const std::string& backend, const std::string& egl_device,
              const std::function<int(MpiServeHooks)>& serve);

}  // namespace peakcast::app
