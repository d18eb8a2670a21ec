// NRRD's data rules (teem's format specification, "line skip", "byte skip", "data file"), which
// MetaImage's LIST and patterns follow too (HeaderSize in each file's bytes): every
// data file holds an equal share of the voxels; in each, `line skip` lines of the file are skipped
// first, then `byte skip` bytes, of the file for raw, txt and hex, of the decoded data for gzip
// and bzip2; -1 (the only negative allowed) puts the voxels at the end of the decoded data. A file
// whose data is longer or shorter than its share is refused with both sizes.
#include <cstdio>
#include <memory>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

// The offset just past `lines` newlines from `offset` in the file.
int64_t after_lines(const fs::path& path, int64_t offset, int64_t lines) {
  if (lines == 0) return offset;
  const File f = open_file(path, offset);
  for (int64_t seen = 0; seen < lines;) {
    const int c = std::fgetc(f.get());
    if (c == EOF)
      throw VolumeError(
          path, "line skip " + std::to_string(lines) + ": the file ends after " + std::to_string(seen) + " lines");
    ++offset;
    if (c == '\n') ++seen;
  }
  return offset;
}

}  // namespace

std::vector<DataPart> resolve_parts(const fs::path& header, const DataLayout& l) {
  if (l.byte_skip < -1)
    throw VolumeError(header, "byte skip " + std::to_string(l.byte_skip) +
                                  ": the only negative byte skip NRRD allows is -1 (the data is the last bytes)");
  if (l.line_skip < 0) throw VolumeError(header, "line skip must be >= 0");
  const int64_t files = int64_t(l.files.size());
  if (files == 0) throw VolumeError(header, "no data file");
  if (l.files_expected > 0 && l.files_expected != files)
    throw VolumeError(header, "the data files' subdimension asks for " + std::to_string(l.files_expected) +
                                  " files, the header names " + std::to_string(files));
  if (l.total_bytes % files != 0)
    throw VolumeError(header, std::to_string(files) + " data files cannot hold equal shares of " +
                                  std::to_string(l.total_bytes) + " bytes");
  const bool in_file = l.encoding == Encoding::Raw || l.encoding == Encoding::Text || l.encoding == Encoding::Hex;
  std::vector<DataPart> parts;
  for (size_t i = 0; i < l.files.size(); ++i) {
    DataPart p;
    p.path = l.files[i];
    p.bytes = l.total_bytes / files;
    std::error_code ec;
    if (!fs::is_regular_file(p.path, ec))
      throw VolumeError(p.path, "no such file (data of " + header.filename().string() + ")");
    p.offset = after_lines(p.path, i == 0 ? l.attached_offset : 0, l.line_skip);
    if ((in_file || l.skip_in_file) && l.byte_skip > 0)
      p.offset += l.byte_skip;
    else if (l.skip_in_file && l.byte_skip == -1 && l.encoding != Encoding::Raw)
      throw VolumeError(header, "a header size of -1 (the data at the end of the file) needs raw data");
    else
      p.decoded_skip = l.byte_skip;
    if (l.encoding == Encoding::Raw) {  // sizes known now: checked before anything is allocated
      const int64_t size = int64_t(fs::file_size(p.path, ec));
      const int64_t holds = size - p.offset;
      if (holds < p.bytes)
        throw VolumeError(p.path, "truncated: the header " + header.filename().string() + " promises " +
                                      std::to_string(p.bytes) + " data bytes here, the file holds " +
                                      std::to_string(std::max<int64_t>(holds, 0)) + " after its skips");
      if (p.decoded_skip == -1) {
        p.offset = size - p.bytes;
        p.decoded_skip = 0;
      } else if (holds > p.bytes) {
        throw VolumeError(p.path, "the file holds " + std::to_string(holds) +
                                      " data bytes after its skips, the header " + header.filename().string() +
                                      " promises " + std::to_string(p.bytes) + " (" + std::to_string(holds - p.bytes) +
                                      " too many; " + l.last_bytes + " reads the last bytes)");
      }
    }
    parts.push_back(std::move(p));
  }
  return parts;
}

}  // namespace peakcast::detail
