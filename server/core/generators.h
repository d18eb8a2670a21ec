// Procedural volumes for tests, demos and benchmarks (`peakcast make-volume`). Every voxel is
// a pure function of (kind, dims, seed, i, j, k), so output is deterministic whatever the
// thread count, and files are written slab by slab (memory: one slab).
#pragma once

#include <filesystem>
#include <string>

#include "core/volume.h"
#include "core/volume_writer.h"

namespace peakcast {

enum class GeneratorKind { MarschnerLobb, Blobs, Fire, Em, Sphere, Ramp, Vessels };

struct GeneratorSpec {
  GeneratorKind kind = GeneratorKind::Blobs;
  Dims dims{64, 64, 64};
  SourceType type = SourceType::U8;
  uint64_t seed = 1;
  glm::dvec3 spacing{1.0, 1.0, 1.0};
};

GeneratorKind parse_generator_kind(const std::string& name);  // throws std::invalid_argument
const char* to_string(GeneratorKind kind);
SourceType default_type(GeneratorKind kind);
Dims default_dims(GeneratorKind kind);

// Value in [0, 1] of voxel (i, j, k); quantised to the spec's type by the callers below.
double generator_value(const GeneratorSpec& spec, int64_t i, int64_t j, int64_t k);

Volume generate_volume(const GeneratorSpec& spec);
void generate_to_file(const GeneratorSpec& spec, const std::filesystem::path& out, WriteOptions options = {});

}  // namespace peakcast
