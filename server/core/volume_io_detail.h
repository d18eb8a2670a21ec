// Shared by the format readers: where the voxel bytes are and how they are encoded.
#pragma once

#include <cstdint>
#include <filesystem>
#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "core/volume_io.h"

namespace peakcast::detail {

enum class Encoding { Raw, Gzip, Zlib };

struct PayloadSpec {
  std::vector<std::filesystem::path> files;  // concatenated in order
  Encoding encoding = Encoding::Raw;
  int64_t byte_skip = 0;  // in the first file (raw: -1 = the data is the last bytes)
};

// Counts the bytes a reader has placed and tells options.progress each new whole percent
// (LoadOptions::progress). Safe to add to from several threads.
class LoadProgress {
 public:
  LoadProgress(const LoadOptions& options, size_t total) : tell_(options.progress), total_(total) {}
  void add(size_t bytes);
  void done();  // 1, once

 private:
  void tell(int percent);
  const std::function<void(double)>& tell_;
  const size_t total_;
  std::atomic<size_t> bytes_{0};
  std::atomic<int> told_{-1};
  std::mutex m_;
};

// Checks dims and the voxel limit (overflow-safe); throws VolumeError naming `file`.
void check_header(const std::filesystem::path& file, const VolumeHeader& h, const LoadOptions& options);

// Allocates the volume and streams the payload into it (raw: straight in; compressed: through a
// 1 MiB buffer), then byte swaps, shifts signed types, applies the non-finite policy and
// computes the statistics.
Volume read_payload(const std::filesystem::path& header_file, const VolumeHeader& h, const PayloadSpec& payload,
                    const LoadOptions& options);

// Inflates a gzip or zlib file (from `skip`) in 1 MiB chunks into `sink`, which returns false to
// stop early. Concatenated gzip members are read as one stream. Throws VolumeError when corrupt.
void inflate_file(const std::filesystem::path& path, int64_t skip, Encoding enc,
                  const std::function<bool(const uint8_t*, size_t)>& sink);

// read_payload's path for options.region (volume_region.cpp): the region's rows only.
Volume read_payload_region(const std::filesystem::path& header_file, const VolumeHeader& h, const PayloadSpec& payload,
                           const LoadOptions& options);

// Time point options.time_point of a file holding `times` volumes of header h one after another
// (a 4-D NRRD with its time axis last, a raw sidecar's "times"): the box of z from t Z to
// (t + 1) Z of the file read as X x Y x (Z T) voxels, as any region is (raw: its rows; gzip:
// inflated to its last row), with options.region inside it, told which time point it is.
Volume read_time_point(const std::filesystem::path& path, const VolumeHeader& h, int64_t times,
                       const PayloadSpec& payload, const LoadOptions& options);

// Post-processing shared with the TIFF reader.
void finish_volume(const std::filesystem::path& file, Volume& v, bool big_endian, const LoadOptions& options);

Volume read_nrrd(const std::filesystem::path& path, const LoadOptions& options);
Volume read_metaimage(const std::filesystem::path& path, const LoadOptions& options);
Volume read_raw_json(const std::filesystem::path& path, const LoadOptions& options);
Volume read_tiff(const std::filesystem::path& path, const LoadOptions& options);

std::string trim(const std::string& s);
std::string lower(std::string s);
std::vector<std::string> split_ws(const std::string& s);
double parse_double(const std::filesystem::path& file, const std::string& field, const std::string& text);
int64_t parse_int(const std::filesystem::path& file, const std::string& field, const std::string& text);

}  // namespace peakcast::detail
