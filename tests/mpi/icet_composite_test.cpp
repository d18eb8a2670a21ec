// Label mpi: IceT from Debian's ParaView packages composites the ranks' images in the
// visibility order given, as the "over" of premultiplied RGBA front to back. Run under mpirun with
// 2 and 3 ranks; every rank renders a different random layer (seeded by its rank), so rank 0 can
// compute the exact composite itself. Exit 0 when every order matches within float rounding.
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <vector>

#include "distributed/icet_compositor.h"

namespace {

constexpr int kWidth = 61, kHeight = 37;

std::vector<float> layer(int rank) {
  std::mt19937 rng(1000u + unsigned(rank));
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> px(size_t(kWidth) * kHeight * 4);
  for (size_t i = 0; i < px.size(); i += 4) {
    const float a = (i / 4) % 5 == size_t(rank) % 5 ? 0.0f : u(rng);  // some pixels empty
    for (int c = 0; c < 3; ++c) px[i + size_t(c)] = u(rng) * a;       // premultiplied
    px[i + 3] = a;
  }
  return px;
}

std::vector<float> over(const std::vector<int>& order) {
  std::vector<float> acc(size_t(kWidth) * kHeight * 4, 0.0f);
  for (int r : order) {
    const std::vector<float> l = layer(r);
    for (size_t i = 0; i < acc.size(); i += 4) {
      const float t = 1.0f - acc[i + 3];
      for (int c = 0; c < 4; ++c) acc[i + size_t(c)] += t * l[i + size_t(c)];
    }
  }
  return acc;
}

float max_diff(const std::vector<float>& a, const std::vector<float>& b) {
  float m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int failures = 0;
  {
    peakcast::distributed::IceTCompositor compositor(MPI_COMM_WORLD, 0);
    std::vector<int> identity(size_t(size), 0);
    std::iota(identity.begin(), identity.end(), 0);
    std::vector<int> reversed(identity.rbegin(), identity.rend());
    std::vector<int> rotated = identity;
    std::rotate(rotated.begin(), rotated.begin() + 1, rotated.end());
    const std::vector<float> mine = layer(rank);
    for (const auto& order : {identity, reversed, rotated}) {
      peakcast::distributed::CompositeTiming timing;
      const std::vector<float> got = compositor.composite(mine, kWidth, kHeight, order, &timing);
      if (rank != 0) continue;
      const float err = max_diff(got, over(order));
      // The same layers in the opposite order: how far a wrong order would be (the test's power).
      std::vector<int> back(order.rbegin(), order.rend());
      const float wrong = max_diff(over(order), over(back));
      std::printf("%d ranks, order", size);
      for (int r : order) std::printf(" %d", r);
      std::printf(": max |IceT - over| = %.2e (reversed order would be %.2f), %.2f ms\n", err, wrong, timing.ms);
      if (!(err <= 1e-5f) || !(wrong > 0.05f)) ++failures;
    }
  }
  MPI_Bcast(&failures, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  if (rank == 0) std::printf("%s\n", failures ? "FAILED" : "IceT composites in the given order");
  return failures ? 1 : 0;
}
