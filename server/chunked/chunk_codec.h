// The compressors of chunked volumes (OME-Zarr's numcodecs ids, Neuroglancer's gzip): decoding
// a chunk to exactly the bytes its array declares, and encoding one for the writer. Every
// refusal is a VolumeError naming the chunk's file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace peakcast::chunked {

enum class Compressor { None, Zlib, Gzip, Zstd, Blosc };

struct CompressorSpec {
  Compressor id = Compressor::None;
  int level = 5;              // zlib/gzip 1-9, zstd 1-22, blosc 0-9
  std::string cname = "lz4";  // blosc's inner codec: blosclz lz4 lz4hc zlib zstd
  int shuffle = 1;            // blosc: 0 none, 1 byte, 2 bit
};

// A .zarray "compressor" entry (null: none). Throws std::invalid_argument naming what is not
// supported (an unknown id, a blosc cname this libblosc lacks).
CompressorSpec parse_compressor(const nlohmann::json& j);
nlohmann::json compressor_json(const CompressorSpec& spec);
// By name on the command line: none zlib gzip zstd blosc (blosc: zstd inside, byte shuffle, as
// ome-zarr-py writes).
CompressorSpec compressor_by_name(const std::string& name);

// `in` decoded to exactly `expected` bytes. A stream that ends early, runs longer or is corrupt
// is refused naming `file`. Zlib and Gzip both accept either wrapping (numcodecs and Neuroglancer
// files are found with both). Never allocates more than `expected` bytes of output.
std::vector<uint8_t> decode_chunk(const CompressorSpec& spec, const std::vector<uint8_t>& in, size_t expected,
                                  const std::filesystem::path& file);

// `n` bytes of voxels of `typesize` bytes each, encoded.
std::vector<uint8_t> encode_chunk(const CompressorSpec& spec, const uint8_t* data, size_t n, size_t typesize);

// Gzip's and zlib's magic at the start of a chunk file.
bool looks_gzip(const std::vector<uint8_t>& bytes);

}  // namespace peakcast::chunked
