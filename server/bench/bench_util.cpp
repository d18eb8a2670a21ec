#include "bench/bench_util.h"

#include <algorithm>
#include <cmath>
#include <fstream>

namespace peakcast::bench {

using namespace peakcast::net;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

namespace {

double status_mib(const char* key) {  // a "Vm...:" line of /proc/self/status, in MiB
  std::ifstream in("/proc/self/status");
  const std::string prefix = std::string(key) + ":";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(prefix, 0) == 0) return std::stod(line.substr(prefix.size())) / 1024.0;
  return 0.0;
}

}  // namespace

double rss_mib() { return status_mib("VmRSS"); }
double peak_rss_mib() { return status_mib("VmHWM"); }
void reset_peak_rss() { std::ofstream("/proc/self/clear_refs") << "5"; }

HttpAnswer http_request(uint16_t port, http::verb verb, const std::string& target, const std::string& body) {
  HttpAnswer a;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    asio::io_context ioc;
    beast::tcp_stream s(ioc);
    s.expires_after(std::chrono::seconds(300));
    s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
    http::request<http::string_body> req{verb, target, 11};
    req.set(http::field::host, "127.0.0.1");
    req.set(http::field::content_type, "application/json");
    req.body() = body;
    req.prepare_payload();
    http::write(s, req);
    beast::flat_buffer buf;
    http::response<http::string_body> res;
    http::read(s, buf, res);
    a.status = int(res.result_int());
    a.body = std::move(res.body());
  } catch (const std::exception& e) {
    a.body = e.what();
  }
  a.ms = ms_between(t0, std::chrono::steady_clock::now());
  return a;
}

}  // namespace peakcast::bench
