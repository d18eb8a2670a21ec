// Shared by the format readers: where the voxel bytes are and how they are encoded.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <filesystem>
#include <atomic>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/volume_io.h"

namespace peakcast::detail {

// Text: numbers in decimal separated by white space or commas (NRRD's txt/text/ascii); Hex: two
// hex digits a byte, white space between allowed.
enum class Encoding { Raw, Gzip, Zlib, Bzip2, Text, Hex };

// One data file's share of a payload, resolved by a reader that knows its format's rules (NRRD:
// data_parts.cpp): where the encoded data starts, what of the decoded data comes before the
// voxels, and exactly how many voxel bytes it holds (decoded data longer or shorter is refused).
struct DataPart {
  std::filesystem::path path;
  int64_t offset = 0;        // file bytes before the encoded data (an attached header, skipped lines)
  int64_t decoded_skip = 0;  // decoded bytes before the voxels; -1: the voxels are its last `bytes`
  int64_t bytes = 0;
};

struct PayloadSpec {
  std::vector<std::filesystem::path> files;  // concatenated in order
  Encoding encoding = Encoding::Raw;
  int64_t byte_skip = 0;  // in the first file (raw: -1 = the data is the last bytes)
  // When not empty: the files resolved one by one (files lists the same paths), each yielding
  // exactly its bytes; byte_skip is then unused.
  std::vector<DataPart> parts;
  SourceType text_type = SourceType::U8;  // Encoding::Text: what the numbers are converted to
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

// Refuses data files outside the server's roots, or other than the header's own for an upload
// (options.single_file), before any of them is looked at.
void check_payload_files(const std::filesystem::path& header_file, const PayloadSpec& payload,
                         const LoadOptions& options);

// Allocates the volume and streams the payload into it (raw: straight in; compressed: through a
// 1 MiB buffer), then byte swaps, shifts signed types, applies the non-finite policy and
// computes the statistics.
Volume read_payload(const std::filesystem::path& header_file, const VolumeHeader& h, const PayloadSpec& payload,
                    const LoadOptions& options);

// Inflates a gzip or zlib file (from `skip`) in 1 MiB chunks into `sink`, which returns false to
// stop early. Concatenated gzip members are read as one stream. Throws VolumeError when corrupt.
void inflate_file(const std::filesystem::path& path, int64_t skip, Encoding enc,
                  const std::function<bool(const uint8_t*, size_t)>& sink);

struct FileCloser {
  void operator()(FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<FILE, FileCloser>;
// Opens a data file for reading at `offset`; refuses one that is missing or cannot be opened.
File open_file(const std::filesystem::path& path, int64_t offset = 0);

// Reads up to `want` bytes of raw data at `skip` (-1: the file's last `want` bytes) into dst;
// returns the count read. `last`: the only or last file, refused when short.
size_t read_raw(const std::filesystem::path& path, int64_t skip, uint8_t* dst, size_t want, bool last,
                LoadProgress& progress);
// Inflates into dst up to `want` bytes; returns the count.
size_t read_compressed(const std::filesystem::path& path, int64_t skip, Encoding enc, uint8_t* dst, size_t want,
                       LoadProgress& progress);

// The decoded bytes of a file from `offset` in `enc` (Text: numbers as text_type's bytes, host
// byte order), 1 MiB at a time into `sink`, which returns false to stop. Throws VolumeError naming
// the file and where when the data is corrupt (data_decoders.cpp).
void decode_file(const std::filesystem::path& path, int64_t offset, Encoding enc, SourceType text_type,
                 const std::function<bool(const uint8_t*, size_t)>& sink);
// A part's voxel bytes (its decoded_skip dropped), 1 MiB at a time into `sink`; refuses decoded
// data shorter or longer than part.bytes with both sizes (not checked when sink stops early).
void stream_part(const DataPart& part, Encoding enc, SourceType text_type,
                 const std::function<bool(const uint8_t*, size_t)>& sink);

// payload.parts one after another into dst (raw: read in place; the rest decoded), exactly total bytes.
void read_parts(const PayloadSpec& payload, uint8_t* dst, size_t total, LoadProgress& progress);

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

// Where a header says its voxels are, resolved by resolve_parts (data_parts.cpp) by NRRD's rules
// (MetaImage's are the same with its HeaderSize always in the file's bytes).
struct DataLayout {
  std::vector<std::filesystem::path> files;
  Encoding encoding = Encoding::Raw;
  int64_t attached_offset = 0;  // attached data: the header's bytes before it
  int64_t line_skip = 0, byte_skip = 0;
  bool skip_in_file = false;                   // byte_skip counts file bytes whatever the encoding (MetaImage)
  std::string last_bytes = "'byte skip: -1'";  // how the header says "the data is the last bytes"
  int64_t total_bytes = 0;                     // every voxel of every time point
  int64_t files_expected = 0;                  // what the data file's subdimension asks for (0: not given)
};
std::vector<DataPart> resolve_parts(const std::filesystem::path& header, const DataLayout& layout);

// A printf-style data file pattern (NRRD's `data file`, MetaImage's ElementDataFile) for one
// index: exactly one %d or %i with flags "-+ 0#" and a width up to 32, %% a percent sign; file
// text never reaches a format function. Anything else is refused naming the pattern.
std::string format_name(const std::filesystem::path& file, const std::string& pattern, long long value);
// The names of a pattern over min..max by step (step != 0, at most a million files).
std::vector<std::filesystem::path> pattern_files(const std::filesystem::path& header, const std::string& pattern,
                                                 const std::string& min, const std::string& max,
                                                 const std::string& step);

// A MetaImage element type converted when read (metaimage_wide.cpp states the rule).
struct WideType {
  std::string name;  // as MetaImage spells it
  int bytes = 8;
  bool floating = false, is_signed = true;
};
std::optional<WideType> wide_metaimage_type(const std::string& element_type);
// Reads payload.parts as `w` values and converts them to the kept type the rule picks; a region is
// cut from the whole.
Volume read_converted(const std::filesystem::path& path, const VolumeHeader& h, const WideType& w,
                      const PayloadSpec& payload, const LoadOptions& options);

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
