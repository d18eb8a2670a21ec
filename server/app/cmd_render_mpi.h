// `peakcast render` under mpirun (cmd_render_mpi.cpp, built where MPI and IceT are found;
// mpi_world_size_hint is in cmd_render.cpp, built always).
#pragma once

#include <string>

#include "app/commands.h"

namespace peakcast::app {

struct MpiRenderArgs {
  std::string scene, out, stats, backend;
};

// The world size the launcher (mpirun, srun) announces in the environment; 1 outside one.
int mpi_world_size_hint();
// Every rank: initialises MPI, renders its brick, composites; rank 0 writes `out` (and the
// stats). Returns the exit code; a failing rank aborts the job with its reason.
int mpi_render(const MpiRenderArgs& a);

}  // namespace peakcast::app
