// The output of `bench quality` (docs/accuracy.md): error against run time per scene and method, as
// report.csv, report.md and one SVG plot per scene. No rendering here: rows in, files out.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace peakcast::bench {

struct QualityRow {
  std::string scene, method;  // method: <classification>/<sampling>/<filter>[/vs3|/vs7][/adaptive]
  std::string knob;           // "step" or "s_k"
  double value = 0;           // the knob's value
  double ms = 0, samples_per_ray = 0;
  double rmse = 0, psnr = 0, max_abs = 0, share_off = 0;  // against the method's own optical model
  double psnr_other = -1;                                 // against the other optical model where meaningful (-1: none)
  std::string image;                                      // PNG path relative to the output directory, or empty
};

struct ConvergedTime {
  std::string scene, model;  // model: "dvr/trilinear", "peaks/tricubic", ...
  double ms = 0, step = 0, last_change = 0;
};

struct Omission {
  std::string scene, left_out, chosen_variant, full_variant;
  double chosen_ms = 0, full_ms = 0;
};

// Least-squares slope of log(rmse) over log(knob) for one scene and method (NaN below 2 points).
double observed_order(const std::vector<QualityRow>& rows, const std::string& scene, const std::string& method);
// The order the method's construction should show: 1 for a Riemann sum of the absorption
// integral, 2 for preintegration (exact per segment for a field linear along it).
double expected_order(const std::string& method);

void write_csv(const std::filesystem::path& file, const std::vector<QualityRow>& rows);
void write_markdown(const std::filesystem::path& file, const std::vector<QualityRow>& rows,
                    const std::vector<ConvergedTime>& references, const std::vector<Omission>& omissions,
                    const std::string& machine);
// Error (RMSE) against time (ms), log-log, a line per method; the converged references' times
// as dashed vertical lines.
void write_svg(const std::filesystem::path& file, const std::string& scene, const std::vector<QualityRow>& rows,
               const std::vector<ConvergedTime>& references);

}  // namespace peakcast::bench
