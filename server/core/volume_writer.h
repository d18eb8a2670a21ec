// Writing volumes: raw + JSON sidecar (.raw), NRRD (.nrrd attached, .nhdr detached; raw or
// gzip) and MetaImage (.mhd + .raw, .mha). Streams slabs so generators never hold a volume.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/volume.h"

namespace peakcast {

struct WriteOptions {
  bool gzip = false;  // NRRD and raw+JSON only
};

class SlabWriter {
 public:
  // Bytes passed to write() are voxels of header.source, little-endian, x fastest.
  SlabWriter(const std::filesystem::path& path, const VolumeHeader& header, WriteOptions options = {});
  ~SlabWriter();
  SlabWriter(const SlabWriter&) = delete;
  SlabWriter& operator=(const SlabWriter&) = delete;

  void write(const void* data, size_t bytes);
  void close();  // throws on short writes or a wrong total

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Writes a loaded volume back in its source type (signed types un-shifted).
void write_volume(const std::filesystem::path& path, const Volume& volume, WriteOptions options = {});

}  // namespace peakcast
