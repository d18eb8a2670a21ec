// Any bytes as the text of an error (a client's words, a reader's message, a path): every way the
// server serialises an error gives valid UTF-8 JSON that parses back, without a server path, and
// never throws. This is the guarantee that no error can end the process (nlohmann's dump()
// throws on invalid UTF-8).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "core/public_text.h"
#include "core/utf8.h"
#include "session/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string in(reinterpret_cast<const char*>(data), size);
  const std::string cut = peakcast::clean_utf8(in, size / 2);
  if (!peakcast::valid_utf8(cut) || cut.size() > size / 2) std::abort();
  const std::string text = peakcast::public_text(in);
  if (!peakcast::valid_utf8(text) || text.size() > peakcast::kMaxPublicTextBytes) std::abort();
  const std::string rest = peakcast::json_text(nlohmann::json{{"error", in}, {"message", text}});
  const std::string ws = peakcast::protocol::error_message(in.substr(0, 16), in);
  for (const std::string* j : {&rest, &ws}) {
    if (!peakcast::valid_utf8(*j)) std::abort();
    if (nlohmann::json::parse(*j, nullptr, false).is_discarded()) std::abort();
  }
  return 0;
}
