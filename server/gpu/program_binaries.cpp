#include "gpu/program_binaries.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <system_error>
#include <unistd.h>

#include "core/log.h"

namespace fs = std::filesystem;

namespace peakcast::gpu {
namespace {

constexpr char kMagic[4] = {'P', 'C', 'P', 'B'};
constexpr uint32_t kMaxBinaryBytes = 64u << 20;  // larger is not a program binary

uint64_t fnv1a(const std::string& s, uint64_t h) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

}  // namespace

ProgramBinaries::ProgramBinaries(fs::path dir, std::string driver_identity)
    : dir_(std::move(dir)), identity_(std::move(driver_identity)) {}

std::string ProgramBinaries::name_of(const std::vector<std::string>& sources) const {
  // Two 64-bit FNV-1a hashes with different offsets: a 128-bit name, each part a separator away
  // from the next so ("ab", "c") and ("a", "bc") differ.
  uint64_t a = fnv1a(identity_ + '\x1f', 0xcbf29ce484222325ull), b = fnv1a('\x1e' + identity_, 0x84222325cbf29ce4ull);
  for (const auto& s : sources) {
    a = fnv1a(s + '\x1f', a);
    b = fnv1a('\x1e' + s, b);
  }
  char name[40];
  std::snprintf(name, sizeof name, "%016llx%016llx.bin", static_cast<unsigned long long>(a),
                static_cast<unsigned long long>(b));
  return name;
}

bool ProgramBinaries::load(const std::string& name, const Program& program) const {
  if (!enabled()) return false;
  std::ifstream in(dir_ / name, std::ios::binary);
  if (!in) return false;
  char magic[4];
  uint32_t format = 0, size = 0;
  in.read(magic, 4);
  in.read(reinterpret_cast<char*>(&format), 4);
  in.read(reinterpret_cast<char*>(&size), 4);
  if (!in || std::memcmp(magic, kMagic, 4) != 0 || size == 0 || size > kMaxBinaryBytes) return false;
  std::vector<char> data(size);
  in.read(data.data(), std::streamsize(size));
  if (!in || in.gcount() != std::streamsize(size)) return false;  // truncated
  glProgramBinary(program.id(), GLenum(format), data.data(), GLsizei(size));
  GLint ok = 0;
  glGetProgramiv(program.id(), GL_LINK_STATUS, &ok);
  return ok != 0;
}

void ProgramBinaries::save(const std::string& name, const Program& program) {
  if (!enabled()) return;
  GLint size = 0;
  glGetProgramiv(program.id(), GL_PROGRAM_BINARY_LENGTH, &size);
  if (size <= 0 || uint32_t(size) > kMaxBinaryBytes) return;  // the driver keeps none
  std::vector<char> data(size_t(size), 0);
  GLenum format = 0;
  GLsizei written = 0;
  glGetProgramBinary(program.id(), size, &written, &format, data.data());
  if (written <= 0) return;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  // Written beside, then renamed into place: a reader sees a whole file or none.
  const fs::path tmp = dir_ / (name + ".tmp" + std::to_string(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    const uint32_t f = uint32_t(format), n = uint32_t(written);
    out.write(kMagic, 4);
    out.write(reinterpret_cast<const char*>(&f), 4);
    out.write(reinterpret_cast<const char*>(&n), 4);
    out.write(data.data(), std::streamsize(n));
    if (!out) ec = std::make_error_code(std::errc::io_error);
  }
  if (!ec) fs::rename(tmp, dir_ / name, ec);
  if (ec) {
    fs::remove(tmp, ec);
    if (!warned_) log::warn("program cache " + dir_.string() + " cannot be written: shaders compile in every process");
    warned_ = true;
  }
}

fs::path default_program_cache_dir() {
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "peakcast/programs";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache/peakcast/programs";
  return {};
}

}  // namespace peakcast::gpu
