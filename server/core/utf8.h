// Bytes from outside (URLs, headers, file names, file headers, messages) are not UTF-8 until
// checked. Every string that reaches JSON goes through here: cut at character boundaries, invalid
// bytes replaced by U+FFFD, and JSON serialised with replacement, so that serialising an error
// can never throw (nlohmann's dump() throws type_error.316 on invalid UTF-8).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

namespace peakcast {

// True when `s` is well-formed UTF-8 (no overlongs, surrogates or code points past U+10FFFF).
bool valid_utf8(std::string_view s);

// `s` as well-formed UTF-8: each byte that does not start a well-formed sequence becomes U+FFFD.
// With max_bytes, the result is cut to at most that many bytes, at a character boundary.
std::string clean_utf8(std::string_view s, size_t max_bytes = std::string::npos);

// The JSON text of `j`; strings that are not UTF-8 come out with U+FFFD. Never throws for bad
// UTF-8 (only std::bad_alloc can escape).
std::string json_text(const nlohmann::json& j, int indent = -1);

}  // namespace peakcast
