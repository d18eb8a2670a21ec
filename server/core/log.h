// The server's log (spdlog): levels, and one line per event as text or as a JSON object
// (`--log-format json`: {"ts", "level", "msg", ...fields}) for log collectors. Outside text (paths,
// client messages) goes in as values, never as a format string.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace peakcast::log {

enum class Level { Debug, Info, Warn, Error, Off };
enum class Format { Text, Json };

// Throws std::invalid_argument for an unknown level or format name.
Level parse_level(std::string_view name);    // debug | info | warn | error | off
Format parse_format(std::string_view name);  // text | json
void configure(Level level, Format format);  // before the server starts; default info, text
Level level();

void write(Level level, std::string_view msg, const nlohmann::json& fields = nlohmann::json::object());
inline void debug(std::string_view m, const nlohmann::json& f = nlohmann::json::object()) { write(Level::Debug, m, f); }
inline void info(std::string_view m, const nlohmann::json& f = nlohmann::json::object()) { write(Level::Info, m, f); }
inline void warn(std::string_view m, const nlohmann::json& f = nlohmann::json::object()) { write(Level::Warn, m, f); }
inline void error(std::string_view m, const nlohmann::json& f = nlohmann::json::object()) { write(Level::Error, m, f); }

// The line written for an event (without the newline): what the tests check.
std::string format_line(Level level, std::string_view msg, const nlohmann::json& fields, Format format,
                        const std::string& timestamp);

}  // namespace peakcast::log
