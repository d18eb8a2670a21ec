// An uploaded ZIP of a DICOM series (upload_zip.cpp, through Debian's libzip): its files
// extracted into one folder, which the DICOM reader opens as a series.
#pragma once

#include <cstdint>
#include <filesystem>

namespace peakcast {

// Extracts every file of `zip` into `folder` (created) under names of its own choosing (the
// entries' names and folders are never used as paths: a name with ".." or "/" reaches nothing),
// skipping folders and hidden entries (__MACOSX/, .DS_Store). Refused (UploadRefusal 400/413)
// before anything is written when the archive is not a ZIP, is encrypted, holds more than
// `max_files` files or says it decodes to more than `max_bytes`; while writing, when an entry
// decodes to more than it said. Returns the bytes written.
int64_t extract_zip(const std::filesystem::path& zip, const std::filesystem::path& folder, int64_t max_bytes,
                    int64_t max_files);

}  // namespace peakcast
