// A payload's byte streams, shared by the format readers: gzip and zlib inflated a MiB at a time,
// and the count of bytes read that LoadOptions::progress hears (LoadProgress).
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {

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

}  // namespace peakcast::detail
