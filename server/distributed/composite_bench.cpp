// peakcast-composite-bench: IceT's compositing cost per frame on this machine, the part of a
// distributed frame that exists today. Every rank hands in a full-frame RGBA float
// layer (the worst case: no empty pixels for IceT to skip); rank 0 prints the median and p95 ms
// of icetCompositeImage over the frames, with MPI's wall time around it.
//   mpirun -np 4 peakcast-composite-bench [--size 1024] [--frames 30]
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "distributed/icet_compositor.h"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1, side = 1024, frames = 30;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--size"))
      side = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--frames"))
      frames = std::atoi(argv[i + 1]);
  }
  if (side < 16 || side > 8192 || frames < 1 || frames > 10000) {
    if (rank == 0) std::fprintf(stderr, "usage: peakcast-composite-bench [--size 16..8192] [--frames 1..10000]\n");
    MPI_Finalize();
    return 2;
  }
  std::vector<float> layer(size_t(side) * size_t(side) * 4);
  std::mt19937 rng(unsigned(rank) + 1);
  std::uniform_real_distribution<float> u(0.0f, 0.5f);
  for (size_t i = 0; i < layer.size(); i += 4) {
    const float a = u(rng);
    layer[i] = layer[i + 1] = layer[i + 2] = a * 0.5f;
    layer[i + 3] = a;
  }
  std::vector<int> order(static_cast<size_t>(size), 0);
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> icet_ms, wall_ms;
  {
    peakcast::distributed::IceTCompositor compositor(MPI_COMM_WORLD, 0);
    for (int f = -2; f < frames; ++f) {  // two warm-up frames
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = MPI_Wtime();
      peakcast::distributed::CompositeTiming timing;
      compositor.composite(layer, side, side, order, &timing);
      MPI_Barrier(MPI_COMM_WORLD);
      if (f >= 0) {
        icet_ms.push_back(timing.ms);
        wall_ms.push_back((MPI_Wtime() - t0) * 1000.0);
      }
    }
  }
  if (rank == 0) {
    auto pct = [](std::vector<double> v, double p) {
      std::sort(v.begin(), v.end());
      return v[std::min(v.size() - 1, size_t(p * double(v.size())))];
    };
    std::printf(
        "{\"ranks\": %d, \"size\": %d, \"frames\": %d, \"icet_ms_median\": %.2f, \"icet_ms_p95\": %.2f, "
        "\"wall_ms_median\": %.2f, \"layer_mib\": %.1f}\n",
        size, side, frames, pct(icet_ms, 0.5), pct(icet_ms, 0.95), pct(wall_ms, 0.5),
        double(layer.size() * sizeof(float)) / (1 << 20));
  }
  MPI_Finalize();
  return 0;
}
