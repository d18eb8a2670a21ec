// Helpers shared by the unit tests.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "core/volume.h"

namespace peakcast::test {

// A fresh directory per test under the build tree's temp area, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

std::filesystem::path data_dir();  // tests/data
// A small blobs volume with spacing (0.5, 1.25, 2) and origin (-3, 4.5, 0.25): the loader tests'.
Volume anisotropic_blobs(SourceType type, const Dims& dims);
uint64_t fnv1a(const void* data, size_t bytes);
void write_file(const std::filesystem::path& p, const std::string& bytes);
// Expects load_volume(file) to be refused with a one-line VolumeError containing `reason`.
void expect_refused(const std::filesystem::path& file, const std::string& reason);
// True when both volumes hold the same dims, spacing, origin, types and physical values.
::testing::AssertionResult same_volume(const Volume& a, const Volume& b);
// A float32 volume with value f(i, j, k) at each voxel, statistics computed.
std::shared_ptr<Volume> float_volume(const Dims& dims, const std::function<float(int64_t, int64_t, int64_t)>& f);

}  // namespace peakcast::test
