// The WebSocket clients of `bench soak` (cmd_bench_soak.cpp): viewers sending random camera, TF,
// render-settings, ping and stroke messages at 60 Hz and acking their frames; a client that never
// acks; one that drops its TCP connection without a close frame, over and over, and comes back.
// Each counts what it sent, what came back and its camera -> frame latency into SoakStats.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "net/beast.h"

namespace peakcast::bench {

using SoakClock = std::chrono::steady_clock;

struct SoakStats {
  std::mutex m;
  SoakClock::time_point start;
  double window_s = 60;
  std::vector<std::vector<double>> latency_ms;  // per window: camera sent -> first frame showing it
  uint64_t sent = 0, frames = 0, expected_answers = 0, answers = 0, unexpected_errors = 0;
  uint64_t lost_sessions = 0, vanished = 0, noack_frames = 0;
  std::string first_unexpected;

  void latency(SoakClock::time_point sent_at, SoakClock::time_point now);
};

enum class SoakClientKind { Viewer, NoAck, Vanisher };

// Connects, says hello and runs on `ioc` until `end` (the vanisher reconnects until then).
void start_soak_client(net::asio::io_context& ioc, uint16_t port, SoakClientKind kind, int size, unsigned seed,
                       SoakStats& out, SoakClock::time_point end);

}  // namespace peakcast::bench
