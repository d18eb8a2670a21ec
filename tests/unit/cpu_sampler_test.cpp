// The CPU backend's sampler (server/cpu/sampler*.h): a SIMD run along a ray equals the scalar
// sampler at every point, for every voxel type and both filters, on every SIMD target this
// machine has, up to the volume's last voxel (whose +x neighbour read lands in the tail
// padding); the scalar sampler is GL's clamp-to-edge trilinear; integer volumes and float ones of a
// plain range are read where they lie, a float volume whose offset dwarfs its range is held in TF
// coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/generators.h"
#include "cpu/cpu_volume.h"
#include "cpu/sampler.h"

namespace peakcast {
namespace {

std::shared_ptr<Volume> blobs(SourceType type, Dims dims) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Blobs;
  s.dims = dims;
  s.type = type;
  return std::make_shared<Volume>(generate_volume(s));
}

// Random runs through (and beyond) the box in voxel coordinates.
void expect_runs_equal_points(const cpu::VoxelGrid& g, const char* what) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.5f, 1.5f), dir(-1.f, 1.f);
  for (int r = 0; r < 200; ++r) {
    cpu::SampleRun run;
    run.half = glm::vec3(0.f);
    run.inv_spacing = glm::vec3(1.f);
    run.o = glm::vec3(u(rng) * g.hi[0], u(rng) * g.hi[1], u(rng) * g.hi[2]);
    run.d = glm::vec3(dir(rng), dir(rng), dir(rng));
    run.t0 = 0.25f;
    run.B = 0.7f;
    run.A = r % 3 == 0 ? 0.01f : 0.f;
    run.first = r % 5;
    run.stride = 1 + r % 3;
    run.count = 1 + r % cpu::kMaxRun;
    float out[cpu::kMaxRun];
    cpu::sample_run(g, run, out);
    for (int k = 0; k < run.count; ++k) {
      const float j = float(run.first) + float(k) * float(run.stride);
      const float t = run.t0 + j * (run.B + run.A * j * 0.5f);
      const float want = cpu::sample_field(g, ((run.o + t * run.d) + run.half) * run.inv_spacing);
      ASSERT_EQ(out[k], want) << what << " run " << r << " point " << k;
    }
  }
}

TEST(CpuSampler, RunsEqualTheScalarSamplerForEveryTypeAndFilter) {
  std::printf("SIMD target: %s, %d lanes\n", cpu::simd_target(), cpu::sample_run_lanes());
  for (SourceType type : {SourceType::U8, SourceType::U16, SourceType::F32}) {
    auto v = blobs(type, {19, 13, 11});
    cpu::CpuVolume cv(v);
    for (Filter f : {Filter::Trilinear, Filter::Tricubic}) {
      cpu::VoxelGrid g = cv.grid(f);
      expect_runs_equal_points(g, to_string(type));
      g.simd_offsets = false;  // the path of volumes beyond 32-bit offsets
      expect_runs_equal_points(g, "scalar path");
    }
  }
}

// field_gradient's six samples at once (trilinear_cross) equal six trilinear lookups at p +- 1
// on each axis, bit for bit: inside, at and beyond the faces, on an axis of one voxel, at
// coordinates where p + 1 rounds (a large grid's far side), and at NaN.
template <class T>
void expect_cross_equals_points(const cpu::VoxelGrid& g, const char* what) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.3f, 1.3f);
  std::vector<glm::vec3> points;
  for (int r = 0; r < 400; ++r) points.emplace_back(u(rng) * g.hi[0], u(rng) * g.hi[1], u(rng) * g.hi[2]);
  points.emplace_back(0.f, 0.f, 0.f);
  points.emplace_back(g.hi[0], g.hi[1], g.hi[2]);
  points.emplace_back(g.hi[0] - 0.5f, 1.f, g.hi[2] + 3.f);
  points.emplace_back(NAN, 1.f, 1.f);
  points.emplace_back(1.f, -0.f, 1.f);
  points.emplace_back(std::nextafter(8.f, 0.f), std::nextafter(8.f, 0.f), std::nextafter(4.f, 0.f));  // p + 1 rounds
  for (const glm::vec3& p : points) {
    float got[6];
    cpu::trilinear_cross<T>(g, p, got);
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 2; ++k) {
        glm::vec3 e(0.f);
        e[a] = 1.f;
        const glm::vec3 q = k == 0 ? p + e : p - e;
        const float want = cpu::trilinear_typed<T>(g, q.x, q.y, q.z);
        const float have = got[2 * a + k];
        ASSERT_TRUE(have == want || (std::isnan(have) && std::isnan(want)))
            << what << " at " << p.x << " " << p.y << " " << p.z << " axis " << a << (k ? " -1" : " +1") << ": " << have
            << " vs " << want;
      }
  }
}

TEST(CpuSampler, GradientSamplesEqualSixTrilinearLookups) {
  for (Dims dims : {Dims{19, 13, 11}, Dims{1, 6, 3}, Dims{40, 2, 33}}) {
    auto u8 = blobs(SourceType::U8, dims), u16 = blobs(SourceType::U16, dims), f32 = blobs(SourceType::F32, dims);
    for (const auto& v : {u8, u16, f32}) {
      cpu::CpuVolume cv(v);
      const cpu::VoxelGrid g = cv.grid(Filter::Trilinear);
      switch (g.type) {
        case VoxelType::U8: expect_cross_equals_points<uint8_t>(g, "u8"); break;
        case VoxelType::U16: expect_cross_equals_points<uint16_t>(g, "u16"); break;
        case VoxelType::F32: expect_cross_equals_points<float>(g, "f32"); break;
      }
    }
  }
  // The check itself: a cross whose +x sample reads a voxel further fails it.
  auto v = blobs(SourceType::U8, {19, 13, 11});
  cpu::CpuVolume cv(v);
  const cpu::VoxelGrid g = cv.grid(Filter::Trilinear);
  const glm::vec3 p(4.25f, 5.5f, 6.75f);
  float got[6];
  cpu::trilinear_cross<uint8_t>(g, p, got);
  EXPECT_NE(got[0], cpu::trilinear_typed<uint8_t>(g, p.x + 2.f, p.y, p.z));
  EXPECT_EQ(got[0], cpu::trilinear_typed<uint8_t>(g, p.x + 1.f, p.y, p.z));
}

TEST(CpuSampler, TrilinearIsGlClampToEdge) {
  auto v = blobs(SourceType::U16, {5, 4, 3});
  cpu::CpuVolume cv(v);
  const cpu::VoxelGrid g = cv.grid(Filter::Trilinear);
  auto at = [&](int i, int j, int k) {
    return float(v->value(i, j, k) - v->min_value) / float(v->max_value - v->min_value);
  };
  // Voxel centres are exact; beyond the box the edge voxel repeats.
  EXPECT_NEAR(cpu::sample_field(g, {2, 1, 1}), at(2, 1, 1), 1e-6);
  EXPECT_NEAR(cpu::sample_field(g, {-3, -1, -0.5f}), at(0, 0, 0), 1e-6);
  EXPECT_NEAR(cpu::sample_field(g, {4, 3, 2}), at(4, 3, 2), 1e-6);  // the last voxel
  EXPECT_NEAR(cpu::sample_field(g, {9, 8, 7}), at(4, 3, 2), 1e-6);
  EXPECT_NEAR(cpu::sample_field(g, {1.5f, 1, 1}), 0.5f * (at(1, 1, 1) + at(2, 1, 1)), 1e-6);
  EXPECT_EQ(cpu::sample_field(g, {NAN, 0, 0}), cpu::sample_field(g, {0, 0, 0}));
}

TEST(CpuSampler, AnAxisOfOneVoxelReadsThatVoxel) {
  for (SourceType type : {SourceType::U8, SourceType::F32}) {
    auto v = blobs(type, {1, 6, 1});
    cpu::CpuVolume cv(v);
    cpu::VoxelGrid g = cv.grid(Filter::Trilinear);
    cpu::SampleRun run;
    run.o = glm::vec3(0.f, 0.f, 0.f);
    run.d = glm::vec3(0.3f, 1.f, -0.2f);
    run.half = glm::vec3(0.f);
    run.inv_spacing = glm::vec3(1.f);
    run.count = 6;
    float out[cpu::kMaxRun];
    cpu::sample_run(g, run, out);
    for (int k = 0; k < 6; ++k) {
      const float want = float((v->value(0, k, 0) - v->min_value) / (v->max_value - v->min_value));
      EXPECT_NEAR(out[k], want, 1e-6) << to_string(type) << " " << k;
    }
  }
}

// The TF coordinate of a voxel, computed in double as the GL upload does.
double unit_of(const Volume& v, int64_t i, int64_t j, int64_t k) {
  return (v.value(i, j, k) - v.min_value) / (v.max_value - v.min_value);
}

TEST(CpuSampler, IntegerAndPlainFloatVoxelsAreReadWhereTheyLie) {
  for (SourceType type : {SourceType::U8, SourceType::F32}) {
    auto v = blobs(type, {16, 16, 16});
    cpu::CpuVolume a(v, build_volume_macrocells(*v));
    EXPECT_EQ(a.resident_bytes(), 0u) << to_string(type);
    EXPECT_EQ(a.grid(Filter::Trilinear).data, v->data()) << to_string(type);
    EXPECT_FALSE(a.drop_host_voxels()) << "voxels read where they lie are the CPU copy: never dropped";
    EXPECT_TRUE(v->has_voxels());
    for (int k = 0; k < 16; k += 5)
      EXPECT_NEAR(cpu::sample_field(a.grid(Filter::Trilinear), {3, 7, float(k)}), unit_of(*v, 3, 7, k), 1e-6);
  }
}

// The TF coordinate between voxels, trilinear in double.
double unit_between(const Volume& v, glm::dvec3 x) {
  const glm::dvec3 f0 = glm::floor(x), f = x - f0;
  double sum = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int a = c & 1, b = (c >> 1) & 1, d = c >> 2;
    sum += (a ? f.x : 1 - f.x) * (b ? f.y : 1 - f.y) * (d ? f.z : 1 - f.z) *
           unit_of(v, int64_t(f0.x) + a, int64_t(f0.y) + b, int64_t(f0.z) + d);
  }
  return sum;
}

// A float volume whose values sit far from 0 for their range (1e4 + [0, 1]): mapped per sample in
// float, the cancellation would cost ~1e-3 of the TF range. It is held in TF coordinates instead.
TEST(CpuSampler, FloatVoxelsFarFromZeroAreHeldInTfCoordinates) {
  auto v = blobs(SourceType::F32, {16, 16, 16});
  float* f = reinterpret_cast<float*>(v->data());
  for (int64_t i = 0; i < v->voxel_count(); ++i) f[i] = 1e4f + f[i] / float(v->max_value);
  v->finalize_statistics();
  cpu::CpuVolume b(v, build_volume_macrocells(*v));
  EXPECT_EQ(b.resident_bytes(), v->byte_size());
  EXPECT_NE(b.grid(Filter::Trilinear).data, v->data());
  double worst = 0.0;
  for (int k = 0; k < 15; ++k)
    worst = std::max(worst, std::abs(cpu::sample_field(b.grid(Filter::Trilinear), {3.3f, 7.6f, k + 0.45f}) -
                                     unit_between(*v, {3.3f, 7.6f, k + 0.45f})));
  EXPECT_LT(worst, 2e-6) << "the copy keeps the TF coordinate to float precision";
  const double span = v->max_value - v->min_value;
  EXPECT_FALSE(cpu::CpuVolume::floats_in_place(*v, 1.0 / span, -v->min_value / span));
  const cpu::VoxelGrid in_place =
      cpu::make_voxel_grid(*v, v->data(), VoxelType::F32, float(1.0 / span), float(-v->min_value / span), false);
  double in_place_worst = 0.0;
  for (int k = 0; k < 15; ++k)
    in_place_worst = std::max(in_place_worst, std::abs(cpu::sample_field(in_place, {3.3f, 7.6f, k + 0.45f}) -
                                                       unit_between(*v, {3.3f, 7.6f, k + 0.45f})));
  EXPECT_GT(in_place_worst, 1e-4) << "why the copy: mapped in float, the TF coordinate would be this far off";
  const float before = cpu::sample_field(b.grid(Filter::Trilinear), {3.5f, 7.25f, 9});
  EXPECT_TRUE(b.drop_host_voxels()) << "the copy in TF coordinates is what the sampler reads";
  EXPECT_FALSE(v->has_voxels());
  EXPECT_EQ(cpu::sample_field(b.grid(Filter::Trilinear), {3.5f, 7.25f, 9}), before);
}

}  // namespace
}  // namespace peakcast
