#include "session/upload_zip.h"

#include <zip.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "session/upload_store.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

struct ZipCloser {
  void operator()(zip_t* z) const { zip_discard(z); }  // read only: nothing to write back
};
struct EntryCloser {
  void operator()(zip_file_t* f) const { zip_fclose(f); }
};

UploadRefusal bad(const std::string& why) { return UploadRefusal(400, "bad_upload", "the ZIP " + why); }

// Folders, and what archivers add beside the files (__MACOSX/ resource forks, .DS_Store).
bool skipped(const std::string& name) {
  if (name.empty() || name.back() == '/') return true;
  if (name.rfind("__MACOSX/", 0) == 0) return true;
  const size_t slash = name.find_last_of('/');
  const std::string base = slash == std::string::npos ? name : name.substr(slash + 1);
  return base.empty() || base[0] == '.';
}

}  // namespace

int64_t extract_zip(const fs::path& zip, const fs::path& folder, int64_t max_bytes, int64_t max_files) {
  int err = 0;
  std::unique_ptr<zip_t, ZipCloser> z(zip_open(zip.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &err));
  if (!z) throw bad("cannot be read (not a ZIP archive, or a damaged one)");
  const zip_int64_t n = zip_get_num_entries(z.get(), 0);
  std::vector<zip_uint64_t> files;
  int64_t declared = 0;
  for (zip_int64_t i = 0; i < n; ++i) {
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(z.get(), zip_uint64_t(i), 0, &st) != 0 || !(st.valid & ZIP_STAT_NAME))
      throw bad("has an entry that cannot be read");
    if (skipped(st.name)) continue;
    if ((st.valid & ZIP_STAT_ENCRYPTION_METHOD) && st.encryption_method != ZIP_EM_NONE)
      throw bad("is encrypted: send it without a password");
    if (int64_t(files.size()) >= max_files)
      throw bad("holds more than " + std::to_string(max_files) + " files: a series is sent as one ZIP of its slices");
    declared += int64_t(st.size);
    if (declared > max_bytes)
      throw UploadRefusal(413, "too_large",
                          "the ZIP decodes to more than " + std::to_string(max_bytes >> 20) +
                              " MiB (what the upload budget leaves, --upload-budget-mib)");
    files.push_back(zip_uint64_t(i));
  }
  if (files.empty()) throw bad("holds no files");
  fs::create_directories(folder);
  int64_t written = 0;
  std::vector<char> buf(1 << 16);
  for (size_t k = 0; k < files.size(); ++k) {
    std::unique_ptr<zip_file_t, EntryCloser> in(zip_fopen_index(z.get(), files[k], 0));
    if (!in) throw bad("has an entry that cannot be decoded (a compression method libzip does not read?)");
    char name[32];
    std::snprintf(name, sizeof name, "slice%06zu.dcm", k);
    std::ofstream out(folder / name, std::ios::binary);
    for (zip_int64_t got; (got = zip_fread(in.get(), buf.data(), buf.size())) != 0;) {
      if (got < 0) throw bad("is damaged (an entry does not decode, or its checksum is wrong)");
      written += got;
      if (written > declared) throw bad("has an entry that decodes to more than it says");
      out.write(buf.data(), got);
    }
    if (!out) throw UploadRefusal(507, "upload_failed", "the upload could not be stored on the server");
  }
  return written;
}

}  // namespace peakcast
