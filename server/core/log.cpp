#include "core/log.h"

#include <atomic>
#include <chrono>
#include <ctime>
#include <memory>
#include <mutex>
#include <stdexcept>

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

namespace peakcast::log {
namespace {

std::atomic<Level> g_level{Level::Info};
std::atomic<Format> g_format{Format::Text};

const char* name(Level l) {
  switch (l) {
    case Level::Debug: return "debug";
    case Level::Info: return "info";
    case Level::Warn: return "warn";
    case Level::Error: return "error";
    case Level::Off: return "off";
  }
  return "info";
}

std::shared_ptr<spdlog::logger> logger() {
  // stderr, the line is already formatted: spdlog adds only the newline (and serialises writers).
  static std::shared_ptr<spdlog::logger> l = [] {
    auto lg = std::make_shared<spdlog::logger>("peakcast", std::make_shared<spdlog::sinks::stderr_sink_mt>());
    lg->set_pattern("%v");
    lg->set_level(spdlog::level::trace);
    lg->flush_on(spdlog::level::trace);
    return lg;
  }();
  return l;
}

std::string now_iso8601() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03dZ", buf, int(ms));
  return out;
}

}  // namespace

Level parse_level(std::string_view n) {
  if (n == "debug") return Level::Debug;
  if (n == "info") return Level::Info;
  if (n == "warn" || n == "warning") return Level::Warn;
  if (n == "error") return Level::Error;
  if (n == "off") return Level::Off;
  throw std::invalid_argument("log level must be debug, info, warn, error or off, not '" +
                              std::string(n.substr(0, 32)) + "'");
}

Format parse_format(std::string_view n) {
  if (n == "text") return Format::Text;
  if (n == "json") return Format::Json;
  throw std::invalid_argument("log format must be text or json, not '" + std::string(n.substr(0, 32)) + "'");
}

void configure(Level level, Format format) {
  g_level = level;
  g_format = format;
}

Level level() { return g_level; }

std::string format_line(Level level, std::string_view msg, const nlohmann::json& fields, Format format,
                        const std::string& timestamp) {
  if (format == Format::Json) {
    nlohmann::json j = {{"ts", timestamp}, {"level", name(level)}, {"msg", std::string(msg)}};
    if (fields.is_object())
      for (auto& [k, v] : fields.items())
        if (!j.contains(k)) j[k] = v;
    return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  }
  std::string line = timestamp + " " + name(level) + " " + std::string(msg);
  if (fields.is_object())
    for (auto& [k, v] : fields.items())
      line += " " + k + "=" +
              (v.is_string() ? v.get<std::string>() : v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  // One event, one line: a newline inside outside text must not forge a second entry.
  for (char& c : line)
    if (c == '\n' || c == '\r') c = ' ';
  return line;
}

void write(Level l, std::string_view msg, const nlohmann::json& fields) {
  if (l < g_level.load() || l == Level::Off) return;
  logger()->info("{}", format_line(l, msg, fields, g_format.load(), now_iso8601()));
}

}  // namespace peakcast::log
