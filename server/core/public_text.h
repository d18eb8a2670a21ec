// Text the server sends to a client (an error's message): well-formed UTF-8, bounded, and free of
// server paths. A library error (std::filesystem, a reader) may name a file where it lies on the
// server; here every absolute path whose first component is a folder of this machine's root
// ("/srv/data/em/x.nrrd", "/proc/self/cmdline") is cut to its last component ("x.nrrd"). Routes and
// the client's own words ("/api/volumes/x", "em/x.nrrd") pass unchanged.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace peakcast {

constexpr size_t kMaxPublicTextBytes = 2048;
std::string public_text(std::string_view message, size_t max_bytes = kMaxPublicTextBytes);

}  // namespace peakcast
