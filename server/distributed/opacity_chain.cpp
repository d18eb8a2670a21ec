#include "distributed/opacity_chain.h"

#include <mpi.h>

#include <algorithm>
#include <stdexcept>

#include "distributed/brick_frame.h"

namespace peakcast::distributed {
namespace {

constexpr int kOpacityTag = 0x5eca;

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// This rank's place in `order`.
size_t place(const std::vector<int>& order) {
  const auto it = std::find(order.begin(), order.end(), world_rank());
  if (it == order.end()) throw std::logic_error("the visibility order does not hold this rank");
  return size_t(it - order.begin());
}

}  // namespace

std::shared_ptr<const std::vector<float>> receive_front_opacity(const std::vector<int>& order, size_t pixels) {
  const size_t k = place(order);
  if (k == 0) return nullptr;
  auto front = std::make_shared<std::vector<float>>(pixels);
  MPI_Recv(front->data(), int(pixels), MPI_FLOAT, order[k - 1], kOpacityTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return front;
}

void send_opacity_behind(const std::vector<int>& order, const std::vector<float>* front, const Image& layer) {
  const size_t k = place(order);
  if (k + 1 >= order.size()) return;
  const std::vector<float> over = opacity_over(front, layer);
  MPI_Send(over.data(), int(over.size()), MPI_FLOAT, order[k + 1], kOpacityTag, MPI_COMM_WORLD);
}

}  // namespace peakcast::distributed
