#include "session/chunked_upload.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "chunked/zarr_convert.h"
#include "core/utf8.h"
#include "core/log.h"
#include "session/upload_formats.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

UploadRefusal bad(const std::string& why) { return UploadRefusal(400, "bad_upload", why); }

int64_t dtype_bytes(const std::string& dtype) {
  return dtype == "uint8" || dtype == "int8" ? 1 : dtype == "float32" ? 4 : 2;
}

Dims triple(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || !j[key].is_array() || j[key].size() != 3)
    throw bad(std::string("chunked upload: ") + key + " must be 3 integers, x, y, z");
  Dims d{};
  for (int a = 0; a < 3; ++a) {
    if (!j[key][a].is_number_integer() || j[key][a].get<int64_t>() < 1)
      throw bad(std::string("chunked upload: ") + key + " must be 3 integers >= 1, x, y, z");
    d[a] = j[key][a].get<int64_t>();
  }
  return d;
}

// [first, last) runs of the received chunks' flat indices (x fastest), for a resume.
nlohmann::json runs_of(const std::vector<bool>& received) {
  nlohmann::json runs = nlohmann::json::array();
  for (size_t i = 0; i < received.size();) {
    if (!received[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < received.size() && received[j]) ++j;
    runs.push_back({i, j});
    i = j;
  }
  return runs;
}

}  // namespace

ChunkedUploads::ChunkedUploads(UploadStore& store, int64_t build_budget_bytes)
    : store_(store), build_budget_(build_budget_bytes > 0 ? build_budget_bytes : kDefaultBuildBudget) {}

ChunkedUploads::~ChunkedUploads() {
  std::lock_guard lock(m_);
  for (auto& [id, u] : uploads_)
    if (u->state != "done") drop(id, *u);
}

nlohmann::json ChunkedUploads::begin(const std::string& client, const nlohmann::json& d, const std::string& owner) {
  if (!store_.enabled())
    throw UploadRefusal(403, "uploads_off", "this server takes no uploads: start it with --upload-dir DIR");
  if (!d.is_object()) throw bad("chunked upload: the body must be a JSON object: dims, dtype, chunk, ...");
  for (auto& [key, _] : d.items())
    if (key != "dims" && key != "dtype" && key != "chunk" && key != "spacing" && key != "origin" && key != "units" &&
        key != "name")
      throw bad("chunked upload: unknown key '" + key.substr(0, 40) +
                "' (dims, dtype, chunk, spacing, origin, units, name)");
  sweep();
  nlohmann::json header = d;
  header.erase("chunk");
  header.erase("name");
  auto u = std::make_shared<Upload>();
  u->spec.raw = raw_sidecar(header, "x.raw");  // checks dims, dtype, spacing, origin, units
  u->spec.dims = triple(d, "dims");
  u->spec.chunk = triple(d, "chunk");
  u->spec.dtype = d["dtype"].get<std::string>();
  u->spec.name = clean_upload_name(d.value("name", std::string("upload")));
  u->spec.owner = owner;
  const int64_t bpv = dtype_bytes(u->spec.dtype);
  int64_t chunk_voxels = 1, voxels = 1, chunks = 1;
  for (int a = 0; a < 3; ++a) {
    if (u->spec.dims[a] < 2) throw bad("chunked upload: every axis of a volume needs at least 2 voxels");
    u->spec.chunk[a] = std::min(u->spec.chunk[a], u->spec.dims[a]);
    u->grid[a] = (u->spec.dims[a] + u->spec.chunk[a] - 1) / u->spec.chunk[a];
    chunk_voxels *= u->spec.chunk[a];
    voxels *= u->spec.dims[a];
    chunks *= u->grid[a];
  }
  if (chunk_voxels * bpv > kMaxChunkBytes)
    throw bad("chunked upload: a chunk of " + std::to_string(chunk_voxels * bpv) + " bytes is over the " +
              std::to_string(kMaxChunkBytes >> 20) + " MiB a chunk may hold: send smaller chunks");
  const int64_t bytes = voxels * bpv;
  // The raw chunks and the pyramid built from them are on disk together until the build ends:
  // the level-0 copy, the coarser levels (1/7 more) and the chunks' own files.
  u->reserved = bytes + bytes / 7 * 8 + (int64_t(1) << 20);
  const std::string id = store_.reserve(client, bytes, u->reserved);
  u->received.assign(size_t(chunks), false);
  const fs::path raw = store_.incoming(id + ".raw");
  u->spec.raw["data_file"] = raw.filename().string();
  u->fd = ::open(raw.c_str(), O_CREAT | O_EXCL | O_RDWR | O_CLOEXEC, 0600);
  if (u->fd < 0 || ::ftruncate(u->fd, off_t(bytes)) != 0 ||
      !(std::ofstream(store_.incoming(id + ".json")) << json_text(u->spec.raw))) {
    drop(id, *u);
    throw UploadRefusal(507, "upload_failed", "the upload's file could not be made on the server");
  }
  std::lock_guard lock(m_);
  uploads_[id] = u;
  return status_of(id, *u);
}

std::shared_ptr<ChunkedUploads::Upload> ChunkedUploads::find(const std::string& id,
                                                             const std::optional<std::string>& as_owner) {
  std::lock_guard lock(m_);
  auto it = uploads_.find(id);
  if (it == uploads_.end()) throw UploadRefusal(404, "not_found", "no chunked upload '" + clean_upload_name(id) + "'");
  if (as_owner && it->second->spec.owner != *as_owner)
    throw UploadRefusal(403, "not_owner", "'" + id + "' was begun with another token");
  return it->second;
}

nlohmann::json ChunkedUploads::put(const std::string& id, const std::optional<std::string>& as_owner,
                                   const std::array<int64_t, 3>& index, const std::string& bytes) {
  auto u = find(id, as_owner);
  const ChunkedUploadSpec& s = u->spec;
  Dims lo{}, box{};
  for (int a = 0; a < 3; ++a) {
    if (index[a] < 0 || index[a] >= u->grid[a])
      throw bad("chunk " + std::to_string(index[0]) + "," + std::to_string(index[1]) + "," + std::to_string(index[2]) +
                " is outside the grid of " + std::to_string(u->grid[0]) + "x" + std::to_string(u->grid[1]) + "x" +
                std::to_string(u->grid[2]) + " chunks");
    lo[a] = index[a] * s.chunk[a];
    box[a] = std::min(s.chunk[a], s.dims[a] - lo[a]);
  }
  const int64_t bpv = dtype_bytes(s.dtype), row = box[0] * bpv;
  if (int64_t(bytes.size()) != row * box[1] * box[2])
    throw bad("chunk " + std::to_string(index[0]) + "," + std::to_string(index[1]) + "," + std::to_string(index[2]) +
              " holds " + std::to_string(box[0]) + "x" + std::to_string(box[1]) + "x" + std::to_string(box[2]) +
              " voxels, " + std::to_string(row * box[1] * box[2]) + " bytes; the body has " +
              std::to_string(bytes.size()));
  {
    std::lock_guard lock(m_);
    if (u->state != "receiving")
      throw UploadRefusal(409, "upload_finished", "'" + id + "' is " + u->state + ": it takes no more chunks");
  }
  {
    std::lock_guard io(u->io);
    if (u->fd < 0) throw UploadRefusal(409, "upload_finished", "'" + id + "' takes no more chunks");
    const char* src = bytes.data();
    for (int64_t z = 0; z < box[2]; ++z)
      for (int64_t y = 0; y < box[1]; ++y, src += row) {
        const int64_t at = (((lo[2] + z) * s.dims[1] + lo[1] + y) * s.dims[0] + lo[0]) * bpv;
        if (::pwrite(u->fd, src, size_t(row), off_t(at)) != row)
          throw UploadRefusal(507, "upload_failed", "a chunk could not be written on the server (disk full?)");
      }
  }
  std::lock_guard lock(m_);
  const size_t flat = size_t(index[0] + u->grid[0] * (index[1] + u->grid[1] * index[2]));
  if (!u->received[flat]) ++u->received_count;
  u->received[flat] = true;
  u->last = std::chrono::steady_clock::now();
  return {{"id", id}, {"received", u->received_count}, {"chunks", u->received.size()}};
}

nlohmann::json ChunkedUploads::status(const std::string& id, const std::optional<std::string>& as_owner) {
  sweep();
  auto u = find(id, as_owner);
  std::lock_guard lock(m_);
  return status_of(id, *u);
}

nlohmann::json ChunkedUploads::status_of(const std::string& id, const Upload& u) const {
  nlohmann::json s = {{"id", id},
                      {"state", u.state},
                      {"name", u.spec.name},
                      {"dims", {u.spec.dims[0], u.spec.dims[1], u.spec.dims[2]}},
                      {"dtype", u.spec.dtype},
                      {"chunk", {u.spec.chunk[0], u.spec.chunk[1], u.spec.chunk[2]}},
                      {"grid", {u.grid[0], u.grid[1], u.grid[2]}},
                      {"chunks", u.received.size()},
                      {"received", u.received_count},
                      {"received_runs", runs_of(u.received)}};
  if (!u.volume.empty()) s["volume"] = u.volume;
  if (!u.error.empty()) s["error"] = u.error;
  return s;
}

void ChunkedUploads::mark_building(const std::string& id, const std::optional<std::string>& as_owner) {
  auto u = find(id, as_owner);
  std::lock_guard lock(m_);
  if (u->state != "receiving") throw UploadRefusal(409, "upload_finished", "'" + id + "' is " + u->state + " already");
  if (const int64_t missing = int64_t(u->received.size()) - u->received_count; missing > 0)
    throw UploadRefusal(409, "chunks_missing",
                        std::to_string(missing) + " of " + std::to_string(u->received.size()) +
                            " chunks have not arrived: send them (GET the upload for which), then finish");
  u->state = "building";
}

void ChunkedUploads::finish(const std::string& id) {
  std::shared_ptr<Upload> u = find(id, std::nullopt);
  const fs::path zarr = store_.incoming(id + ".zarr");
  try {
    {
      std::lock_guard io(u->io);  // a chunk being written ends first; none after
      ::close(u->fd);
      u->fd = -1;
    }
    chunked::ZarrWriteOptions options;
    options.pyramid = true;
    options.chunk = 64;
    chunked::convert_to_ome_zarr_by_slabs(store_.incoming(id + ".json"), zarr, LoadOptions{}, options, build_budget_);
    std::error_code ec;
    fs::remove(store_.incoming(id + ".raw"), ec);
    fs::remove(store_.incoming(id + ".json"), ec);
    store_.commit_folder(id, zarr, u->spec.name, u->spec.owner);
    std::lock_guard lock(m_);
    store_.unreserve(u->reserved);
    u->reserved = 0;
    u->state = "done";
    u->volume = id;
  } catch (const std::exception& e) {
    log::warn("chunked upload not built", {{"id", id}, {"error", e.what()}});
    std::lock_guard lock(m_);
    drop(id, *u);
    u->state = "failed";
    u->error = e.what();
  }
}

void ChunkedUploads::remove(const std::string& id, const std::optional<std::string>& as_owner) {
  auto u = find(id, as_owner);
  std::lock_guard lock(m_);
  if (u->state == "building") throw UploadRefusal(409, "upload_building", "'" + id + "' is being built: wait for it");
  if (u->state == "receiving" || u->state == "failed") drop(id, *u);
  uploads_.erase(id);  // a finished one's volume stays: DELETE /api/volumes/{id} removes it
}

void ChunkedUploads::drop(const std::string& id, Upload& u) {
  {
    std::lock_guard io(u.io);
    if (u.fd >= 0) ::close(u.fd);
    u.fd = -1;
  }
  std::error_code ec;
  for (const char* ext : {".raw", ".json"}) fs::remove(store_.incoming(id + ext), ec);
  fs::remove_all(store_.incoming(id + ".zarr"), ec);
  fs::remove_all(chunked::partial_path(store_.incoming(id + ".zarr")), ec);
  if (u.reserved > 0) store_.unreserve(u.reserved);
  u.reserved = 0;
}

void ChunkedUploads::sweep() {
  std::lock_guard lock(m_);
  const auto now = std::chrono::steady_clock::now();
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    Upload& u = *it->second;
    if (u.state == "receiving" && now - u.last > kIdle) {
      log::info("chunked upload abandoned: removed", {{"id", it->first}, {"received", u.received_count}});
      drop(it->first, u);
      it = uploads_.erase(it);
    } else if (u.state == "done" || u.state == "failed") {
      it = now - u.last > kIdle ? uploads_.erase(it) : std::next(it);  // their status, kept a while
    } else {
      ++it;
    }
  }
}

}  // namespace peakcast
