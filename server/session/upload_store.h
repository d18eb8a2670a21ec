// Volumes that scripts and the browser send (POST /api/volumes): streamed into the upload folder
// as a file of their own, checked by the same readers and limits as any volume file, then moved
// into place under a new id and registered with the volume store, or refused with the reason and
// nothing left behind. The folder is the server's own (--upload-dir), never a data directory.
// Uploads outlive the process: a restart lists them again. No network here: the HTTP side
// (net/http_upload.cpp) streams the body into a Ticket's file.
#pragma once

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/volume_io.h"
#include "session/limits.h"
#include "session/volume_store.h"

namespace peakcast {

// A refused upload or deletion: an HTTP status, a code from proto/ and a message that names no
// server path.
struct UploadRefusal : std::runtime_error {
  UploadRefusal(int status, std::string code, const std::string& message, int retry_after_s = 0)
      : std::runtime_error(message), status(status), code(std::move(code)), retry_after_s(retry_after_s) {}
  int status;
  std::string code;
  int retry_after_s;  // > 0: when to come back (Retry-After), for 429 and 503
};

struct UploadLimits {
  int64_t max_bytes = limits::kDefaultMaxUploadBytes;
  int64_t budget_bytes = limits::kDefaultUploadBudgetBytes;
  int max_concurrent = limits::kDefaultMaxConcurrentUploads;
  double per_minute = limits::kUploadsPerMinutePerClient;
  double burst = limits::kUploadBurst;
  std::chrono::seconds idle_timeout = limits::kDefaultUploadIdleTimeout;
  // After the first idle_timeout, an upload slower than this on average is ended (a trickle
  // would hold a slot for as long as it lasts); the whole body must arrive within `deadline`.
  double min_bytes_per_second = limits::kDefaultUploadMinBytesPerSecond;
  std::chrono::seconds deadline = limits::kDefaultUploadDeadline;
};

// What the request says of its body besides the bytes: a name, and for raw voxels their
// header (query parameters, or the JSON part of a multipart body).
struct UploadParams {
  std::string name;
  std::string content_type;           // multipart/form-data carries a JSON part and a data part
  std::optional<nlohmann::json> raw;  // {dims, dtype, spacing?, origin?, endian?}
  std::string owner;                  // who sent it (net/access.h: a token's name); empty on an open server
};

class UploadStore {
 public:
  // `dir` empty: uploads are off (every begin() is refused saying how to turn them on).
  // Throws std::invalid_argument for a folder inside a data directory or one that cannot be
  // written. Leftovers of uploads cut short by a crash are removed; finished ones are listed.
  UploadStore(std::filesystem::path dir, UploadLimits limits, VolumeStore& volumes);
  bool enabled() const { return !dir_.empty(); }
  const UploadLimits& limits() const { return limits_; }

  // One upload being received: its file in the folder's incoming area. Destroying a ticket that
  // was not committed removes the file and gives the slot back.
  class Ticket {
   public:
    ~Ticket();
    Ticket(const Ticket&) = delete;
    Ticket& operator=(const Ticket&) = delete;
    const std::filesystem::path& file() const { return file_; }
    const std::string& id() const { return id_; }

   private:
    friend class UploadStore;
    Ticket(UploadStore& store, std::string id, std::filesystem::path file)
        : store_(store), id_(std::move(id)), file_(std::move(file)) {}
    UploadStore& store_;
    std::string id_;
    std::filesystem::path file_;
    bool committed_ = false;
  };

  // Refused (UploadRefusal) when uploads are off, `client` exceeds its rate, too many are being
  // received, or the announced length exceeds the per-upload limit or the budget left.
  std::unique_ptr<Ticket> begin(const std::string& client, std::optional<int64_t> length);
  // Raw voxels described by the query (`raw`, not multipart): what their header decides, checked
  // before the body is read: a header the raw reader refuses, a body length that is not what dims
  // and dtype need, voxels past the memory budget (UploadRefusal, as commit would refuse them).
  void check_raw_header(const nlohmann::json& raw, int64_t length) const;
  // The body is in the ticket's file: find its format, check it as any volume file is, move it
  // into place and register it. Throws UploadRefusal (the files are gone then).
  std::shared_ptr<VolumeEntry> commit(std::unique_ptr<Ticket> ticket, const UploadParams& params);
  // Removes an upload (UploadRefusal 404 for no such volume, 403 for a volume that is not an
  // upload). `as_owner`: only an upload that this owner made (403 not_owner otherwise); nullopt:
  // any (the admin, or an open server).
  void remove(const std::string& id, const std::optional<std::string>& as_owner = std::nullopt);
  int64_t used_bytes() const;

  // Chunked uploads (session/chunked_upload.h): a new upload id, `budget_bytes` reserved in the
  // budget (what the array and its pyramid take) after the checks begin() makes of `bytes` (the
  // array's voxels) and of the client's rate; unreserve gives it back.
  std::string reserve(const std::string& client, int64_t bytes, int64_t budget_bytes);
  void unreserve(int64_t bytes);
  // Where an upload's files are made before it is whole.
  std::filesystem::path incoming(const std::string& file) const { return incoming_ / file; }
  // A folder made in the incoming area (a pyramid) moved into place as upload `id`, read and
  // kept. UploadRefusal (the files are gone then).
  std::shared_ptr<VolumeEntry> commit_folder(const std::string& id, const std::filesystem::path& folder,
                                             const std::string& name, const std::string& owner);

 private:
  struct Bucket;
  Bucket& rate_locked(const std::string& client);
  void check_size_locked(int64_t length) const;
  void release(Ticket& t);
  LoadOptions charged_load(int64_t file_bytes, int64_t& charged);
  // A ZIP of a DICOM series: its files into the incoming folder `id`.dcm, within what the budget
  // leaves; returns that folder, `bytes` set to what it holds. `zip` is removed either way.
  std::filesystem::path unzip_series(const std::string& id, const std::filesystem::path& zip, int64_t& bytes);
  void keep(const std::string& id, const VolumeEntry& entry, const std::string& name, const std::filesystem::path& open,
            int64_t charged, const std::string& owner);
  std::filesystem::path dir_, incoming_;
  UploadLimits limits_;
  VolumeStore& volumes_;
  mutable std::mutex m_;
  int receiving_ = 0;
  int64_t reserved_ = 0;  // chunked uploads' bytes while they are received and built
  struct Kept {
    int64_t bytes;  // what the budget counts: the file, or the voxels it decodes to when more
    std::string owner;
  };
  std::map<std::string, Kept> kept_;
  int64_t used_locked() const;
  struct Bucket {
    double tokens;
    std::chrono::steady_clock::time_point last;
  };
  std::map<std::string, Bucket> rate_;
};

}  // namespace peakcast
