#include "core/peaks.h"
#include "core/value_range.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace peakcast {

std::vector<Peak> find_peaks(const TransferFunction& tf) {
  std::vector<Peak> out;
  const auto& p = tf.points;
  const size_t n = p.size();
  size_t k = 0;
  while (k < n) {
    size_t e = k;  // run of equal opacity [k, e]
    while (e + 1 < n && p[e + 1].a == p[k].a) ++e;
    const bool left_lower = k > 0 && p[k - 1].a < p[k].a;
    const bool right_lower = e + 1 < n && p[e + 1].a < p[e].a;
    if (left_lower && right_lower && p[k].a > 0) {
      const double v = 0.5 * (p[k].value + p[e].value);
      out.push_back({v, tf.eval(v)});
    }
    k = e + 1;
  }
  return out;
}

int PeakTable::bin_of(double f) const {
  const double u = (f - lo) / (hi - lo) * bins;
  return std::clamp(int(std::floor(u)), 0, bins - 1);
}

PeakTable build_peak_table(const std::vector<Peak>& all, double lo, double hi, int bins) {
  const auto t0 = std::chrono::steady_clock::now();
  PeakTable t;
  t.bins = bins;
  t.lo = lo;
  t.hi = table_range(lo, hi).hi;
  std::vector<double> v;
  for (const auto& p : all)
    if (p.value > lo && p.value <= t.hi) v.push_back(p.value);  // (lo, hi]: f >= lo always
  std::sort(v.begin(), v.end());
  const double w = (t.hi - lo) / bins;
  auto start = [&](int k) { return lo + w * k; };
  auto end = [&](int k) { return k == bins - 1 ? t.hi : lo + w * (k + 1); };
  // Candidates for (i, j): values in (start(min), end(max)] = indices [first[min], last[max]].
  std::vector<int> first(static_cast<size_t>(bins)), last(static_cast<size_t>(bins));
  for (int k = 0; k < bins; ++k) {
    first[size_t(k)] = int(std::upper_bound(v.begin(), v.end(), start(k)) - v.begin());
    last[size_t(k)] = int(std::upper_bound(v.begin(), v.end(), end(k)) - v.begin()) - 1;
  }
  int most = 0;
  for (int i = 0; i < bins; ++i)
    for (int j = 0; j < bins; ++j)
      most = std::max(most, last[size_t(std::max(i, j))] - first[size_t(std::min(i, j))] + 1);
  t.layers = std::max(1, (most + 3) / 4);
  t.texels.assign(size_t(t.layers) * bins * bins * 4, PeakTable::kNoPeak);
  for (int j = 0; j < bins; ++j)
    for (int i = 0; i < bins; ++i) {
      const int a = first[size_t(std::min(i, j))], b = last[size_t(std::max(i, j))];
      const bool descending = i > j;
      for (int n = 0; n <= b - a; ++n) {
        const int idx = descending ? b - n : a + n;
        const size_t off = ((size_t(n / 4) * bins + size_t(j)) * bins + size_t(i)) * 4 + size_t(n % 4);
        t.texels[off] = v[size_t(idx)];
      }
    }
  t.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

std::vector<double> peaks_crossed(const PeakTable& t, double f0, double f1, int max_peaks) {
  const int i = t.bin_of(f0), j = t.bin_of(f1);
  const bool reverse = (i == j) && f0 > f1;  // the diagonal is stored ascending
  std::vector<double> found;
  for (int layer = 0; layer < t.layers; ++layer)
    for (int s = 0; s < 4; ++s) {
      const double v = t.texel(i, j, layer)[s];
      if (v == PeakTable::kNoPeak) goto done;
      if (crosses(f0, f1, v)) found.push_back(v);
      if (!reverse && int(found.size()) == max_peaks) goto done;
    }
done:
  if (reverse) {
    std::reverse(found.begin(), found.end());
    if (int(found.size()) > max_peaks) found.resize(size_t(max_peaks));
  }
  return found;
}

std::vector<double> peaks_crossed_exact(const std::vector<Peak>& peaks, double f0, double f1, int max_peaks) {
  std::vector<double> v;
  for (const auto& p : peaks)
    if (crosses(f0, f1, p.value)) v.push_back(p.value);
  std::sort(v.begin(), v.end());
  if (f0 > f1) std::reverse(v.begin(), v.end());
  if (int(v.size()) > max_peaks) v.resize(size_t(max_peaks));
  return v;
}

}  // namespace peakcast
