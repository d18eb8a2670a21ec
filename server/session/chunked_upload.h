// Arrays larger than one request, or than the server's memory (docs/rest.md, "Chunked uploads"):
// a script declares the array (dims, dtype, its chunk shape), sends it chunk by chunk in any
// order (a zarr or dask array, a numpy memmap: never whole in the client's memory), asks what
// arrived (to resume after an interruption), and finishes: the server then writes an OME-Zarr
// pyramid from the chunks, reading them by slabs within its memory budget, and keeps it as an
// upload that opens at the finest level the budget holds. The chunks go into one raw file in the
// upload folder's incoming area (sparse until written); nothing is registered until the pyramid
// is whole, and an upload removed, abandoned (kIdle without a chunk) or failed leaves nothing.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/volume.h"
#include "session/upload_store.h"

namespace peakcast {

struct ChunkedUploadSpec {
  Dims dims{0, 0, 0};   // x, y, z voxels
  Dims chunk{0, 0, 0};  // x, y, z voxels of every chunk but those at the far edges
  std::string dtype;    // uint8, int8, uint16, int16, float32 (little-endian, x fastest)
  nlohmann::json raw;   // the raw header: dims, dtype, spacing, origin, units
  std::string name, owner;
};

class ChunkedUploads {
 public:
  static constexpr int64_t kMaxChunkBytes = int64_t(16) << 20;  // one chunk's body
  static constexpr std::chrono::minutes kIdle{60};              // no chunk for this long: removed

  // `build_budget_bytes`: the memory the pyramid's build reads level 0 within (the server's
  // memory budget, or kDefaultBuildBudget when it has none).
  ChunkedUploads(UploadStore& store, int64_t build_budget_bytes);
  ~ChunkedUploads();

  // Parses and checks the declaration (a JSON object: dims, dtype, chunk, spacing?, origin?,
  // units?, name?), reserves its bytes in the upload budget and makes its file; the upload's
  // status. UploadRefusal: uploads off, the rate, sizes, the budget (as UploadStore::begin).
  nlohmann::json begin(const std::string& client, const nlohmann::json& declaration, const std::string& owner);
  // Chunk (i, j, k) of the grid (x, y, z order): its box's voxels exactly. Any order, any thread;
  // sending a chunk again replaces it. UploadRefusal 404 (no such upload), 403 (another owner's),
  // 400 (an index outside the grid, a body of the wrong size), 409 (finished already).
  // `as_owner`: only the upload this owner began (403 otherwise); nullopt: any (the admin).
  nlohmann::json put(const std::string& id, const std::optional<std::string>& as_owner,
                     const std::array<int64_t, 3>& index, const std::string& bytes);
  nlohmann::json status(const std::string& id, const std::optional<std::string>& as_owner);
  // Checks every chunk arrived (409 naming how many did not) and marks the upload "building";
  // then finish builds the pyramid and registers the volume on the caller's thread (minutes for
  // gigabytes: the server's pyramid pool). Its status says "done" with the volume id after, or
  // "failed" with why (its files gone).
  void mark_building(const std::string& id, const std::optional<std::string>& as_owner);
  void finish(const std::string& id);
  // An upload being received (or failed) removed whole; 409 while it is built.
  void remove(const std::string& id, const std::optional<std::string>& as_owner);

 private:
  struct Upload {
    ChunkedUploadSpec spec;
    std::array<int64_t, 3> grid{0, 0, 0};
    std::vector<bool> received;
    int64_t received_count = 0;
    int64_t reserved = 0;             // in the upload budget until the pyramid replaces it
    std::string state = "receiving";  // receiving, building, done, failed
    std::string volume, error;
    std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
    // The chunks' file: written under `io`, closed under it (a chunk racing a finish or a
    // removal is refused, never written to a closed or reused descriptor). m_ before io.
    std::mutex io;
    int fd = -1;
  };
  std::shared_ptr<Upload> find(const std::string& id, const std::optional<std::string>& as_owner);
  nlohmann::json status_of(const std::string& id, const Upload& u) const;
  void drop(const std::string& id, Upload& u);  // its files, its reservation
  void sweep();                                 // abandoned uploads

  UploadStore& store_;
  int64_t build_budget_;
  std::mutex m_;
  std::map<std::string, std::shared_ptr<Upload>> uploads_;
};

inline constexpr int64_t kDefaultBuildBudget = int64_t(256) << 20;

}  // namespace peakcast
