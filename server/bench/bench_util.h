// Small helpers the benchmark commands share: order statistics, wall-clock spans, the process's
// resident memory, and one blocking HTTP request (the soak's stills and health checks).
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "net/beast.h"

namespace peakcast::bench {

double median(std::vector<double> v);                // 0 when empty
double percentile(std::vector<double> v, double p);  // p in [0, 1]; NaN when empty
double ms_between(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b);
double rss_mib();       // VmRSS of this process
double peak_rss_mib();  // VmHWM: the peak since the start or reset_peak_rss
void reset_peak_rss();  // VmHWM back to the current RSS

struct HttpAnswer {
  int status = 0;  // 0: no answer (the body holds the error)
  std::string body;
  double ms = 0;
};
// One request to 127.0.0.1:port on its own connection, JSON body.
HttpAnswer http_request(uint16_t port, net::http::verb verb, const std::string& target, const std::string& body);

}  // namespace peakcast::bench
