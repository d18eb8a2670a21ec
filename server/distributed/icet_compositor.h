// Sort-last compositing of the ranks' brick images with IceT (the engine ParaView uses), in
// visibility order. Each rank hands in its image as premultiplied RGBA floats (transparent where
// its brick leaves the ray empty); the display rank gets the composite "over" of all of them,
// front to back. Only this file and icet_compositor.cpp include IceT.
#pragma once

#include <memory>
#include <vector>

#include <mpi.h>

namespace peakcast::distributed {

struct CompositeTiming {
  double ms = 0.0;  // icetCompositeImage on this rank
};

class IceTCompositor {
 public:
  // comm: the ranks that render (MPI_COMM_WORLD in `mpirun peakcast render`). display: the rank
  // that receives the image.
  explicit IceTCompositor(MPI_Comm comm, int display = 0);
  ~IceTCompositor();
  IceTCompositor(const IceTCompositor&) = delete;
  IceTCompositor& operator=(const IceTCompositor&) = delete;

  // rgba: width*height*4 premultiplied floats, rows bottom-up as GL reads them. order: every
  // rank once, front to back. Returns the composite on the display rank, an empty vector on the
  // others.
  std::vector<float> composite(const std::vector<float>& rgba, int width, int height, const std::vector<int>& order,
                               CompositeTiming* timing = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peakcast::distributed
