// Any bytes as an upload: its body sniffed (NRRD, MetaImage, TIFF, or refused), taken apart as
// multipart/form-data (the first line is the Content-Type), its JSON raw header checked against
// its size, its name cleaned. Refused with an UploadRefusal or accepted, never a crash; a cleaned
// name is UTF-8 within the length limit.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/utf8.h"
#include "session/upload_formats.h"
#include "session/upload_store.h"

namespace fs = std::filesystem;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fs::path dir = [] {
    auto d = fs::temp_directory_path() / ("peakcast_fuzz_upload_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
  }();
  const std::string in(reinterpret_cast<const char*>(data), size);
  const fs::path body = dir / "body", out = dir / "data";
  auto put = [&](const std::string& bytes) {
    std::ofstream(body, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  };
  put(in);
  try {
    (void)peakcast::sniff_upload(body, false);
  } catch (const peakcast::UploadRefusal&) {
  }
  const auto nl = in.find('\n');
  put(nl == std::string::npos ? "" : in.substr(nl + 1));
  try {
    (void)peakcast::split_multipart(body, in.substr(0, nl), out);
  } catch (const peakcast::UploadRefusal&) {
  }
  const nlohmann::json header = nlohmann::json::parse(in, nullptr, false);
  if (!header.is_discarded()) {
    try {
      const auto sidecar = peakcast::raw_sidecar(header, "x.raw");
      peakcast::check_raw_body(sidecar, int64_t(size));
    } catch (const peakcast::UploadRefusal&) {
    }
  }
  const std::string name = peakcast::clean_upload_name(in);
  if (name.empty() || name.size() > peakcast::limits::kMaxUploadNameLength || !peakcast::valid_utf8(name)) std::abort();
  return 0;
}
