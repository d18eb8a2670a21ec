#include "unit/test_util.h"

#include <fstream>
#include <random>

#include "core/generators.h"
#include "core/volume_io.h"

namespace fs = std::filesystem;

namespace peakcast::test {

TempDir::TempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "peakcast";
  for (auto& c : name)
    if (c == '/') c = '_';
  path_ = fs::temp_directory_path() / ("peakcast_test_" + name + "_" + std::to_string(std::random_device{}()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

fs::path data_dir() { return PEAKCAST_TEST_DATA; }

uint64_t fnv1a(const void* data, size_t bytes) {
  uint64_t h = 1469598103934665603ull;
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

void write_file(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

::testing::AssertionResult same_volume(const Volume& a, const Volume& b) {
  if (a.dims() != b.dims()) return ::testing::AssertionFailure() << "dims differ";
  if (a.source_type() != b.source_type())
    return ::testing::AssertionFailure() << "types differ: " << to_string(a.source_type()) << " vs "
                                         << to_string(b.source_type());
  if (a.spacing != b.spacing) return ::testing::AssertionFailure() << "spacing differs";
  if (a.origin != b.origin) return ::testing::AssertionFailure() << "origin differs";
  const auto& d = a.dims();
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i)
        if (a.value(i, j, k) != b.value(i, j, k))
          return ::testing::AssertionFailure()
                 << "voxel (" << i << "," << j << "," << k << "): " << a.value(i, j, k) << " vs " << b.value(i, j, k);
  return ::testing::AssertionSuccess();
}

std::shared_ptr<Volume> float_volume(const Dims& dims, const std::function<float(int64_t, int64_t, int64_t)>& f) {
  VolumeHeader h;
  h.dims = dims;
  h.source = SourceType::F32;
  auto v = std::make_shared<Volume>(h);
  float* p = reinterpret_cast<float*>(v->data());
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) p[i + dims[0] * (j + dims[1] * k)] = f(i, j, k);
  v->finalize_statistics();
  return v;
}

Volume anisotropic_blobs(SourceType type, const Dims& dims) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Blobs;
  s.dims = dims;
  s.type = type;
  s.spacing = {0.5, 1.25, 2.0};
  Volume v = generate_volume(s);
  v.origin = {-3.0, 4.5, 0.25};
  return v;
}

void expect_refused(const fs::path& file, const std::string& reason) {
  try {
    load_volume(file);
    ADD_FAILURE() << file << " loaded, expected refusal: " << reason;
  } catch (const VolumeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(reason), std::string::npos) << "'" << what << "' lacks '" << reason << "'";
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

}  // namespace peakcast::test
