#include "net/http_text.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include <arpa/inet.h>

namespace peakcast::net {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::string path_of(const std::string& target) { return target.substr(0, target.find('?')); }

std::string query_param(const std::string& target, const std::string& key) {
  const auto q = target.find('?');
  if (q == std::string::npos) return "";
  size_t i = q + 1;
  while (i < target.size()) {
    size_t amp = target.find('&', i);
    if (amp == std::string::npos) amp = target.size();
    const std::string pair = target.substr(i, amp - i);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) == key) return eq == std::string::npos ? "" : pair.substr(eq + 1);
    i = amp + 1;
  }
  return "";
}

std::string url_decode(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '+') {
      out += ' ';
    } else if (s[i] == '%' && i + 2 < s.size() && hex_value(s[i + 1]) >= 0 && hex_value(s[i + 2]) >= 0) {
      out += char(hex_value(s[i + 1]) * 16 + hex_value(s[i + 2]));
      i += 2;
    } else {
      out += s[i];
    }
  }
  return out;
}

std::string token_from(const std::string& authorization, const std::string& target) {
  const std::string prefix = "Bearer ";
  if (authorization.rfind(prefix, 0) == 0) return authorization.substr(prefix.size());
  return url_decode(query_param(target, "token"));
}

std::optional<nlohmann::json> raw_header_from_query(const std::string& target) {
  if (query_param(target, "dims").empty()) return std::nullopt;
  auto numbers = [&](const std::string& key) {
    const std::string text = url_decode(query_param(target, key));
    nlohmann::json out = nlohmann::json::array();
    for (size_t i = 0; i <= text.size() && out.size() < 16;) {
      size_t e = text.find(',', i);
      if (e == std::string::npos) e = text.size();
      const std::string part = text.substr(i, e - i);
      try {
        size_t used = 0;
        const double v = std::stod(part, &used);
        if (used != part.size() || !std::isfinite(v)) throw std::invalid_argument(part);
        if (part.find_first_of(".eE") == std::string::npos && std::fabs(v) < 9e15)
          out.push_back(int64_t(v));
        else
          out.push_back(v);
      } catch (const std::exception&) {
        out.push_back(part);  // refused by name later, as any wrong header value
      }
      i = e + 1;
    }
    return out;
  };
  nlohmann::json h = nlohmann::json::object();
  h["dims"] = numbers("dims");
  for (const char* key : {"spacing", "origin"})
    if (!query_param(target, key).empty()) h[key] = numbers(key);
  if (!query_param(target, "times").empty()) {
    const nlohmann::json t = numbers("times");
    h["times"] = t.size() == 1 ? t[0] : t;  // a list is refused by name, as any wrong value
  }
  for (const char* key : {"dtype", "endian", "units"})
    if (const std::string v = url_decode(query_param(target, key)); !v.empty()) h[key] = v;
  return h;
}

bool tokens_equal(std::string_view a, std::string_view b) {
  // Every byte of the longer string is visited whatever the contents; only the lengths show.
  const size_t n = std::max(a.size(), b.size());
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned char>(x ^ y);
  }
  return diff == 0;
}

std::string host_name(std::string_view h) {
  while (!h.empty() && (h.back() == ' ' || h.back() == '\t')) h.remove_suffix(1);
  while (!h.empty() && (h.front() == ' ' || h.front() == '\t')) h.remove_prefix(1);
  if (h.empty()) return "";
  std::string_view name, port;
  if (h.front() == '[') {  // [v6]:port
    const auto close = h.find(']');
    if (close == std::string_view::npos) return "";
    name = h.substr(1, close - 1);
    port = h.substr(close + 1);
  } else {
    const auto colon = h.find(':');
    name = h.substr(0, colon);
    if (colon != std::string_view::npos) port = h.substr(colon);
  }
  if (!port.empty()) {  // ":digits"
    if (port.front() != ':' || port.size() < 2 || port.size() > 6) return "";
    for (char c : port.substr(1))
      if (c < '0' || c > '9') return "";
  }
  if (name.empty()) return "";
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (!(std::isalnum(u) || c == '-' || c == '.' || c == '_' || c == ':')) return "";
  }
  std::string out = lower(name);
  if (out.back() == '.') out.pop_back();  // "localhost." is localhost
  return out;
}

bool is_ip_literal(std::string_view name) {
  const std::string s(name);
  unsigned char buf[16];
  return inet_pton(AF_INET, s.c_str(), buf) == 1 || inet_pton(AF_INET6, s.c_str(), buf) == 1;
}

HostCheck::HostCheck(std::string bind, std::vector<std::string> names) : bind_(lower(bind)) {
  for (auto& n : names) {
    if (n == "*")
      any_ = true;
    else
      names_.push_back(host_name(n));
  }
  any_ip_ = bind_ == "0.0.0.0" || bind_ == "::" || bind_.empty();
}

bool HostCheck::allowed(std::string_view header) const {
  if (any_ || header.empty()) return true;
  const std::string name = host_name(header);
  if (name.empty()) return false;
  if (name == "localhost" || name == "127.0.0.1" || name == "::1" || name == bind_) return true;
  if (any_ip_ && is_ip_literal(name)) return true;
  return std::find(names_.begin(), names_.end(), name) != names_.end();
}

}  // namespace peakcast::net
