#include "distributed/icet_compositor.h"

#include <IceT.h>
#include <IceTMPI.h>

#include <chrono>
#include <stdexcept>
#include <string>

namespace peakcast::distributed {

struct IceTCompositor::Impl {
  IceTContext context = nullptr;
  int display = 0, rank = 0, size = 1;
};

IceTCompositor::IceTCompositor(MPI_Comm comm, int display) : impl_(std::make_unique<Impl>()) {
  MPI_Comm_rank(comm, &impl_->rank);
  MPI_Comm_size(comm, &impl_->size);
  if (display < 0 || display >= impl_->size) throw std::invalid_argument("display rank out of range");
  impl_->display = display;
  IceTCommunicator icet_comm = icetCreateMPICommunicator(comm);
  impl_->context = icetCreateContext(icet_comm);
  icetDestroyMPICommunicator(icet_comm);  // the context holds its own duplicate
  icetSetColorFormat(ICET_IMAGE_COLOR_RGBA_FLOAT);
  icetSetDepthFormat(ICET_IMAGE_DEPTH_NONE);
  icetCompositeMode(ICET_COMPOSITE_MODE_BLEND);
  icetStrategy(ICET_STRATEGY_SEQUENTIAL);                      // one tile: the single-image strategy does the work
  icetSingleImageStrategy(ICET_SINGLE_IMAGE_STRATEGY_RADIXK);  // as ParaView
  icetEnable(ICET_ORDERED_COMPOSITE);
  icetDisable(ICET_CORRECT_COLORED_BACKGROUND);  // the background goes under the result afterwards
}

IceTCompositor::~IceTCompositor() {
  if (impl_->context) icetDestroyContext(impl_->context);
}

std::vector<float> IceTCompositor::composite(const std::vector<float>& rgba, int width, int height,
                                             const std::vector<int>& order, CompositeTiming* timing) {
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4)
    throw std::invalid_argument("composite: the image is not width x height RGBA floats");
  std::vector<int> seen(size_t(impl_->size), 0);
  bool permutation = int(order.size()) == impl_->size;
  for (int r : order) permutation = permutation && r >= 0 && r < impl_->size && !seen[size_t(r)]++;
  if (!permutation) throw std::invalid_argument("composite: the order must name every rank once");
  icetSetContext(impl_->context);
  icetResetTiles();
  icetAddTile(0, 0, width, height, impl_->display);
  std::vector<IceTInt> ranks(order.begin(), order.end());
  icetCompositeOrder(ranks.data());
  const IceTDouble identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const IceTFloat background[4] = {0, 0, 0, 0};
  const IceTInt viewport[4] = {0, 0, width, height};
  const auto t0 = std::chrono::steady_clock::now();
  IceTImage image = icetCompositeImage(rgba.data(), nullptr, viewport, identity, identity, background);
  if (timing) timing->ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (impl_->rank != impl_->display) return {};
  if (icetImageIsNull(image) || icetImageGetWidth(image) != width || icetImageGetHeight(image) != height)
    throw std::runtime_error("IceT returned no image on the display rank");
  const IceTFloat* c = icetImageGetColorcf(image);
  return std::vector<float>(c, c + size_t(width) * size_t(height) * 4);
}

}  // namespace peakcast::distributed
