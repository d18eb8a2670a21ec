// Counters, gauges and histograms exposed as Prometheus text (GET /metrics). Thread-safe;
// declared next to the code that updates them through the one registry.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace peakcast {

class Histogram {
 public:
  explicit Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)), counts_(bounds_.size() + 1, 0) {}
  void observe(double v);
  void render(std::string& out, const std::string& name, const std::string& labels) const;

 private:
  mutable std::mutex m_;
  std::vector<double> bounds_;
  std::vector<uint64_t> counts_;
  double sum_ = 0;
  uint64_t count_ = 0;
};

class Metrics {
 public:
  Metrics();
  // name{labels} -> value; `help` is printed once per name.
  void add(const std::string& name, const std::string& labels, double delta);
  void set(const std::string& name, const std::string& labels, double value);
  void observe(const std::string& name, const std::string& labels, double value);  // milliseconds histograms
  std::string prometheus_text() const;
  double value(const std::string& name, const std::string& labels = "") const;

 private:
  struct Family {
    std::string type, help;
    std::map<std::string, double> values;
    std::map<std::string, std::unique_ptr<Histogram>> histograms;
  };
  mutable std::mutex m_;
  std::map<std::string, Family> families_;
};

}  // namespace peakcast
