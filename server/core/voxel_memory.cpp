#include "core/voxel_memory.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>

namespace peakcast {
namespace {

// Below this an array comes from the heap (small volumes, test bricks of a few KiB): mapping
// costs a system call and a page each way.
constexpr size_t kMapFrom = size_t(256) << 10;

// Large voxel arrays in 2 MiB pages where the kernel offers them on request (Debian's default
// THP mode is "madvise"): a brick read by an out-of-core still fills tens of MiB of fresh memory,
// and in 4 KiB pages most of that time went to page faults (perf: a third of the CPU in the
// kernel). Only whole huge pages inside the array are advised.
void advise_huge_pages(void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  if (bytes < 4 * kHuge) return;
  const uintptr_t lo = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t hi = (reinterpret_cast<uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);  // advice: a refusal is harmless
}

}  // namespace

void VoxelFree::operator()(void* p) const noexcept {
  if (!p) return;
  if (mapped)
    munmap(p, mapped);
  else
    std::free(p);
}

VoxelArray<unsigned char> allocate_voxel_bytes(size_t bytes) {
  if (bytes < kMapFrom) {
    void* p = std::malloc(bytes ? bytes : 1);
    if (!p) throw std::bad_alloc();
    return VoxelArray<unsigned char>(static_cast<unsigned char*>(p), VoxelFree{0});
  }
  void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  advise_huge_pages(p, bytes);
  return VoxelArray<unsigned char>(static_cast<unsigned char*>(p), VoxelFree{bytes});
}

}  // namespace peakcast
