// A DICOM series' slices as a grid: ordered along the slice normal, evenly spaced, untilted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include <glm/geometric.hpp>

#include "core/dicom.h"

namespace fs = std::filesystem;

namespace peakcast::dicom {
namespace {

std::string mm(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.4g mm", v);
  return buf;
}

std::string name(const SliceHeader& s) { return s.file.filename().string(); }

void check_alike(const fs::path& dir, const std::vector<SliceHeader>& slices) {
  const SliceHeader& a = slices[0];
  for (const SliceHeader& s : slices) {
    if (s.rows != a.rows || s.cols != a.cols)
      throw VolumeError(dir, "slices of different sizes: " + name(a) + " is " + std::to_string(a.cols) + "x" +
                                 std::to_string(a.rows) + ", " + name(s) + " " + std::to_string(s.cols) + "x" +
                                 std::to_string(s.rows));
    if (glm::length(s.row - a.row) > 1e-4 || glm::length(s.col - a.col) > 1e-4)
      throw VolumeError(dir, "slices of different orientations (ImageOrientationPatient): " + name(a) + " and " +
                                 name(s) + "; one series is one orientation");
    if (std::abs(s.row_spacing - a.row_spacing) > 1e-4 * a.row_spacing ||
        std::abs(s.col_spacing - a.col_spacing) > 1e-4 * a.col_spacing)
      throw VolumeError(dir, "slices of different pixel spacings: " + name(a) + " and " + name(s));
    if (slices.size() > 1 && !s.has_position)
      throw VolumeError(dir, name(s) + " has no ImagePositionPatient: the slices cannot be ordered");
  }
}

}  // namespace

SeriesGeometry order_slices(const fs::path& dir, const std::vector<SliceHeader>& slices) {
  if (slices.empty()) throw VolumeError(dir, "no DICOM slices");
  check_alike(dir, slices);
  SeriesGeometry g;
  g.order.resize(slices.size());
  std::iota(g.order.begin(), g.order.end(), size_t(0));
  const glm::dvec3 normal = glm::normalize(glm::cross(slices[0].row, slices[0].col));
  std::vector<double> d(slices.size());
  for (size_t i = 0; i < slices.size(); ++i) d[i] = glm::dot(slices[i].position, normal);
  std::stable_sort(g.order.begin(), g.order.end(), [&](size_t a, size_t b) { return d[a] < d[b]; });
  g.origin = slices[g.order[0]].position;
  if (slices.size() == 1) {
    g.gap = slices[0].thickness > 0 ? slices[0].thickness : 1.0;
    return g;
  }
  const size_t n = slices.size();
  g.gap = (d[g.order[n - 1]] - d[g.order[0]]) / double(n - 1);
  std::vector<double> gaps(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) {
    gaps[i] = d[g.order[i + 1]] - d[g.order[i]];
    if (gaps[i] <= 1e-6 * std::max(1.0, std::abs(g.gap)))
      throw VolumeError(dir, "two slices at one position: " + name(slices[g.order[i]]) + " and " +
                                 name(slices[g.order[i + 1]]) +
                                 " (a series of several acquisitions; open one of them)");
  }
  std::vector<double> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + long(sorted.size() / 2), sorted.end());
  const double usual = sorted[sorted.size() / 2];
  size_t worst = 0;  // the gap furthest from the usual one
  for (size_t i = 0; i < gaps.size(); ++i)
    if (std::abs(gaps[i] - usual) > std::abs(gaps[worst] - usual)) worst = i;
  if (std::abs(gaps[worst] - usual) > 0.01 * usual)
    throw VolumeError(dir, "uneven slice spacing: a gap of " + mm(gaps[worst]) + " between " +
                               name(slices[g.order[worst]]) + " and " + name(slices[g.order[worst + 1]]) +
                               " where the others are " + mm(usual) +
                               " (missing slices?); peakcast draws evenly spaced slices only");
  for (size_t i = 0; i + 1 < n; ++i) {
    const SliceHeader &a = slices[g.order[i]], &b = slices[g.order[i + 1]];
    const double shift = glm::length(b.position - a.position - gaps[i] * normal);
    if (shift > 0.01 * gaps[i]) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.2f", std::atan2(shift, gaps[i]) * 180.0 / M_PI);
      throw VolumeError(dir, "gantry tilt: each slice is shifted " + mm(shift) + " in its plane (" + buf +
                                 " degrees, between " + name(a) + " and " + name(b) +
                                 "); peakcast draws untilted grids only (resample the series first)");
    }
  }
  return g;
}

SeriesPath split_series_path(const fs::path& path) {
  std::error_code ec;
  const std::string s = path.string();
  const size_t hash = s.rfind('#');
  if (fs::exists(path, ec) || hash == std::string::npos || s.find('/', hash) != std::string::npos) return {path, ""};
  return {fs::path(s.substr(0, hash)), s.substr(hash + 1)};
}

}  // namespace peakcast::dicom
