// The encodings of a payload a reader resolved file by file (DataPart): raw, gzip/zlib, bzip2,
// hex and text, decoded a MiB at a time, and a part's byte skip and exact size on top. Decoding
// never sizes anything from the stream: the output goes out in 1 MiB pieces, and a stream that
// decodes to more than its part is stopped and refused (a bzip2 or gzip bomb costs its first MiBs).
#include <bzlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

using Sink = std::function<bool(const uint8_t*, size_t)>;
constexpr size_t kPiece = size_t(1) << 20;

// Calls each(chunk, n) for the file's bytes from `offset`, 1 MiB at a time, until it returns false.
template <typename Each>
void each_chunk(const fs::path& path, int64_t offset, Each&& each) {
  File f = open_file(path, offset);
  std::vector<uint8_t> in(kPiece);
  for (;;) {
    const size_t n = std::fread(in.data(), 1, in.size(), f.get());
    if (n == 0 || !each(in.data(), n)) return;
  }
}

void decode_bzip2(const fs::path& path, int64_t offset, const Sink& sink) {
  bz_stream z{};
  if (BZ2_bzDecompressInit(&z, 0, 0) != BZ_OK) throw VolumeError(path, "bzip2: out of memory");
  std::unique_ptr<bz_stream, int (*)(bz_stream*)> guard(&z, BZ2_bzDecompressEnd);
  std::vector<char> out(kPiece);
  bool more = true, ended = false;
  each_chunk(path, offset, [&](const uint8_t* data, size_t n) {
    z.next_in = reinterpret_cast<char*>(const_cast<uint8_t*>(data));
    z.avail_in = unsigned(n);
    while (more && z.avail_in > 0) {
      if (ended) {  // another stream follows (pbzip2 writes several): read on as one
        BZ2_bzDecompressEnd(&z);
        char* next = z.next_in;
        const unsigned left = z.avail_in;
        z = bz_stream{};
        if (BZ2_bzDecompressInit(&z, 0, 0) != BZ_OK) throw VolumeError(path, "bzip2: out of memory");
        z.next_in = next;
        z.avail_in = left;
        ended = false;
      }
      z.next_out = out.data();
      z.avail_out = unsigned(out.size());
      const int rc = BZ2_bzDecompress(&z);
      if (rc != BZ_OK && rc != BZ_STREAM_END)
        throw VolumeError(path, "bzip2 stream corrupt (error " + std::to_string(rc) + ") at compressed byte " +
                                    std::to_string(z.total_in_lo32));
      const size_t produced = out.size() - z.avail_out;
      if (produced > 0) more = sink(reinterpret_cast<const uint8_t*>(out.data()), produced);
      ended = rc == BZ_STREAM_END;
    }
    return more;
  });
  if (more && !ended) throw VolumeError(path, "truncated: the bzip2 stream does not end");
}

int hex_digit(uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  c = uint8_t(c | 0x20);
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool is_space(uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

void decode_hex(const fs::path& path, int64_t offset, const Sink& sink) {
  std::vector<uint8_t> out;
  out.reserve(kPiece);
  int high = -1;
  int64_t at = offset;
  bool more = true;
  each_chunk(path, offset, [&](const uint8_t* data, size_t n) {
    for (size_t i = 0; i < n && more; ++i, ++at) {
      if (is_space(data[i])) continue;
      const int d = hex_digit(data[i]);
      if (d < 0) throw VolumeError(path, "hex data: byte " + std::to_string(at) + " is not a hex digit");
      if (high < 0) {
        high = d;
        continue;
      }
      out.push_back(uint8_t(high << 4 | d));
      high = -1;
      if (out.size() == kPiece) {
        more = sink(out.data(), out.size());
        out.clear();
      }
    }
    return more;
  });
  if (!more) return;
  if (high >= 0) throw VolumeError(path, "hex data: an odd number of hex digits");
  if (!out.empty()) sink(out.data(), out.size());
}

// One number of a text payload as `type`'s bytes: integers must be whole and in range.
void put_number(const fs::path& path, const std::string& word, int64_t index, SourceType type,
                std::vector<uint8_t>& out) {
  const char* b = word.data() + (word[0] == '+' ? 1 : 0);
  double v = 0;
  const auto [end, ec] = std::from_chars(b, word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size())
    throw VolumeError(path,
                      "text data: value " + std::to_string(index) + " '" + word.substr(0, 40) + "' is not a number");
  auto whole = [&](double lo, double hi) {
    if (!(v == std::floor(v) && v >= lo && v <= hi))
      throw VolumeError(path, "text data: value " + std::to_string(index) + " (" + word.substr(0, 40) +
                                  ") does not fit " + to_string(type));
  };
  auto append = [&](auto x) {
    uint8_t bytes[sizeof(x)];
    std::memcpy(bytes, &x, sizeof(x));
    out.insert(out.end(), bytes, bytes + sizeof(x));
  };
  switch (type) {
    case SourceType::U8: whole(0, 255), append(uint8_t(v)); break;
    case SourceType::I8: whole(-128, 127), append(int8_t(v)); break;
    case SourceType::U16: whole(0, 65535), append(uint16_t(v)); break;
    case SourceType::I16: whole(-32768, 32767), append(int16_t(v)); break;
    case SourceType::F32: append(float(v)); break;
  }
}

void decode_text(const fs::path& path, int64_t offset, SourceType type, const Sink& sink) {
  std::vector<uint8_t> out;
  out.reserve(kPiece + 8);
  std::string word;
  int64_t index = 0;
  bool more = true;
  auto flush_word = [&] {
    if (word.empty()) return;
    put_number(path, word, index++, type, out);
    word.clear();
    if (out.size() >= kPiece) {
      more = sink(out.data(), out.size());
      out.clear();
    }
  };
  each_chunk(path, offset, [&](const uint8_t* data, size_t n) {
    for (size_t i = 0; i < n && more; ++i) {
      if (is_space(data[i]) || data[i] == ',') {
        flush_word();
      } else if (word.size() >= 64) {
        throw VolumeError(path, "text data: value " + std::to_string(index) + " is longer than 64 characters");
      } else {
        word += char(data[i]);
      }
    }
    return more;
  });
  if (more) flush_word();
  if (more && !out.empty()) sink(out.data(), out.size());
}

}  // namespace

void decode_file(const fs::path& path, int64_t offset, Encoding enc, SourceType text_type, const Sink& sink) {
  switch (enc) {
    case Encoding::Raw: return each_chunk(path, offset, sink);
    case Encoding::Gzip:
    case Encoding::Zlib: return inflate_file(path, offset, enc, sink);
    case Encoding::Bzip2: return decode_bzip2(path, offset, sink);
    case Encoding::Hex: return decode_hex(path, offset, sink);
    case Encoding::Text: return decode_text(path, offset, text_type, sink);
  }
}

void stream_part(const DataPart& part, Encoding enc, SourceType text_type, const Sink& sink) {
  const std::string unit = enc == Encoding::Text ? " bytes (as " + std::string(to_string(text_type)) + ")" : " bytes";
  // Decoding runs past the part's end only so far: a longer stream is refused once this is reached.
  const int64_t cap = 2 * part.bytes + int64_t(kPiece);
  int64_t skip = part.decoded_skip;
  if (skip == -1) {  // the voxels are the last bytes: count the decoded data first
    int64_t n = 0;
    decode_file(part.path, part.offset, enc, text_type, [&](const uint8_t*, size_t k) {
      n += int64_t(k);
      return n <= cap;
    });
    if (n > cap)
      throw VolumeError(part.path, "byte skip -1: the decoded data runs past " + std::to_string(cap) +
                                       " bytes, more than twice the volume's " + std::to_string(part.bytes) +
                                       " and 1 MiB");
    if (n < part.bytes)
      throw VolumeError(part.path, "truncated: the decoded data holds " + std::to_string(n) + unit +
                                       ", the volume needs " + std::to_string(part.bytes));
    skip = n - part.bytes;
  }
  int64_t seen = 0, given = 0;
  bool stopped = false;
  decode_file(part.path, part.offset, enc, text_type, [&](const uint8_t* data, size_t k) {
    const int64_t a = std::clamp<int64_t>(skip - seen, 0, int64_t(k));
    const int64_t b = std::clamp<int64_t>(skip + part.bytes - seen, 0, int64_t(k));
    seen += int64_t(k);
    if (b > a) {
      given += b - a;
      if (!sink(data + a, size_t(b - a))) {
        stopped = true;
        return false;
      }
    }
    return seen <= skip + part.bytes || seen <= cap;  // past the end: counted up to the cap
  });
  if (stopped) return;
  const int64_t voxels = seen - std::min(seen, skip);
  if (voxels < part.bytes)
    throw VolumeError(part.path, "truncated: the decoded data holds " + std::to_string(voxels) + unit +
                                     (skip > 0 ? " after the byte skip" : "") + ", the volume needs " +
                                     std::to_string(part.bytes));
  if (voxels > part.bytes)
    throw VolumeError(part.path, "the decoded data holds " + std::string(seen > cap ? "more than " : "") +
                                     std::to_string(voxels) + unit + (skip > 0 ? " after the byte skip" : "") +
                                     ", the volume needs " + std::to_string(part.bytes) + " (" +
                                     std::to_string(voxels - part.bytes) +
                                     " too many; 'byte skip: -1' reads the last bytes)");
}

void read_parts(const PayloadSpec& payload, uint8_t* dst, size_t total, LoadProgress& progress) {
  size_t at = 0;
  for (const DataPart& p : payload.parts) {
    if (at + size_t(p.bytes) > total) throw VolumeError(p.path, "the data files hold more than the volume's bytes");
    if (payload.encoding == Encoding::Raw) {
      at += read_raw(p.path, p.offset, dst + at, size_t(p.bytes), true, progress);
      continue;
    }
    stream_part(p, payload.encoding, payload.text_type, [&](const uint8_t* data, size_t n) {
      std::copy(data, data + n, dst + at);
      at += n;
      progress.add(n);
      return true;
    });
  }
  if (at != total)
    throw VolumeError(payload.parts.back().path, "truncated: the data files hold " + std::to_string(at) +
                                                     " bytes, the volume needs " + std::to_string(total));
}

}  // namespace peakcast::detail
