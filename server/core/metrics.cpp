#include "core/metrics.h"

#include <cmath>
#include <sstream>

namespace peakcast {

namespace {
const std::vector<double> kMsBuckets = {1, 2, 5, 10, 20, 35, 50, 75, 100, 150, 200, 300, 500, 750, 1000, 2000, 5000};

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string with_le(const std::string& labels, const std::string& le) {
  return "{" + labels + (labels.empty() ? "" : ",") + "le=\"" + le + "\"}";
}
}  // namespace

void Histogram::observe(double v) {
  std::lock_guard lock(m_);
  size_t b = 0;
  while (b < bounds_.size() && v > bounds_[b]) ++b;
  counts_[b]++;
  sum_ += v;
  count_++;
}

void Histogram::render(std::string& out, const std::string& name, const std::string& labels) const {
  std::lock_guard lock(m_);
  uint64_t cum = 0;
  for (size_t b = 0; b < bounds_.size(); ++b) {
    cum += counts_[b];
    out += name + "_bucket" + with_le(labels, fmt(bounds_[b])) + " " + std::to_string(cum) + "\n";
  }
  cum += counts_.back();
  out += name + "_bucket" + with_le(labels, "+Inf") + " " + std::to_string(cum) + "\n";
  const std::string l = labels.empty() ? "" : "{" + labels + "}";
  out += name + "_sum" + l + " " + fmt(sum_) + "\n";
  out += name + "_count" + l + " " + std::to_string(count_) + "\n";
}

Metrics::Metrics() {
  auto def = [&](const char* name, const char* type, const char* help) {
    families_[name].type = type;
    families_[name].help = help;
  };
  def("peakcast_sessions", "gauge", "WebSocket sessions open");
  def("peakcast_frames_sent_total", "counter", "Frames written to clients, by kind");
  def("peakcast_frames_dropped_total", "counter", "Encoded frames replaced by a newer one before they were sent");
  def("peakcast_bytes_sent_total", "counter", "Frame bytes written to clients");
  def("peakcast_render_ms", "histogram", "GPU render time per frame, milliseconds");
  def("peakcast_encode_ms", "histogram", "Image encode time per frame, milliseconds");
  def("peakcast_input_to_sent_ms", "histogram", "Client input received to frame written, milliseconds, by kind");
  def("peakcast_http_requests_total", "counter", "REST requests by route and status");
  def("peakcast_ws_errors_total", "counter", "Error replies sent on WebSocket sessions, by code");
  def("peakcast_gpu_volumes", "gauge", "Volumes resident on the GPU");
  def("peakcast_stills_queued", "gauge", "REST stills waiting or rendering");
  def("peakcast_still_wait_ms", "histogram", "REST still: queued to first band rendered, milliseconds");
  def("peakcast_stills_total", "counter",
      "REST stills by outcome (done, refused_queue, refused_cost, cancelled, shutting_down, render_failed)");
  def("peakcast_connections", "gauge", "Open TCP connections (HTTP and WebSocket)");
  def("peakcast_connections_refused_total", "counter", "TCP connections closed at accept: connection caps reached");
  def("peakcast_ws_paced_total", "counter", "WebSocket reads delayed by the per-client message rate");
  def("peakcast_ws_write_timeouts_total", "counter", "WebSocket clients closed because a write did not finish in time");
  def("peakcast_gpu_volume_bytes", "gauge", "Bytes of volume textures resident on the GPU");
}

void Metrics::add(const std::string& name, const std::string& labels, double delta) {
  std::lock_guard lock(m_);
  auto& f = families_[name];
  if (f.type.empty()) f.type = "counter";
  f.values[labels] += delta;
}

void Metrics::set(const std::string& name, const std::string& labels, double value) {
  std::lock_guard lock(m_);
  auto& f = families_[name];
  if (f.type.empty()) f.type = "gauge";
  f.values[labels] = value;
}

void Metrics::observe(const std::string& name, const std::string& labels, double value) {
  Histogram* h;
  {
    std::lock_guard lock(m_);
    auto& f = families_[name];
    if (f.type.empty()) f.type = "histogram";
    auto& slot = f.histograms[labels];
    if (!slot) slot = std::make_unique<Histogram>(kMsBuckets);
    h = slot.get();
  }
  h->observe(value);
}

double Metrics::value(const std::string& name, const std::string& labels) const {
  std::lock_guard lock(m_);
  auto it = families_.find(name);
  if (it == families_.end()) return 0.0;
  auto v = it->second.values.find(labels);
  return v == it->second.values.end() ? 0.0 : v->second;
}

std::string Metrics::prometheus_text() const {
  std::lock_guard lock(m_);
  std::string out;
  for (const auto& [name, f] : families_) {
    out += "# HELP " + name + " " + (f.help.empty() ? name : f.help) + "\n";
    out += "# TYPE " + name + " " + f.type + "\n";
    if (f.type == "histogram") {
      for (const auto& [labels, h] : f.histograms) h->render(out, name, labels);
    } else {
      if (f.values.empty()) out += name + " 0\n";
      for (const auto& [labels, v] : f.values)
        out += name + (labels.empty() ? "" : "{" + labels + "}") + " " + fmt(v) + "\n";
    }
  }
  return out;
}

}  // namespace peakcast
