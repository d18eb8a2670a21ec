// JPEG through the TurboJPEG 2.1 API (tjInitCompress / tjCompress2). One encoder per thread:
// a TurboJPEG handle is not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace peakcast::encode {

enum class Subsampling { S444, S420 };

class JpegEncoder {
 public:
  JpegEncoder();
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  // rgb: width*height*3 bytes, row 0 at the top. Throws std::runtime_error on failure.
  std::vector<uint8_t> encode(const uint8_t* rgb, int width, int height, int quality, Subsampling sub);

 private:
  void* handle_ = nullptr;
};

// Decodes to RGB (tests and tools). Throws on corrupt data.
std::vector<uint8_t> decode_jpeg(const uint8_t* data, size_t size, int& width, int& height);

}  // namespace peakcast::encode
