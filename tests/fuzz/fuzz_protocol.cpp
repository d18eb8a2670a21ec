// Any bytes as a WebSocket text message: parsed or refused with a ProtocolError, never a crash.
#include <cstddef>
#include <cstdint>
#include <string>

#include "session/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    peakcast::protocol::parse_client_message(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const peakcast::protocol::ProtocolError&) {
  }
  try {
    peakcast::protocol::decode_frame_header(data, size);
  } catch (const peakcast::protocol::ProtocolError&) {
  }
  return 0;
}
