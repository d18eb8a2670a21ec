#include "core/volume_writer.h"

#include <zlib.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast {

struct SlabWriter::Impl {
  fs::path path;
  VolumeHeader header;
  FILE* raw = nullptr;
  gzFile gz = nullptr;
  size_t written = 0, expected = 0;
};

namespace {

std::string nrrd_type(SourceType t) {
  switch (t) {
    case SourceType::U8: return "uint8";
    case SourceType::I8: return "int8";
    case SourceType::U16: return "uint16";
    case SourceType::I16: return "int16";
    case SourceType::F32: return "float";
  }
  return "";
}

std::string met_type(SourceType t) {
  switch (t) {
    case SourceType::U8: return "MET_UCHAR";
    case SourceType::I8: return "MET_CHAR";
    case SourceType::U16: return "MET_USHORT";
    case SourceType::I16: return "MET_SHORT";
    case SourceType::F32: return "MET_FLOAT";
  }
  return "";
}

std::string nrrd_header(const VolumeHeader& h, bool gzip, const std::string& data_file) {
  std::ostringstream s;
  s.precision(17);
  s << "NRRD0004\n# written by peakcast\ntype: " << nrrd_type(h.source) << "\ndimension: 3\nsizes: " << h.dims[0] << " "
    << h.dims[1] << " " << h.dims[2] << "\nspace: right-anterior-superior\n"
    << "space directions: (" << h.spacing.x << ",0,0) (0," << h.spacing.y << ",0) (0,0," << h.spacing.z
    << ")\nspace origin: (" << h.origin.x << "," << h.origin.y << "," << h.origin.z << ")\n"
    << "encoding: " << (gzip ? "gzip" : "raw") << "\nendian: little\n";
  if (!h.unit.empty()) s << "space units: \"" << h.unit << "\" \"" << h.unit << "\" \"" << h.unit << "\"\n";
  if (!data_file.empty()) s << "data file: " << data_file << "\n";
  return s.str();
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error(p.string() + ": cannot write");
}

}  // namespace

SlabWriter::SlabWriter(const fs::path& path, const VolumeHeader& h, WriteOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->header = h;
  impl_->expected = size_t(h.voxel_count()) * source_bytes(h.source);
  const std::string ext = detail::lower(path.extension().string());
  fs::path data = path;
  std::string prefix;  // header bytes written before the data, in the data file
  bool gzip = options.gzip;
  if (ext == ".nrrd") {
    prefix = nrrd_header(h, gzip, "") + "\n";
  } else if (ext == ".nhdr") {
    data = fs::path(path).replace_extension(gzip ? ".raw.gz" : ".raw");
    write_text(path, nrrd_header(h, gzip, data.filename().string()));
  } else if (ext == ".mhd" || ext == ".mha") {
    if (gzip) throw std::invalid_argument(path.string() + ": gzip output is for .nrrd/.nhdr/.raw");
    std::ostringstream s;
    s.precision(17);
    s << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
      << "Offset = " << h.origin.x << " " << h.origin.y << " " << h.origin.z << "\n"
      << "ElementSpacing = " << h.spacing.x << " " << h.spacing.y << " " << h.spacing.z << "\n"
      << "DimSize = " << h.dims[0] << " " << h.dims[1] << " " << h.dims[2] << "\n"
      << "ElementType = " << met_type(h.source) << "\n";
    if (ext == ".mha") {
      prefix = s.str() + "ElementDataFile = LOCAL\n";
    } else {
      data = fs::path(path).replace_extension(".raw");
      write_text(path, s.str() + "ElementDataFile = " + data.filename().string() + "\n");
    }
  } else if (ext == ".raw") {
    nlohmann::json j = {{"dims", {h.dims[0], h.dims[1], h.dims[2]}},
                        {"dtype", to_string(h.source)},
                        {"spacing", {h.spacing.x, h.spacing.y, h.spacing.z}},
                        {"origin", {h.origin.x, h.origin.y, h.origin.z}},
                        {"endian", "little"},
                        {"encoding", gzip ? "gzip" : "raw"}};
    if (!h.value_unit.empty()) j["values"] = h.value_unit;
    write_text(path.string() + ".json", j.dump(2) + "\n");
  } else {
    throw std::invalid_argument(path.string() + ": unknown output format (use .raw .nrrd .nhdr .mhd .mha)");
  }
  if (gzip) {
    if (!prefix.empty()) {
      write_text(data, prefix);
      impl_->gz = gzopen(data.c_str(), "ab6");
    } else {
      impl_->gz = gzopen(data.c_str(), "wb6");
    }
    if (!impl_->gz) throw std::runtime_error(data.string() + ": cannot open for writing");
  } else {
    impl_->raw = std::fopen(data.c_str(), "wb");
    if (!impl_->raw) throw std::runtime_error(data.string() + ": cannot open for writing");
    std::fwrite(prefix.data(), 1, prefix.size(), impl_->raw);
  }
}

SlabWriter::~SlabWriter() {
  if (impl_->raw) std::fclose(impl_->raw);
  if (impl_->gz) gzclose(impl_->gz);
}

void SlabWriter::write(const void* data, size_t bytes) {
  const auto* p = static_cast<const uint8_t*>(data);
  if (impl_->raw) {
    if (std::fwrite(p, 1, bytes, impl_->raw) != bytes)
      throw std::runtime_error(impl_->path.string() + ": short write (disk full?)");
  } else {
    for (size_t off = 0; off < bytes;) {
      unsigned n = unsigned(std::min<size_t>(bytes - off, 1u << 30));
      if (gzwrite(impl_->gz, p + off, n) != int(n))
        throw std::runtime_error(impl_->path.string() + ": gzip write failed");
      off += n;
    }
  }
  impl_->written += bytes;
}

void SlabWriter::close() {
  bool ok = true;
  if (impl_->raw) ok = std::fclose(impl_->raw) == 0;
  if (impl_->gz) ok = gzclose(impl_->gz) == Z_OK;
  impl_->raw = nullptr;
  impl_->gz = nullptr;
  if (!ok) throw std::runtime_error(impl_->path.string() + ": write failed on close");
  if (impl_->written != impl_->expected)
    throw std::runtime_error(impl_->path.string() + ": wrote " + std::to_string(impl_->written) + " bytes, expected " +
                             std::to_string(impl_->expected));
}

void write_volume(const fs::path& path, const Volume& v, WriteOptions options) {
  VolumeHeader h;
  h.dims = v.dims();
  h.spacing = v.spacing;
  h.origin = v.origin;
  h.unit = v.unit;
  h.value_unit = v.value_unit;
  h.source = v.source_type();
  SlabWriter w(path, h, options);
  const size_t slice = size_t(h.dims[0] * h.dims[1]) * voxel_bytes(v.type());
  std::vector<uint8_t> buf(slice);
  for (int64_t z = 0; z < h.dims[2]; ++z) {
    std::copy_n(v.data() + z * slice, slice, buf.data());
    if (h.source == SourceType::I8)
      for (auto& b : buf) b ^= 0x80;
    if (h.source == SourceType::I16)
      for (size_t i = 1; i < buf.size(); i += 2) buf[i] ^= 0x80;  // little-endian high byte
    w.write(buf.data(), buf.size());
  }
  w.close();
}

}  // namespace peakcast
