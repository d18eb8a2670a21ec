// A payload's byte streams, shared by the format readers: raw bytes (large files read by the
// workers in parallel), gzip and zlib inflated a MiB at a time, and the count of bytes read that
// LoadOptions::progress hears (LoadProgress).
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "core/parallel.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {

File open_file(const fs::path& path, int64_t offset) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw VolumeError(path, "no such file");
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) throw VolumeError(path, std::string("cannot open: ") + std::strerror(errno));
  if (offset > 0 && std::fseek(f.get(), long(offset), SEEK_SET) != 0) throw VolumeError(path, "cannot seek");
  return f;
}

void LoadProgress::add(size_t bytes) {
  if (!tell_ || total_ == 0) return;
  const size_t now = bytes_.fetch_add(bytes) + bytes;
  // Reading ends at 99%: the statistics are still to come.
  const int percent = int(std::min<size_t>(99, now / (total_ / 100 + 1)));
  if (percent > told_.load(std::memory_order_relaxed)) tell(percent);
}

void LoadProgress::done() {
  if (tell_) tell(100);
}

void LoadProgress::tell(int percent) {
  std::lock_guard lock(m_);
  if (percent <= told_) return;
  told_ = percent;
  tell_(percent / 100.0);
}

void inflate_file(const fs::path& path, int64_t skip, Encoding enc,
                  const std::function<bool(const uint8_t*, size_t)>& sink) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(nullptr, std::fclose);
  {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw VolumeError(path, "no such file");
    f.reset(std::fopen(path.c_str(), "rb"));
    if (!f) throw VolumeError(path, std::string("cannot open: ") + std::strerror(errno));
  }
  if (skip > 0) std::fseek(f.get(), long(skip), SEEK_SET);
  if (enc == Encoding::Gzip) {
    unsigned char magic[2] = {0, 0};
    if (std::fread(magic, 1, 2, f.get()) != 2 || magic[0] != 0x1f || magic[1] != 0x8b)
      throw VolumeError(path, "gzip stream corrupt: missing gzip magic bytes");
    std::fseek(f.get(), long(std::max<int64_t>(skip, 0)), SEEK_SET);
  }
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw VolumeError(path, "zlib init failed");
  std::unique_ptr<z_stream, int (*)(z_stream*)> guard(&z, inflateEnd);
  std::vector<unsigned char> in(1 << 20), out(1 << 20);
  bool more = true;
  while (more) {
    z.avail_in = uInt(std::fread(in.data(), 1, in.size(), f.get()));
    if (z.avail_in == 0) break;
    z.next_in = in.data();
    while (more && z.avail_in > 0) {
      z.next_out = out.data();
      z.avail_out = uInt(out.size());
      const int rc = inflate(&z, Z_NO_FLUSH);
      const size_t n = out.size() - z.avail_out;
      if (n > 0) more = sink(out.data(), n);
      if (rc == Z_STREAM_END) {
        if (z.avail_in > 0 || !std::feof(f.get())) {
          inflateReset(&z);  // concatenated gzip members
          continue;
        }
        return;
      }
      if (rc != Z_OK && rc != Z_BUF_ERROR)
        throw VolumeError(path, std::string("gzip stream corrupt: ") + (z.msg ? z.msg : "inflate error"));
      if (rc == Z_BUF_ERROR && n == 0) break;
    }
  }
}

// Reads up to `want` bytes of raw data into dst; returns the count read. Reads go in pieces of at
// most 8 MiB, each told to `progress`.
size_t read_raw(const fs::path& path, int64_t skip, uint8_t* dst, size_t want, bool last, LoadProgress& progress) {
  File f = open_file(path);
  std::error_code ec;
  const auto size = int64_t(fs::file_size(path, ec));
  int64_t offset = skip;
  if (skip < 0) offset = std::max<int64_t>(0, size - int64_t(want));
  if (offset > size) throw VolumeError(path, "byte skip beyond the end of the file");
  // Refuse truncated files before touching the data (the only file, or the last of several).
  if (last && size - offset < int64_t(want))
    throw VolumeError(path, "truncated: header promises " + std::to_string(want) + " data bytes, file holds " +
                                std::to_string(size - offset));
  const size_t avail = size_t(std::max<int64_t>(0, size - offset));
  const size_t n = std::min(want, avail);
  constexpr size_t piece = size_t(8) << 20;
  if (n < (size_t(64) << 20)) {
    std::fseek(f.get(), long(offset), SEEK_SET);
    size_t got = 0;
    while (got < n) {
      const size_t r = std::fread(dst + got, 1, std::min(piece, n - got), f.get());
      if (r == 0) break;
      got += r;
      progress.add(r);
    }
    return got;
  }
  // Large files: the workers read a share each with pread: the copy
  // from the page cache and the first touch of the fresh allocation run in parallel.
  const int fd = fileno(f.get());
  std::atomic<bool> failed{false};
  parallel_chunks(n, [&](size_t begin, size_t end, int) {
    while (begin < end && !failed) {
      const ssize_t got = ::pread(fd, dst + begin, std::min(end - begin, piece), off_t(offset + int64_t(begin)));
      if (got <= 0) {
        failed = true;
        return;
      }
      begin += size_t(got);
      progress.add(size_t(got));
    }
  });
  if (failed) throw VolumeError(path, "read failed (the file shrank or could not be read)");
  return n;
}

// Inflates gzip or zlib streams (auto-detected) into dst, 1 MiB of input at a time.
size_t read_compressed(const fs::path& path, int64_t skip, Encoding enc, uint8_t* dst, size_t want,
                       LoadProgress& progress) {
  size_t produced = 0;
  inflate_file(path, skip, enc, [&](const uint8_t* data, size_t n) {
    const size_t take = std::min(n, want - produced);
    std::copy(data, data + take, dst + produced);
    produced += take;
    progress.add(take);
    return produced < want;
  });
  return produced;
}

}  // namespace peakcast::detail
