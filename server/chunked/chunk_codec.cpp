#include "chunked/chunk_codec.h"

#include <blosc.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/volume_io.h"

namespace peakcast::chunked {
namespace {

using Bytes = std::vector<uint8_t>;

void check_size(size_t got, size_t expected, const std::filesystem::path& file) {
  if (got < expected)
    throw VolumeError(file, "truncated chunk: " + std::to_string(got) + " of " + std::to_string(expected) + " bytes");
  if (got > expected) throw VolumeError(file, "chunk holds more than its " + std::to_string(expected) + " bytes");
}

// zlib or gzip (windowBits 15 + 32 detects either). Once `expected` bytes are out, a one-byte
// spill buffer tells a stream that runs longer.
Bytes inflate_bytes(const Bytes& in, size_t expected, const std::filesystem::path& file) {
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw std::runtime_error("zlib: inflateInit2 failed");
  Bytes out(expected);
  uint8_t spill = 0;
  bool spilling = false;
  z.next_in = const_cast<uint8_t*>(in.data());
  z.avail_in = uInt(std::min<size_t>(in.size(), UINT32_MAX));
  z.next_out = out.data();
  z.avail_out = uInt(expected);
  int rc = Z_OK;
  for (;;) {
    if (z.avail_out == 0) {
      if (spilling) break;  // a byte past the end
      spilling = true;
      z.next_out = &spill;
      z.avail_out = 1;
    }
    rc = inflate(&z, Z_NO_FLUSH);
    if (rc != Z_OK) break;
  }
  const size_t got = size_t(z.total_out);
  const std::string msg = z.msg ? z.msg : "error";
  inflateEnd(&z);
  if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
    throw VolumeError(file, "corrupt compressed chunk (zlib: " + msg + ")");
  check_size(got, expected, file);
  if (rc != Z_STREAM_END) throw VolumeError(file, "truncated chunk: the compressed stream does not end");
  return out;
}

Bytes unzstd(const Bytes& in, size_t expected, const std::filesystem::path& file) {
  std::unique_ptr<ZSTD_DStream, size_t (*)(ZSTD_DStream*)> d(ZSTD_createDStream(), ZSTD_freeDStream);
  if (!d) throw std::runtime_error("zstd: out of memory");
  // The frame's window is what the decoder allocates, whatever the chunk decodes to: a 15-byte
  // frame may claim 128 MiB (found by tests/fuzz/fuzz_chunk_codecs). A chunk's encoder never needs
  // a window larger than the chunk (numcodecs compresses it in one call, its size known), so the
  // window is capped at the power of two that holds `expected`: a larger claim is refused.
  int window_log = 10;  // ZSTD_WINDOWLOG_ABSOLUTEMIN (zstd.h states it only for static linking)
  while (window_log < 31 && (size_t(1) << window_log) < expected) ++window_log;
  ZSTD_DCtx_setParameter(d.get(), ZSTD_d_windowLogMax, window_log);
  // Only the current frame format: libzstd's legacy decoders (v0.1-v0.7 magics) ignore that cap
  // and allocate the window a 14-byte frame claims (64 MiB, found by the same fuzz target).
  // numcodecs and every zstd since 1.0 write the current magic, 0xFD2FB528 little-endian.
  if (in.size() < 4 || in[0] != 0x28 || in[1] != 0xb5 || in[2] != 0x2f || in[3] != 0xfd)
    throw VolumeError(file, "corrupt compressed chunk (zstd: not a zstd frame, or a pre-1.0 legacy one)");
  Bytes out(expected);
  uint8_t spill = 0;
  bool spilling = false;
  ZSTD_inBuffer ib{in.data(), in.size(), 0};
  ZSTD_outBuffer ob{out.data(), expected, 0};
  bool ended = false;
  for (;;) {
    if (ob.pos == ob.size) {
      if (spilling) break;  // a byte past the end
      spilling = true;
      ob = ZSTD_outBuffer{&spill, 1, 0};
    }
    const size_t rc = ZSTD_decompressStream(d.get(), &ob, &ib);
    if (ZSTD_isError(rc))
      throw VolumeError(file, std::string("corrupt compressed chunk (zstd: ") + ZSTD_getErrorName(rc) + ")");
    if (rc == 0) {
      ended = true;
      break;
    }
    if (ib.pos == ib.size && ob.pos < ob.size) break;  // needs input there is none of
  }
  check_size(spilling ? expected + ob.pos : ob.pos, expected, file);
  if (!ended) throw VolumeError(file, "truncated chunk: the compressed stream does not end");
  return out;
}

Bytes unblosc(const Bytes& in, size_t expected, const std::filesystem::path& file) {
  size_t nbytes = 0;
  if (in.size() < BLOSC_MIN_HEADER_LENGTH || blosc_cbuffer_validate(in.data(), in.size(), &nbytes) != 0)
    throw VolumeError(file, "corrupt blosc chunk (header does not match its " + std::to_string(in.size()) + " bytes)");
  check_size(nbytes, expected, file);
  Bytes out(expected);
  const int n = blosc_decompress_ctx(in.data(), out.data(), out.size(), 1);
  if (n < 0 || size_t(n) != expected) throw VolumeError(file, "corrupt blosc chunk");
  return out;
}

}  // namespace

bool looks_gzip(const Bytes& b) { return b.size() >= 2 && b[0] == 0x1f && b[1] == 0x8b; }

CompressorSpec parse_compressor(const nlohmann::json& j) {
  CompressorSpec s;
  if (j.is_null()) return s;
  if (!j.is_object() || !j.contains("id") || !j["id"].is_string())
    throw std::invalid_argument("compressor must be null or an object with an \"id\"");
  const std::string id = j["id"];
  auto num = [&](const char* key, int fallback) {
    if (!j.contains(key)) return fallback;
    if (!j[key].is_number_integer())
      throw std::invalid_argument(std::string("compressor.") + key + " must be an integer");
    return j[key].get<int>();
  };
  if (id == "zlib")
    s = {Compressor::Zlib, num("level", 1)};
  else if (id == "gzip")
    s = {Compressor::Gzip, num("level", 1)};
  else if (id == "zstd")
    s = {Compressor::Zstd, num("level", 1)};
  else if (id == "blosc") {
    s.id = Compressor::Blosc;
    s.level = num("clevel", 5);
    s.shuffle = num("shuffle", 1);
    if (j.contains("cname")) {
      if (!j["cname"].is_string()) throw std::invalid_argument("compressor.cname must be a string");
      s.cname = j["cname"];
    }
    if (blosc_compname_to_compcode(s.cname.c_str()) < 0)
      throw std::invalid_argument("blosc compressor '" + s.cname + "' is not in this libblosc");
  } else {
    throw std::invalid_argument("compressor '" + id + "' is not supported (none, zlib, gzip, zstd, blosc)");
  }
  return s;
}

nlohmann::json compressor_json(const CompressorSpec& s) {
  switch (s.id) {
    case Compressor::None: return nullptr;
    case Compressor::Zlib: return {{"id", "zlib"}, {"level", s.level}};
    case Compressor::Gzip: return {{"id", "gzip"}, {"level", s.level}};
    case Compressor::Zstd: return {{"id", "zstd"}, {"level", s.level}};
    case Compressor::Blosc:
      return {{"id", "blosc"}, {"cname", s.cname}, {"clevel", s.level}, {"shuffle", s.shuffle}, {"blocksize", 0}};
  }
  return nullptr;
}

CompressorSpec compressor_by_name(const std::string& name) {
  if (name == "none") return {Compressor::None};
  if (name == "zlib") return {Compressor::Zlib, 5};
  if (name == "gzip") return {Compressor::Gzip, 5};
  if (name == "zstd") return {Compressor::Zstd, 5};
  if (name == "blosc") return {Compressor::Blosc, 5, "zstd", 1};
  throw std::invalid_argument("unknown compressor '" + name + "' (none, zlib, gzip, zstd, blosc)");
}

Bytes decode_chunk(const CompressorSpec& spec, const Bytes& in, size_t expected, const std::filesystem::path& file) {
  switch (spec.id) {
    case Compressor::None: check_size(in.size(), expected, file); return in;
    case Compressor::Zlib:
    case Compressor::Gzip: return inflate_bytes(in, expected, file);
    case Compressor::Zstd: return unzstd(in, expected, file);
    case Compressor::Blosc: return unblosc(in, expected, file);
  }
  return {};
}

Bytes encode_chunk(const CompressorSpec& spec, const uint8_t* data, size_t n, size_t typesize) {
  Bytes out;
  switch (spec.id) {
    case Compressor::None: return Bytes(data, data + n);
    case Compressor::Zlib:
    case Compressor::Gzip: {
      z_stream z{};
      const int bits = spec.id == Compressor::Gzip ? 15 + 16 : 15;
      if (deflateInit2(&z, std::clamp(spec.level, 1, 9), Z_DEFLATED, bits, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw std::runtime_error("zlib: deflateInit2 failed");
      out.resize(deflateBound(&z, uLong(n)) + 32);
      z.next_in = const_cast<uint8_t*>(data);
      z.avail_in = uInt(n);
      z.next_out = out.data();
      z.avail_out = uInt(out.size());
      const int rc = deflate(&z, Z_FINISH);
      out.resize(z.total_out);
      deflateEnd(&z);
      if (rc != Z_STREAM_END) throw std::runtime_error("zlib: deflate failed");
      return out;
    }
    case Compressor::Zstd: {
      out.resize(ZSTD_compressBound(n));
      const size_t m = ZSTD_compress(out.data(), out.size(), data, n, spec.level);
      if (ZSTD_isError(m)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(m));
      out.resize(m);
      return out;
    }
    case Compressor::Blosc: {
      out.resize(n + BLOSC_MAX_OVERHEAD);
      const int m = blosc_compress_ctx(std::clamp(spec.level, 0, 9), spec.shuffle, typesize, n, data, out.data(),
                                       out.size(), spec.cname.c_str(), 0, 1);
      if (m <= 0) throw std::runtime_error("blosc: compression failed");
      out.resize(size_t(m));
      return out;
    }
  }
  return out;
}

}  // namespace peakcast::chunked
