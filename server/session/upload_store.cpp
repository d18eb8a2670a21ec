#include "session/upload_store.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <set>
#include <system_error>

#include "core/log.h"
#include "core/utf8.h"
#include "session/upload_formats.h"
#include "session/upload_zip.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

constexpr const char* kMetaSuffix = ".upload.json";

std::string new_id() {
  static std::mutex m;
  static std::mt19937_64 rng{std::random_device{}()};
  std::lock_guard lock(m);
  char id[32];
  std::snprintf(id, sizeof id, "upload-%012llx", static_cast<unsigned long long>(rng() & 0xffffffffffffull));
  return id;
}

// Every file of an upload: `<id>.<ext>`, its sidecar, its meta file, and their temporaries.
void remove_files(const fs::path& dir, const std::string& id) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::vector<fs::path> gone;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind(id + ".", 0) == 0) gone.push_back(e.path());
  for (const auto& p : gone) fs::remove_all(p, ec);  // a DICOM series' folder too
}

bool inside(const fs::path& child, const fs::path& parent) {
  std::error_code ec;
  const fs::path c = fs::weakly_canonical(child, ec), p = fs::weakly_canonical(parent, ec);
  auto ci = c.begin(), pi = p.begin();
  for (; pi != p.end() && !pi->empty(); ++ci, ++pi)
    if (ci == c.end() || *ci != *pi) return false;
  return true;
}

}  // namespace

UploadStore::UploadStore(fs::path dir, UploadLimits limits, VolumeStore& volumes)
    : dir_(std::move(dir)), limits_(limits), volumes_(volumes) {
  if (dir_.empty()) return;
  for (const fs::path& data : volumes_.data_dirs())
    if (inside(dir_, data) || inside(data, dir_))
      throw std::invalid_argument("--upload-dir " + dir_.string() + " must not be inside a --data directory (" +
                                  data.string() + ") or hold one: data directories may be read-only and are " +
                                  "never written");
  incoming_ = dir_ / ".incoming";
  std::error_code ec;
  fs::create_directories(incoming_, ec);
  const fs::path probe = incoming_ / ".probe";
  if (ec || !std::ofstream(probe)) throw std::invalid_argument("--upload-dir " + dir_.string() + " cannot be written");
  fs::remove(probe, ec);
  // Uploads cut short by a crash: gone. Finished ones: listed again. Files of an upload whose
  // meta file is missing or damaged: gone too (they would be counted by nothing, listed by
  // nothing and deletable by nobody).
  for (const auto& e : fs::directory_iterator(incoming_, ec)) fs::remove_all(e.path(), ec);
  std::set<std::string> listed;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string f = e.path().filename().string();
    if (!f.ends_with(kMetaSuffix)) continue;
    try {
      const nlohmann::json meta = nlohmann::json::parse(std::ifstream(e.path()));
      const std::string id = meta.at("id");
      if (id.rfind("upload-", 0) != 0 || f != id + kMetaSuffix) throw std::runtime_error("its id does not match");
      const std::string file_name = meta.at("file");
      if (file_name.find('/') != std::string::npos || file_name.rfind(id + ".", 0) != 0)
        throw std::runtime_error("its file is not its own");
      const fs::path file = dir_ / file_name;
      if (!fs::exists(file)) throw std::runtime_error("its data is gone");
      const std::string name = clean_upload_name(meta.at("name").get<std::string>());
      const std::string owner = meta.value("owner", std::string());
      nlohmann::json info = meta.value("info", nlohmann::json::object());
      if (info.is_object()) {
        info["name"] = name;
        if (!owner.empty()) info["owner"] = owner;
      }
      volumes_.register_upload(id, file, name, owner, info);
      kept_[id] = Kept{meta.at("bytes").get<int64_t>(), owner};
      listed.insert(id);
    } catch (const std::exception& x) {
      log::warn("upload " + f + " not listed: " + x.what());
    }
  }
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string f = e.path().filename().string();
    if (f.rfind("upload-", 0) != 0) continue;
    const std::string id = f.substr(0, f.find('.'));
    if (listed.count(id)) continue;
    log::warn("upload files without their meta file removed: " + f);
    fs::remove_all(e.path(), ec);
  }
}

int64_t UploadStore::used_locked() const {
  int64_t used = reserved_;
  for (const auto& [_, k] : kept_) used += k.bytes;
  return used;
}

UploadStore::Ticket::~Ticket() {
  if (!committed_) remove_files(store_.incoming_, id_);
  store_.release(*this);
}

void UploadStore::release(Ticket&) {
  std::lock_guard lock(m_);
  --receiving_;
}

// `client`'s bucket, refilled for the time since its last request, holding a token (the caller
// takes it once the upload is accepted), or 429 saying when the next comes (m_ held).
UploadStore::Bucket& UploadStore::rate_locked(const std::string& client) {
  const auto now = std::chrono::steady_clock::now();
  if (rate_.size() > 4096) rate_.clear();  // forget idle clients now and then: a full bucket each
  auto it = rate_.try_emplace(client, Bucket{limits_.burst, now}).first;
  Bucket& b = it->second;
  b.tokens =
      std::min(limits_.burst, b.tokens + std::chrono::duration<double>(now - b.last).count() * limits_.per_minute / 60);
  b.last = now;
  if (b.tokens < 1) {
    // The next token comes when the bucket has refilled to one: that is when to come back.
    const int wait_s = std::max(1, int(std::ceil((1.0 - b.tokens) * 60.0 / std::max(limits_.per_minute, 1e-9))));
    throw UploadRefusal(429, "rate_limited",
                        "too many uploads from this client: its burst of " + std::to_string(int(limits_.burst)) +
                            " is spent, and it refills at " + std::to_string(int(limits_.per_minute)) +
                            " a minute (--uploads-per-minute); the next may start in " + std::to_string(wait_s) + " s",
                        wait_s);
  }
  return b;
}

// 413 past the per-upload limit, 507 past what the budget leaves (m_ held).
void UploadStore::check_size_locked(int64_t length) const {
  const int64_t used = used_locked();
  if (length > limits_.max_bytes)
    throw UploadRefusal(413, "too_large",
                        "an upload may hold " + std::to_string(limits_.max_bytes >> 20) +
                            " MiB (--max-upload-mib); this one has " + std::to_string(length) + " bytes");
  if (used + length > limits_.budget_bytes)
    throw UploadRefusal(507, "upload_budget",
                        "the uploads kept hold " + std::to_string(used >> 20) + " of " +
                            std::to_string(limits_.budget_bytes >> 20) +
                            " MiB (--upload-budget-mib): delete some first");
}

std::unique_ptr<UploadStore::Ticket> UploadStore::begin(const std::string& client, std::optional<int64_t> length) {
  if (!enabled())
    throw UploadRefusal(403, "uploads_off", "this server takes no uploads: start it with --upload-dir DIR");
  std::lock_guard lock(m_);
  Bucket& b = rate_locked(client);
  if (receiving_ >= limits_.max_concurrent)
    throw UploadRefusal(503, "uploads_busy",
                        std::to_string(limits_.max_concurrent) + " uploads are being received now; retry later", 5);
  if (length) check_size_locked(*length);
  b.tokens -= 1;
  ++receiving_;
  const std::string id = new_id();
  return std::unique_ptr<Ticket>(new Ticket(*this, id, incoming_ / (id + ".body")));
}

std::string UploadStore::reserve(const std::string& client, int64_t bytes, int64_t budget_bytes) {
  if (!enabled())
    throw UploadRefusal(403, "uploads_off", "this server takes no uploads: start it with --upload-dir DIR");
  std::lock_guard lock(m_);
  Bucket& b = rate_locked(client);
  check_size_locked(bytes);
  if (used_locked() + budget_bytes > limits_.budget_bytes)
    throw UploadRefusal(507, "upload_budget",
                        "this array and the pyramid built from it take about " + std::to_string(budget_bytes >> 20) +
                            " MiB; with the uploads kept that exceeds " + std::to_string(limits_.budget_bytes >> 20) +
                            " MiB (--upload-budget-mib)");
  b.tokens -= 1;
  reserved_ += budget_bytes;
  return new_id();
}

void UploadStore::unreserve(int64_t bytes) {
  std::lock_guard lock(m_);
  reserved_ -= bytes;
}

void UploadStore::check_raw_header(const nlohmann::json& raw, int64_t length) const {
  const nlohmann::json sidecar = raw_sidecar(raw, "voxels.raw");
  check_raw_body(sidecar, length);
  const int64_t budget = volumes_.load_options().memory_budget_bytes;
  const int64_t times = std::max<int64_t>(1, sidecar.value("times", int64_t(1)));
  const int64_t held = length / times;  // one time point is held at a time; stored as sent (integers, float32)
  if (budget > 0 && held > budget)
    throw UploadRefusal(422, "bad_volume",
                        std::to_string(held >> 20) + " MiB of voxels" + (times > 1 ? " a time point" : "") +
                            " exceeds the server's memory budget of " + std::to_string(budget >> 20) +
                            " MiB (--memory-budget-mib), refused before the body was sent: send it downsampled "
                            "(e.g. array[::2, ::2, ::2]), or as an OME-Zarr pyramid in one of the server's --data "
                            "directories (peakcast convert IN OUT.zarr --pyramid), which opens at a level that fits");
}

std::shared_ptr<VolumeEntry> UploadStore::commit(std::unique_ptr<Ticket> t, const UploadParams& params) {
  std::error_code ec;
  const std::string id = t->id(), name = clean_upload_name(params.name);
  fs::path body = t->file();
  const int64_t received = int64_t(fs::file_size(body, ec));
  if (ec || received == 0) throw UploadRefusal(400, "bad_upload", "the upload has no body");
  if (received > limits_.max_bytes)
    throw UploadRefusal(413, "too_large", "an upload may hold " + std::to_string(limits_.max_bytes >> 20) + " MiB");
  std::optional<nlohmann::json> raw = params.raw;
  if (params.content_type.rfind("multipart/form-data", 0) == 0) {
    const fs::path data = incoming_ / (id + ".data");
    MultipartUpload m = split_multipart(body, params.content_type, data);
    if (m.header) raw = m.header;
    body = data;
  }
  const UploadFormat format = sniff_upload(body, raw.has_value());
  int64_t bytes = int64_t(fs::file_size(body));
  if (format == UploadFormat::DicomZip) body = unzip_series(id, body, bytes);
  // Into place: the data file, and for raw voxels the sidecar the raw reader takes.
  const fs::path file = dir_ / (id + extension_of(format));
  fs::path open = file;
  if (format == UploadFormat::Raw) {
    const nlohmann::json sidecar = raw_sidecar(*raw, file.filename().string());
    check_raw_body(sidecar, bytes);
    open = dir_ / (id + ".json");
    std::ofstream(incoming_ / (id + ".json")) << json_text(sidecar);
  }
  {
    std::lock_guard lock(m_);
    if (used_locked() + bytes > limits_.budget_bytes)
      throw UploadRefusal(
          507, "upload_budget",
          "the uploads kept would exceed " + std::to_string(limits_.budget_bytes >> 20) + " MiB (--upload-budget-mib)");
  }
  fs::rename(body, file, ec);
  if (!ec && format == UploadFormat::Raw) fs::rename(incoming_ / (id + ".json"), open, ec);
  if (ec) {
    remove_files(dir_, id);
    throw UploadRefusal(507, "upload_failed", "the upload could not be stored on the server");
  }
  int64_t charged = bytes;
  const LoadOptions options = charged_load(bytes, charged);
  std::shared_ptr<VolumeEntry> entry;
  try {
    entry = volumes_.add_upload(id, open, name, params.owner, options);  // read and checked as any volume file
  } catch (const UploadRefusal&) {
    remove_files(dir_, id);
    throw;
  } catch (const std::exception& e) {
    remove_files(dir_, id);
    // The reader names the file: the client sees the upload's name, never a server path.
    std::string why = e.what();
    for (const std::string& p :
         {open.string(), file.string(), dir_.string(), open.filename().string(), file.filename().string()})
      for (size_t at; (at = why.find(p)) != std::string::npos;) why.replace(at, p.size(), name);
    if (dynamic_cast<const VolumeError*>(&e)) throw UploadRefusal(422, "bad_volume", why);
    throw UploadRefusal(500, "upload_failed", why);
  }
  if (entry->volume) charged = std::max(charged, int64_t(entry->volume->byte_size()));
  keep(id, *entry, name, open, charged, params.owner);
  t->committed_ = true;
  return entry;
}

fs::path UploadStore::unzip_series(const std::string& id, const fs::path& zip, int64_t& bytes) {
  const fs::path folder = incoming_ / (id + extension_of(UploadFormat::DicomZip));
  int64_t left = 0;
  {
    std::lock_guard lock(m_);
    left = limits_.budget_bytes - used_locked();
  }
  std::error_code ec;
  try {
    bytes = extract_zip(zip, folder, std::min(left, limits_.max_bytes * 8), 100000);
  } catch (...) {
    fs::remove_all(folder, ec);
    fs::remove(zip, ec);
    throw;
  }
  fs::remove(zip, ec);
  return folder;
}

// The budget counts what the upload costs the server: its file, or the voxels it decodes to when
// more (a small gzip file of zeros). Charged from the header, before anything is decoded; the
// reader refuses a header naming any other file (an upload is one file).
LoadOptions UploadStore::charged_load(int64_t file_bytes, int64_t& charged) {
  LoadOptions options = volumes_.load_options();
  options.single_file = true;
  options.on_header = [this, file_bytes, &charged](const VolumeHeader& h) {
    for (int a = 0; a < 3; ++a)
      if (h.dims[a] < 2)
        throw UploadRefusal(400, "bad_upload",
                            "every axis of a volume needs at least 2 voxels (sizes " + std::to_string(h.dims[0]) + "x" +
                                std::to_string(h.dims[1]) + "x" + std::to_string(h.dims[2]) + ")");
    const int64_t decoded = h.voxel_count() * int64_t(voxel_bytes(storage_type(h.source)));
    charged = std::max(file_bytes, decoded);
    std::lock_guard lock(m_);
    if (used_locked() + charged > limits_.budget_bytes)
      throw UploadRefusal(507, "upload_budget",
                          "this upload decodes to " + std::to_string(decoded >> 20) +
                              " MiB; with the uploads kept that exceeds " + std::to_string(limits_.budget_bytes >> 20) +
                              " MiB (--upload-budget-mib)");
  };
  return options;
}

// A registered upload's meta file, then its count: a failure takes it out again, whole (no
// volume without its files, no files without their meta).
void UploadStore::keep(const std::string& id, const VolumeEntry& entry, const std::string& name, const fs::path& open,
                       int64_t charged, const std::string& owner) {
  try {
    const nlohmann::json meta = {{"id", id},         {"name", name},   {"file", open.filename().string()},
                                 {"bytes", charged}, {"owner", owner}, {"info", entry.info(false)}};
    {
      std::ofstream out(dir_ / (id + ".upload.tmp"));
      out << json_text(meta);
      if (!out) throw std::runtime_error("its meta file could not be written");
    }
    fs::rename(dir_ / (id + ".upload.tmp"), dir_ / (id + kMetaSuffix));
    std::lock_guard lock(m_);
    kept_[id] = Kept{charged, owner};
  } catch (const std::exception& e) {
    volumes_.remove_upload(id);
    remove_files(dir_, id);
    log::warn("upload not kept", {{"id", id}, {"error", e.what()}});
    throw UploadRefusal(507, "upload_failed", "the upload could not be stored on the server");
  }
}

void UploadStore::remove(const std::string& id, const std::optional<std::string>& as_owner) {
  {
    std::lock_guard lock(m_);
    auto it = kept_.find(id);
    if (it == kept_.end()) {
      if (volumes_.find(id) || volumes_.known(id))
        throw UploadRefusal(403, "not_an_upload", "'" + id + "' is not an upload: only uploads can be deleted");
      throw UploadRefusal(404, "not_found", "no volume '" + clean_utf8(id, 200) + "'");
    }
    if (as_owner && it->second.owner != *as_owner)
      throw UploadRefusal(
          403, "not_owner",
          "'" + id + "' was uploaded with another token: only its owner or the admin token may delete it");
    kept_.erase(it);
  }
  volumes_.remove_upload(id);
  remove_files(dir_, id);
}

std::shared_ptr<VolumeEntry> UploadStore::commit_folder(const std::string& id, const fs::path& folder,
                                                        const std::string& name, const std::string& owner) {
  std::error_code ec;
  const fs::path open = dir_ / (id + folder.extension().string());
  int64_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(folder, ec))
    if (e.is_regular_file(ec)) bytes += int64_t(e.file_size(ec));
  fs::rename(folder, open, ec);
  if (ec) {
    remove_files(dir_, id);
    throw UploadRefusal(507, "upload_failed", "the upload could not be stored on the server");
  }
  std::shared_ptr<VolumeEntry> entry;
  try {
    entry = volumes_.add_upload(id, open, name, owner, volumes_.load_options());
  } catch (const std::exception& e) {
    remove_files(dir_, id);
    throw UploadRefusal(422, "bad_volume", std::string("the pyramid built from the chunks did not open: ") + e.what());
  }
  keep(id, *entry, name, open, bytes, owner);
  return entry;
}

int64_t UploadStore::used_bytes() const {
  std::lock_guard lock(m_);
  return used_locked();
}

}  // namespace peakcast
