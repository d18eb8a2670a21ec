// Arrays of voxels (a volume, a brick, the CPU backend's float copy) taken from the kernel
// rather than the heap once they are large: freeing one gives its pages back at once. From the
// heap, glibc keeps freed blocks under its mmap threshold (which rises to 32 MiB as blocks are
// freed) in the freeing thread's arena, where another thread's next brick cannot use them: an
// out-of-core still, which reads each brick on a fresh thread, held several bricks' worth past
// its budget (tests/gpu/outofcore_test.cpp, PeakMemoryStaysWithinTheBudget).
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>

namespace peakcast {

struct VoxelFree {
  size_t mapped = 0;  // bytes mapped; 0: from the heap
  void operator()(void* p) const noexcept;
};

template <class T>
using VoxelArray = std::unique_ptr<T[], VoxelFree>;

// `bytes` of uninitialised (heap) or zeroed (mapped) memory, in 2 MiB pages where the kernel
// offers them on request. Throws std::bad_alloc.
VoxelArray<unsigned char> allocate_voxel_bytes(size_t bytes);

template <class T>
VoxelArray<T> allocate_voxels(size_t count) {
  static_assert(std::is_trivial_v<T>, "voxels are plain values");
  if (count > size_t(-1) / sizeof(T)) throw std::bad_alloc();
  VoxelArray<unsigned char> b = allocate_voxel_bytes(count * sizeof(T));
  const VoxelFree f = b.get_deleter();
  return VoxelArray<T>(reinterpret_cast<T*>(b.release()), f);
}

}  // namespace peakcast
