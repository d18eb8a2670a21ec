// What a request's text says, read without trusting it: the path and query of a target, a bearer
// token, a Host header against the allow-list. Pure functions of strings (no sockets, no Beast):
// the fuzz targets call them directly (tests/fuzz/fuzz_http_text.cpp).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace peakcast::net {

// Bearer token from "Authorization: Bearer X" or the query "?token=X"; empty when absent.
std::string token_from(const std::string& authorization, const std::string& target);
std::string path_of(const std::string& target);  // target without the query
std::string query_param(const std::string& target, const std::string& key);
std::string url_decode(const std::string& s);  // %XX and '+' (a query's space)

// An upload's raw-voxel header from its query (dims=X,Y,Z&dtype=..&spacing=..&origin=..&endian=..):
// numbers where the text is one, the text otherwise (refused by name by raw_sidecar). Nothing
// when the query has no dims.
std::optional<nlohmann::json> raw_header_from_query(const std::string& target);

// a == b in time that depends only on their lengths, not on where they differ.
bool tokens_equal(std::string_view a, std::string_view b);

// The host name of a Host header, lower case, without its port or an IPv6 literal's brackets:
// "Example.org:8080" -> "example.org", "[::1]:80" -> "::1". Empty for a malformed header.
std::string host_name(std::string_view host_header);
bool is_ip_literal(std::string_view name);

// Which Host headers the server answers (DNS rebinding: a page from another name must not reach
// it). `names`: the operator's --allowed-host list ("*": any). Always allowed: `bind` (the listen
// address), localhost and the loopback addresses; when bound to every interface (0.0.0.0, ::),
// any IP literal too (rebinding needs a name). An absent Host header is allowed (not a browser).
class HostCheck {
 public:
  HostCheck() = default;
  HostCheck(std::string bind, std::vector<std::string> names);
  bool allowed(std::string_view host_header) const;

 private:
  std::string bind_;
  std::vector<std::string> names_;
  bool any_ = false, any_ip_ = false;
};

}  // namespace peakcast::net
