#include "bench/quality_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

namespace peakcast::bench {
namespace {

std::ofstream open_out(const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  return out;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// Methods of a scene, in first-seen order.
std::vector<std::string> methods_of(const std::vector<QualityRow>& rows, const std::string& scene) {
  std::vector<std::string> m;
  for (const auto& r : rows)
    if (r.scene == scene && std::find(m.begin(), m.end(), r.method) == m.end()) m.push_back(r.method);
  return m;
}

std::string escape_xml(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else
      o += c;
  }
  return o;
}

}  // namespace

double observed_order(const std::vector<QualityRow>& rows, const std::string& scene, const std::string& method) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const auto& r : rows)
    if (r.scene == scene && r.method == method && r.rmse > 0 && r.value > 0) {
      const double x = std::log(r.value), y = std::log(r.rmse);
      sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
    }
  if (n < 2) return std::numeric_limits<double>::quiet_NaN();
  const double d = n * sxx - sx * sx;
  return d > 0 ? (n * sxy - sx * sy) / d : std::numeric_limits<double>::quiet_NaN();
}

// Each sample stands for its chord (docs/scenes.md), so uniform DVR sampling is the midpoint rule
// (order 2), as preintegration is; adaptive multipliers take a cell's steps from its first point
// (order 1), and peak finding's error is the root's and the hit's, not the integral's.
double expected_order(const std::string& method) {
  if (method.rfind("peaks/", 0) == 0 || method.find("/adaptive") != std::string::npos) return 1.0;
  return 2.0;
}

void write_csv(const std::filesystem::path& file, const std::vector<QualityRow>& rows) {
  auto out = open_out(file);
  out << "scene,method,knob,step,ms,samples_per_ray,rmse,psnr,max_abs,share_off,image\n";
  for (const auto& r : rows)
    out << r.scene << ',' << r.method << ',' << r.knob << ',' << fmt("%.6g", r.value) << ',' << fmt("%.4f", r.ms) << ','
        << fmt("%.3f", r.samples_per_ray) << ',' << fmt("%.6e", r.rmse) << ',' << fmt("%.3f", r.psnr) << ','
        << fmt("%.6e", r.max_abs) << ',' << fmt("%.6f", r.share_off) << ',' << r.image << '\n';
}

void write_markdown(const std::filesystem::path& file, const std::vector<QualityRow>& rows,
                    const std::vector<ConvergedTime>& references, const std::vector<Omission>& omissions,
                    const std::string& machine) {
  auto out = open_out(file);
  out << "# Error against run time\n\n"
      << machine << "\n\n"
      << "Error is against the converged image (CPU, double) of the method's own optical model: the DVR model "
         "for post and preint, the peak model for peaks; `other` is the PSNR against the other model where the "
         "TF has peaks. ms: median GPU time of a frame. Order: slope of log RMSE over log step (or s_k).\n";
  std::vector<std::string> scenes;
  for (const auto& r : rows)
    if (std::find(scenes.begin(), scenes.end(), r.scene) == scenes.end()) scenes.push_back(r.scene);
  for (const auto& scene : scenes) {
    out << "\n## " << scene << "\n\n![" << scene << "](" << scene << ".svg)\n\n";
    out << "| method | knob | value | ms | samples/ray | RMSE | PSNR dB | max abs | share off | other dB |\n"
        << "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
      if (r.scene == scene)
        out << "| " << r.method << " | " << r.knob << " | " << fmt("%g", r.value) << " | " << fmt("%.2f", r.ms) << " | "
            << fmt("%.1f", r.samples_per_ray) << " | " << fmt("%.2e", r.rmse) << " | " << fmt("%.1f", r.psnr) << " | "
            << fmt("%.3f", r.max_abs) << " | " << fmt("%.3f", r.share_off) << " | "
            << (r.psnr_other >= 0 ? fmt("%.1f", r.psnr_other) : "–") << " |\n";
    out << "\n| method | observed order | expected |\n|---|---|---|\n";
    for (const auto& m : methods_of(rows, scene))
      out << "| " << m << " | " << fmt("%.2f", observed_order(rows, scene, m)) << " | "
          << fmt("%.0f", expected_order(m)) << " |\n";
    out << "\nConverged references: ";
    bool first = true;
    for (const auto& c : references)
      if (c.scene == scene) {
        out << (first ? "" : "; ") << c.model << " " << fmt("%.0f", c.ms) << " ms (step " << fmt("%.4g", c.step)
            << ", last change " << fmt("%.1e", c.last_change) << ")";
        first = false;
      }
    out << "\n";
  }
  if (!omissions.empty()) {
    out << "\n## What leaving code out saves\n\n| scene | left out | chosen variant | ms | with the code | ms | saved "
           "|\n"
        << "|---|---|---|---|---|---|---|\n";
    for (const auto& o : omissions)
      out << "| " << o.scene << " | " << o.left_out << " | " << o.chosen_variant << " | " << fmt("%.2f", o.chosen_ms)
          << " | " << o.full_variant << " | " << fmt("%.2f", o.full_ms) << " | "
          << fmt("%.0f%%", 100.0 * (1.0 - o.chosen_ms / o.full_ms)) << " |\n";
  }
}

void write_svg(const std::filesystem::path& file, const std::string& scene, const std::vector<QualityRow>& rows,
               const std::vector<ConvergedTime>& references) {
  double t0 = 1e300, t1 = 0, e0 = 1e300, e1 = 0;
  for (const auto& r : rows)
    if (r.scene == scene && r.rmse > 0 && r.ms > 0)
      t0 = std::min(t0, r.ms), t1 = std::max(t1, r.ms), e0 = std::min(e0, r.rmse), e1 = std::max(e1, r.rmse);
  for (const auto& c : references)
    if (c.scene == scene && c.ms > 0) t1 = std::max(t1, c.ms), t0 = std::min(t0, c.ms);
  if (t1 <= 0 || e1 <= 0) {
    t0 = 1, t1 = 10, e0 = 1e-3, e1 = 1e-1;
  }
  const double lt0 = std::floor(std::log10(t0)), lt1 = std::ceil(std::log10(t1) + 1e-9);
  const double le0 = std::floor(std::log10(e0)), le1 = std::ceil(std::log10(e1) + 1e-9);
  const double W = 760, H = 480, L = 70, R = 220, T = 40, B = 50;
  auto X = [&](double t) { return L + (std::log10(t) - lt0) / std::max(lt1 - lt0, 1.0) * (W - L - R); };
  auto Y = [&](double e) { return T + (le1 - std::log10(e)) / std::max(le1 - le0, 1.0) * (H - T - B); };
  static const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e",
                                  "#17becf", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22"};
  auto out = open_out(file);
  out << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' font-family='sans-serif' "
      << "font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='" << L << "' y='22' font-size='15'>" << escape_xml(scene)
      << ": RMSE against the converged image vs frame time</text>\n";
  for (double p = lt0; p <= lt1; ++p)
    out << "<line x1='" << X(std::pow(10, p)) << "' y1='" << T << "' x2='" << X(std::pow(10, p)) << "' y2='" << H - B
        << "' stroke='#ddd'/><text x='" << X(std::pow(10, p)) - 12 << "' y='" << H - B + 16 << "'>1e" << p
        << "</text>\n";
  for (double p = le0; p <= le1; ++p)
    out << "<line x1='" << L << "' y1='" << Y(std::pow(10, p)) << "' x2='" << W - R << "' y2='" << Y(std::pow(10, p))
        << "' stroke='#ddd'/><text x='" << 22 << "' y='" << Y(std::pow(10, p)) + 4 << "'>1e" << p << "</text>\n";
  out << "<text x='" << (L + W - R) / 2 - 40 << "' y='" << H - 12 << "'>frame time (ms, log)</text>\n"
      << "<text x='14' y='" << T - 10 << "'>RMSE (log)</text>\n";
  size_t k = 0;
  for (const auto& m : methods_of(rows, scene)) {
    const char* c = colours[k % std::size(colours)];
    std::vector<std::pair<double, double>> pts;
    for (const auto& r : rows)
      if (r.scene == scene && r.method == m && r.rmse > 0 && r.ms > 0) pts.push_back({r.ms, r.rmse});
    std::sort(pts.begin(), pts.end());
    out << "<polyline fill='none' stroke='" << c << "' stroke-width='1.8' points='";
    for (const auto& [t, e] : pts) out << X(t) << ',' << Y(e) << ' ';
    out << "'/>\n";
    for (const auto& [t, e] : pts)
      out << "<circle cx='" << X(t) << "' cy='" << Y(e) << "' r='3' fill='" << c << "'/>\n";
    out << "<line x1='" << W - R + 12 << "' y1='" << T + 14 + 18 * k << "' x2='" << W - R + 32 << "' y2='"
        << T + 14 + 18 * k << "' stroke='" << c << "' stroke-width='2'/><text x='" << W - R + 36 << "' y='"
        << T + 18 + 18 * k << "'>" << escape_xml(m) << "</text>\n";
    ++k;
  }
  int marked = 0;
  for (const auto& r : references)
    if (r.scene == scene && r.ms > 0) {
      // Labels run up along their line, staggered so lines at nearly one time stay readable.
      out << "<line x1='" << X(r.ms) << "' y1='" << T << "' x2='" << X(r.ms) << "' y2='" << H - B
          << "' stroke='black' stroke-dasharray='5,4'/><text transform='translate(" << X(r.ms) - 3 << ","
          << T + 6 + 120 * (marked++ % 3) << ") rotate(-90)' text-anchor='end' font-size='11'>converged "
          << escape_xml(r.model) << "</text>\n";
    }
  out << "</svg>\n";
}

}  // namespace peakcast::bench
