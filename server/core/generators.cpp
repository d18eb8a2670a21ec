#include "core/generators.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/hash.h"
#include "core/parallel.h"
#include "core/vessel_tree.h"

namespace peakcast {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Marschner & Lobb 1994, f_M = 6, alpha = 0.25, on [-1, 1]^3.
double marschner_lobb(double x, double y, double z) {
  const double fm = 6.0, alpha = 0.25;
  const double r = std::sqrt(x * x + y * y);
  const double rho_r = std::cos(2.0 * kPi * fm * std::cos(kPi * r / 2.0));
  return (1.0 - std::sin(kPi * z / 2.0) + alpha * (1.0 + rho_r)) / (2.0 * (1.0 + alpha));
}

struct Blob {
  double x, y, z, inv_r2, weight;
};

std::vector<Blob> make_blobs(uint64_t seed, int count) {
  std::vector<Blob> blobs;
  for (int b = 0; b < count; ++b) {
    double r = 0.08 + 0.14 * hash01(seed, b, 0, 0, 11);
    blobs.push_back({0.15 + 0.7 * hash01(seed, b, 1, 0, 11), 0.15 + 0.7 * hash01(seed, b, 2, 0, 11),
                     0.15 + 0.7 * hash01(seed, b, 3, 0, 11), 1.0 / (r * r), 0.4 + 0.6 * hash01(seed, b, 4, 0, 11)});
  }
  return blobs;
}

double blobs_value(const std::vector<Blob>& blobs, double x, double y, double z) {
  double s = 0;
  for (const auto& b : blobs) {
    double dx = x - b.x, dy = y - b.y, dz = z - b.z;
    s += b.weight * std::exp(-(dx * dx + dy * dy + dz * dz) * b.inv_r2);
  }
  return std::min(1.0, s);
}

// Heptane-like: a smooth plume of temperature plus a thin, hot reaction sheet (about one voxel
// wide) on a wavy surface: the sharp feature peak finding is made for.
double fire_value(const GeneratorSpec& s, double x, double y, double z, double voxel) {
  const double plume = 0.45 * std::exp(-((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5)) / 0.05) * (1.0 - 0.6 * z);
  const double sheet_h =
      0.45 + 0.08 * std::sin(2 * kPi * (2 * x + 0.3 * double(s.seed % 7))) * std::cos(2 * kPi * 1.5 * y);
  const double d = (z - sheet_h) / voxel;  // in voxels
  const double sheet = 0.5 * std::exp(-d * d / 0.5);
  return std::clamp(0.05 + plume + sheet, 0.0, 1.0);
}

// Electron-microscopy-like: membranes of a 3D Voronoi tessellation (seeds jittered on a grid
// of `cell` voxels), on a grey cytoplasm, with voxel noise.
double em_value(const GeneratorSpec& s, int64_t i, int64_t j, int64_t k) {
  const double cell = 40.0;
  const int64_t gi = int64_t(std::floor(i / cell)), gj = int64_t(std::floor(j / cell)),
                gk = int64_t(std::floor(k / cell));
  double d1 = 1e30, d2 = 1e30;
  for (int64_t c = gk - 1; c <= gk + 1; ++c)
    for (int64_t b = gj - 1; b <= gj + 1; ++b)
      for (int64_t a = gi - 1; a <= gi + 1; ++a) {
        const double sx = (a + hash01(s.seed, a, b, c, 1)) * cell - double(i);
        const double sy = (b + hash01(s.seed, a, b, c, 2)) * cell - double(j);
        const double sz = (c + hash01(s.seed, a, b, c, 3)) * cell - double(k);
        const double d = sx * sx + sy * sy + sz * sz;
        if (d < d1) {
          d2 = d1;
          d1 = d;
        } else if (d < d2) {
          d2 = d;
        }
      }
  const double gap = std::sqrt(d2) - std::sqrt(d1);  // ~2x distance to the bisector plane
  const double membrane = std::exp(-gap * gap / 4.0);
  const double noise = hash01(s.seed, i, j, k, 4) - 0.5;
  return std::clamp(0.22 + 0.6 * membrane + 0.08 * noise, 0.0, 1.0);
}

template <typename T>
void quantise(const std::vector<double>& v, uint8_t* out, double scale) {
  auto* o = reinterpret_cast<T*>(out);
  for (size_t i = 0; i < v.size(); ++i) o[i] = T(std::lround(std::clamp(v[i], 0.0, 1.0) * scale));
}

// Fills slices [z0, z1) in the spec's source type, little-endian (signed types as signed).
// What a kind computes once per volume rather than per voxel.
struct Prepared {
  std::vector<Blob> blobs;
  VesselTree vessels;
};
Prepared prepare(const GeneratorSpec& s) {
  Prepared p;
  if (s.kind == GeneratorKind::Blobs) p.blobs = make_blobs(s.seed, 12);
  if (s.kind == GeneratorKind::Vessels) p.vessels = make_vessel_tree(s.seed, s.dims);
  return p;
}

void fill_slab(const GeneratorSpec& s, const Prepared& pre, int64_t z0, int64_t z1, uint8_t* out) {
  const int64_t nx = s.dims[0], ny = s.dims[1];
  const size_t row_bytes = size_t(nx) * source_bytes(s.type);
  parallel_for(size_t((z1 - z0) * ny), [&](size_t row) {
    const int64_t k = z0 + int64_t(row) / ny, j = int64_t(row) % ny;
    std::vector<double> v(static_cast<size_t>(nx));
    for (int64_t i = 0; i < nx; ++i) {
      if (s.kind == GeneratorKind::Blobs) {
        auto u = [](int64_t q, int64_t n) { return n > 1 ? double(q) / double(n - 1) : 0.5; };
        v[i] = blobs_value(pre.blobs, u(i, nx), u(j, ny), u(k, s.dims[2]));
      } else if (s.kind == GeneratorKind::Vessels) {
        v[i] = pre.vessels.value(i, j, k);
      } else {
        v[i] = generator_value(s, i, j, k);
      }
    }
    uint8_t* dst = out + row * row_bytes;
    switch (s.type) {
      case SourceType::U8: quantise<uint8_t>(v, dst, 255.0); break;
      case SourceType::U16: quantise<uint16_t>(v, dst, 65535.0); break;
      case SourceType::I8:
        for (auto& x : v) x = std::clamp(x, 0.0, 1.0) * 255.0 - 128.0;
        for (int64_t i = 0; i < nx; ++i) reinterpret_cast<int8_t*>(dst)[i] = int8_t(std::lround(v[i]));
        break;
      case SourceType::I16:
        for (int64_t i = 0; i < nx; ++i)
          reinterpret_cast<int16_t*>(dst)[i] = int16_t(std::lround(std::clamp(v[i], 0.0, 1.0) * 65535.0 - 32768.0));
        break;
      case SourceType::F32:
        for (int64_t i = 0; i < nx; ++i) reinterpret_cast<float*>(dst)[i] = float(v[i]);
        break;
    }
  });
}

}  // namespace

GeneratorKind parse_generator_kind(const std::string& n) {
  if (n == "marschner-lobb") return GeneratorKind::MarschnerLobb;
  if (n == "blobs") return GeneratorKind::Blobs;
  if (n == "fire") return GeneratorKind::Fire;
  if (n == "em") return GeneratorKind::Em;
  if (n == "sphere") return GeneratorKind::Sphere;
  if (n == "ramp") return GeneratorKind::Ramp;
  if (n == "vessels") return GeneratorKind::Vessels;
  throw std::invalid_argument("unknown volume kind '" + n +
                              "' (marschner-lobb, blobs, fire, em, sphere, ramp, vessels)");
}

const char* to_string(GeneratorKind k) {
  static const char* names[] = {"marschner-lobb", "blobs", "fire", "em", "sphere", "ramp", "vessels"};
  return names[int(k)];
}

SourceType default_type(GeneratorKind k) {
  switch (k) {
    case GeneratorKind::Blobs: return SourceType::U8;
    case GeneratorKind::Em:
    case GeneratorKind::Vessels: return SourceType::U16;
    default: return SourceType::F32;
  }
}

Dims default_dims(GeneratorKind k) {
  switch (k) {
    case GeneratorKind::MarschnerLobb: return {41, 41, 41};
    case GeneratorKind::Em: return {900, 500, 930};
    case GeneratorKind::Fire: return {151, 151, 151};
    case GeneratorKind::Vessels: return {128, 128, 128};
    default: return {64, 64, 64};
  }
}

double generator_value(const GeneratorSpec& s, int64_t i, int64_t j, int64_t k) {
  auto u = [](int64_t q, int64_t n) { return n > 1 ? double(q) / double(n - 1) : 0.5; };
  const double x = u(i, s.dims[0]), y = u(j, s.dims[1]), z = u(k, s.dims[2]);
  switch (s.kind) {
    case GeneratorKind::MarschnerLobb: return marschner_lobb(2 * x - 1, 2 * y - 1, 2 * z - 1);
    case GeneratorKind::Blobs: return blobs_value(make_blobs(s.seed, 12), x, y, z);
    case GeneratorKind::Fire: return fire_value(s, x, y, z, 1.0 / double(std::max<int64_t>(s.dims[2] - 1, 1)));
    case GeneratorKind::Em: return em_value(s, i, j, k);
    case GeneratorKind::Sphere: {  // 1 at the centre falling linearly to 0 at the inscribed radius
      const double dx = x - 0.5, dy = y - 0.5, dz = z - 0.5;
      return std::clamp(1.0 - 2.0 * std::sqrt(dx * dx + dy * dy + dz * dz), 0.0, 1.0);
    }
    case GeneratorKind::Ramp: return x;  // linear in x: trilinear interpolation is exact
    case GeneratorKind::Vessels: return make_vessel_tree(s.seed, s.dims).value(i, j, k);
  }
  return 0.0;
}

Volume generate_volume(const GeneratorSpec& s) {
  VolumeHeader h;
  h.dims = s.dims;
  h.spacing = s.spacing;
  h.source = s.type;
  Volume v(h);
  fill_slab(s, prepare(s), 0, s.dims[2], v.data());
  const size_t n = size_t(v.voxel_count());
  if (s.type == SourceType::I8)
    for (size_t i = 0; i < n; ++i) v.data()[i] ^= 0x80;
  if (s.type == SourceType::I16)
    for (size_t i = 0; i < n; ++i) reinterpret_cast<uint16_t*>(v.data())[i] ^= 0x8000;
  v.finalize_statistics();
  v.name = to_string(s.kind);
  return v;
}

void generate_to_file(const GeneratorSpec& s, const std::filesystem::path& out, WriteOptions options) {
  VolumeHeader h;
  h.dims = s.dims;
  h.spacing = s.spacing;
  h.source = s.type;
  for (int a = 0; a < 3; ++a)
    if (s.dims[a] <= 0) throw std::invalid_argument("every dimension must be >= 1");
  SlabWriter writer(out, h, options);
  const Prepared pre = prepare(s);
  const int64_t slab = 16;
  std::vector<uint8_t> buf(size_t(s.dims[0] * s.dims[1] * slab) * source_bytes(s.type));
  for (int64_t z0 = 0; z0 < s.dims[2]; z0 += slab) {
    const int64_t z1 = std::min(s.dims[2], z0 + slab);
    fill_slab(s, pre, z0, z1, buf.data());
    writer.write(buf.data(), size_t(s.dims[0] * s.dims[1] * (z1 - z0)) * source_bytes(s.type));
  }
  writer.close();
}

}  // namespace peakcast
