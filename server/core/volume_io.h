// Loading volumes from files (docs/scenes.md). Every refusal is a VolumeError whose message
// names the file and the reason; nothing larger than the configured limit is ever allocated.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <utility>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/volume.h"

namespace peakcast {

class VolumeError : public std::runtime_error {
 public:
  VolumeError(const std::filesystem::path& file, const std::string& reason)
      : std::runtime_error(file.string() + ": " + reason) {}
};

// A region asked of a format read only whole (a TIFF stack).
class RegionNotReadable : public VolumeError {
 public:
  using VolumeError::VolumeError;
};

// What to do with NaN/Inf voxels in float volumes. Default: replace (NaN -> the finite minimum,
// +Inf -> finite maximum, -Inf -> finite minimum) and report the count, as ParaView users expect
// a volume with a few masked voxels to open; `refuse` for pipelines that want to stop instead.
// `keep` leaves them for a caller that knows better extremes: a brick of a distributed volume
// replaces them with the whole volume's (replace_nonfinite, which then computes the range and
// histogram: a volume read with `keep` and non-finite voxels has none until then).
enum class NonFinitePolicy { Replace, Refuse, Keep };

// A box of voxels [lo, hi) to read instead of the whole volume (a brick of a distributed
// render). The volume read holds hi - lo voxels per axis, its origin moved to voxel lo.
struct VoxelRegion {
  std::array<int64_t, 3> lo{}, hi{};
};

struct LoadOptions {
  int64_t max_voxels = int64_t(1) << 32;
  NonFinitePolicy nonfinite = NonFinitePolicy::Replace;
  // Raw data reads only the region's rows (pread); compressed data is inflated up to the
  // region's last row and the rest discarded. TIFF stacks are refused (whole-file format).
  std::optional<VoxelRegion> region;
  // Told the fraction of the voxel data read so far: non-decreasing, in steps of at least 1%, and
  // 1 once the volume is whole (statistics done). Called from the loading thread or its workers,
  // never two calls at once. Empty: nobody is told.
  std::function<void(double)> progress;
  // Chunked volumes (OME-Zarr, Neuroglancer precomputed; docs/chunked-volumes.md): the pyramid
  // level (0: full resolution) and, where the array has them, the time point and channel.
  int level = 0;
  int64_t time_point = 0;
  int64_t channel = 0;
  // Host memory for the voxels of a whole read (0: none, the voxel limit alone). A chunked volume
  // is read at its finest level from `level` on that fits; any other volume past it is refused
  // (docs/chunked-volumes.md).
  int64_t memory_budget_bytes = 0;
  // false: no range and histogram (a brick whose caller reduces the whole volume's; saves a pass).
  bool statistics = true;
  // Host memory for what a read decodes besides the volume's voxels (0: no limit): compressed
  // chunks being decoded at once (a chunk may be far larger than the box it fills). Charged
  // before decoding: fewer chunks at once, or refused when not even one fits beside the voxels.
  // The server sets it to --memory-budget-mib for every read, whichever level is read.
  int64_t decode_budget_bytes = 0;
  // true: the voxels must be in the file named (or, for raw voxels, the file its sidecar names
  // beside it): a header naming any other data file is refused before that file is looked at.
  // An upload is one file (session/upload_store.cpp).
  bool single_file = false;
  // Told each header once it is checked, before anything is allocated or decoded: a caller that
  // charges the decoded bytes elsewhere (an upload's budget) throws from here to refuse.
  std::function<void(const VolumeHeader&)> on_header;
};

// The spacings and origins a volume may have: every spacing within [kMinSpacing, kMaxSpacing] and
// every origin coordinate within +-kMaxOrigin (world units). Inside, a volume draws the same
// picture at any scale (measured from 1e-15 to 1e15; held by client-python/tests/test_results.py);
// past 1e18 world units, products of coordinates leave float's range on the GPU and pictures
// break. Returns "" within the bounds, else why, with the way out (another unit).
constexpr double kMinSpacing = 1e-12, kMaxSpacing = 1e12, kMaxOrigin = 1e15;
std::string spacing_refusal(const glm::dvec3& spacing, const glm::dvec3& origin);

// Format by name: .nrrd/.nhdr, .mhd/.mha, .json (sidecar) or .raw with a sidecar,
// .tif/.tiff (multi-page), a directory of numbered 2D TIFFs, or a chunked volume's directory
// (OME-Zarr, Neuroglancer precomputed: one level of it, options.level).
Volume load_volume(const std::filesystem::path& path, const LoadOptions& options = {});

// A volume as the server loads it (session/volume_store.h): the volume and the bytes of voxels
// this process will hold for it: its own, or for a distributed volume (which holds none here)
// the largest rank's brick, which the memory budget counts.
struct LoadedVolume {
  std::shared_ptr<Volume> volume;
  int64_t resident_bytes = 0;
};
using VolumeLoader = std::function<LoadedVolume(const std::filesystem::path&, const LoadOptions&)>;

// A float volume's finite extremes (lo > hi when no voxel is finite; other types: their range).
std::pair<float, float> finite_extremes(const Volume& v);
// A float volume's NaN/Inf voxels inside [lo, hi) (a brick's own box); 0 for other types.
int64_t count_nonfinite(const Volume& v, const Dims& lo, const Dims& hi);
// Replaces a float volume's NaN and -Inf voxels by lo and +Inf by hi, counts them in
// nonfinite_replaced and computes the statistics anew. Nothing for other types.
void replace_nonfinite(Volume& v, float lo, float hi);

// Resolves `requested` inside one of `roots` (defined in core/file_roots.cpp, beside the confinement) (the server's
// data directories). Relative paths are tried against each root in order; absolute ones must lie inside a root. Throws
// VolumeError on traversal outside every root or when nothing exists.
std::filesystem::path resolve_in_roots(const std::filesystem::path& requested,
                                       const std::vector<std::filesystem::path>& roots);

}  // namespace peakcast
