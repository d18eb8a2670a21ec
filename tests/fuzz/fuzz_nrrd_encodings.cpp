// Any bytes as the attached data of a NRRD in one of its decoded encodings (txt, hex, bzip2, gzip),
// with a byte skip of 0, -1 or 7 and a type (the first byte picks): loaded as a 16^3 volume
// (4096 voxels, the limit) or refused with a VolumeError. The output is bounded: the decoders
// never size a buffer from the stream (fuzz_nrrd_encodings.options caps every allocation), and a
// stream decoding to more than its volume is stopped, so a bzip2 or gzip bomb is a finding only
// if it takes long.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_enc_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  static const char* encodings[] = {"txt", "hex", "bzip2", "gzip"};
  static const char* skips[] = {"0", "-1", "7"};
  static const char* types[] = {"uint8", "int16", "float"};
  const uint8_t pick = data[0];
  const std::string header = std::string("NRRD0004\ntype: ") + types[(pick >> 4) % 3] +
                             "\ndimension: 3\nsizes: 16 16 16\nencoding: " + encodings[pick & 3] +
                             "\nbyte skip: " + skips[(pick >> 2) % 3] + "\n\n";
  std::string file = header;
  file.append(reinterpret_cast<const char*>(data + 1), size - 1);
  fuzz_load(dir / "h.nrrd", reinterpret_cast<const uint8_t*>(file.data()), file.size());
  return 0;
}
