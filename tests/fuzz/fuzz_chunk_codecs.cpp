// Any bytes as a compressed chunk, decoded by each codec to an expected size taken from the first
// two bytes (at most 64 KiB): the output is exactly that size or the chunk is refused with a
// VolumeError; never more output than expected (fuzz_chunk_codecs.options caps every allocation,
// so a decoder that sized its output from the stream's own claim is a finding).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "chunked/chunk_codec.h"
#include "core/volume_io.h"

using namespace peakcast::chunked;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  const size_t expected = size_t(data[0]) << 8 | data[1];
  const std::vector<uint8_t> in(data + 2, data + size);
  for (Compressor id : {Compressor::None, Compressor::Zlib, Compressor::Gzip, Compressor::Zstd, Compressor::Blosc}) {
    CompressorSpec spec;
    spec.id = id;
    try {
      const auto out = decode_chunk(spec, in, expected, "chunk");
      if (out.size() != expected) std::abort();
    } catch (const peakcast::VolumeError&) {
    }
  }
  return 0;
}
