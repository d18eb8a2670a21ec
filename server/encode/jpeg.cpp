#include "encode/jpeg.h"

#include <turbojpeg.h>

#include <stdexcept>
#include <string>

namespace peakcast::encode {

JpegEncoder::JpegEncoder() : handle_(tjInitCompress()) {
  if (!handle_) throw std::runtime_error("tjInitCompress failed");
}

JpegEncoder::~JpegEncoder() {
  if (handle_) tjDestroy(handle_);
}

std::vector<uint8_t> JpegEncoder::encode(const uint8_t* rgb, int width, int height, int quality, Subsampling sub) {
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int samp = sub == Subsampling::S444 ? TJSAMP_444 : TJSAMP_420;
  if (tjCompress2(handle_, rgb, width, 0, height, TJPF_RGB, &out, &size, samp, quality, TJFLAG_FASTDCT) != 0) {
    std::string err = tjGetErrorStr2(handle_);
    if (out) tjFree(out);
    throw std::runtime_error("JPEG encode failed: " + err);
  }
  std::vector<uint8_t> bytes(out, out + size);
  tjFree(out);
  return bytes;
}

std::vector<uint8_t> decode_jpeg(const uint8_t* data, size_t size, int& width, int& height) {
  tjhandle h = tjInitDecompress();
  if (!h) throw std::runtime_error("tjInitDecompress failed");
  int sub = 0, colorspace = 0;
  if (tjDecompressHeader3(h, data, (unsigned long)size, &width, &height, &sub, &colorspace) != 0) {
    std::string err = tjGetErrorStr2(h);
    tjDestroy(h);
    throw std::runtime_error("JPEG header: " + err);
  }
  std::vector<uint8_t> rgb(size_t(width) * height * 3);
  if (tjDecompress2(h, data, (unsigned long)size, rgb.data(), width, 0, height, TJPF_RGB, 0) != 0) {
    std::string err = tjGetErrorStr2(h);
    tjDestroy(h);
    throw std::runtime_error("JPEG decode: " + err);
  }
  tjDestroy(h);
  return rgb;
}

}  // namespace peakcast::encode
