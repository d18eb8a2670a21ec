// The CPU backend's sampler (server/cpu/sampler*.h): a SIMD run along a ray equals the scalar
// sampler at every point, for every voxel type and both filters, on every SIMD target this
// machine has, up to the volume's last voxel (whose +x neighbour read lands in the tail
// padding); the scalar sampler is GL's clamp-to-edge trilinear; float volumes are held once, in
// TF coordinates, and integer ones not copied at all.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

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

TEST(CpuSampler, TrilinearIsGlClampToEdge) {
  auto v = blobs(SourceType::U16, {5, 4, 3});
  cpu::CpuVolume cv(v);
  const cpu::VoxelGrid g = cv.grid(Filter::Trilinear);
  auto at = [&](int i, int j, int k) { return float(v->value(i, j, k) - v->min_value) / float(v->max_value - v->min_value); };
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

TEST(CpuSampler, IntegerVoxelsAreReadWhereTheyLieFloatOnesHeldOnce) {
  auto u8 = blobs(SourceType::U8, {16, 16, 16});
  cpu::CpuVolume a(u8, build_volume_macrocells(*u8));
  EXPECT_EQ(a.resident_bytes(), 0u);
  EXPECT_EQ(a.grid(Filter::Trilinear).data, u8->data());
  EXPECT_FALSE(a.drop_host_voxels()) << "integer voxels are the CPU copy: never dropped";
  EXPECT_TRUE(u8->has_voxels());

  auto f32 = blobs(SourceType::F32, {16, 16, 16});
  const float before = cpu::sample_field(cpu::CpuVolume(f32).grid(Filter::Trilinear), {3.5f, 7.25f, 9});
  cpu::CpuVolume b(f32, build_volume_macrocells(*f32));
  EXPECT_EQ(b.resident_bytes(), f32->byte_size());
  EXPECT_TRUE(b.drop_host_voxels()) << "the copy in TF coordinates is what the sampler reads";
  EXPECT_FALSE(f32->has_voxels());
  EXPECT_EQ(cpu::sample_field(b.grid(Filter::Trilinear), {3.5f, 7.25f, 9}), before);
}

}  // namespace
}  // namespace peakcast
