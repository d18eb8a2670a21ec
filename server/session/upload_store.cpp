#include "session/upload_store.h"

#include <fstream>
#include <random>
#include <system_error>

#include "core/log.h"
#include "session/upload_formats.h"

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

// A name as the client gave it, made safe to show: printable, bounded; "upload" when empty.
std::string clean_name(const std::string& name) {
  std::string out;
  for (char c : name)
    if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) out += c;
  if (out.size() > limits::kMaxUploadNameLength) out.resize(limits::kMaxUploadNameLength);
  return out.empty() ? "upload" : out;
}

// Every file of an upload: `<id>.<ext>`, its sidecar, its meta file, and their temporaries.
void remove_files(const fs::path& dir, const std::string& id) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::vector<fs::path> gone;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().rfind(id + ".", 0) == 0) gone.push_back(e.path());
  for (const auto& p : gone) fs::remove(p, ec);
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

UploadStore::UploadStore(fs::path dir, UploadLimits limits, VolumeStore& volumes, LoadOptions load)
    : dir_(std::move(dir)), limits_(limits), volumes_(volumes), load_(load) {
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
  // Uploads cut short by a crash: gone. Finished ones: listed again.
  for (const auto& e : fs::directory_iterator(incoming_, ec)) fs::remove_all(e.path(), ec);
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string f = e.path().filename().string();
    if (!f.ends_with(kMetaSuffix)) continue;
    try {
      const nlohmann::json meta = nlohmann::json::parse(std::ifstream(e.path()));
      const std::string id = meta.at("id");
      const fs::path file = dir_ / meta.at("file").get<std::string>();
      if (!fs::exists(file)) throw std::runtime_error("its data is gone");
      volumes_.register_upload(id, file, meta.at("name"), meta.value("info", nlohmann::json::object()));
      kept_[id] = meta.at("bytes").get<int64_t>();
    } catch (const std::exception& x) {
      log::warn("upload " + f + " not listed: " + x.what());
    }
  }
}

UploadStore::Ticket::~Ticket() {
  if (!committed_) remove_files(store_.incoming_, id_);
  store_.release(*this);
}

void UploadStore::release(Ticket&) {
  std::lock_guard lock(m_);
  --receiving_;
}

std::unique_ptr<UploadStore::Ticket> UploadStore::begin(const std::string& client, std::optional<int64_t> length) {
  if (!enabled())
    throw UploadRefusal(403, "uploads_off", "this server takes no uploads: start it with --upload-dir DIR");
  std::lock_guard lock(m_);
  const auto now = std::chrono::steady_clock::now();
  if (rate_.size() > 4096) rate_.clear();  // forget idle clients now and then: a full bucket each
  auto it = rate_.try_emplace(client, Bucket{limits_.burst, now}).first;
  Bucket& b = it->second;
  b.tokens = std::min(limits_.burst, b.tokens + std::chrono::duration<double>(now - b.last).count() * limits_.per_minute / 60);
  b.last = now;
  if (b.tokens < 1)
    throw UploadRefusal(429, "rate_limited", "too many uploads from this client: at most " +
                                                 std::to_string(int(limits_.per_minute)) + " a minute");
  if (receiving_ >= limits_.max_concurrent)
    throw UploadRefusal(503, "uploads_busy", std::to_string(limits_.max_concurrent) +
                                                 " uploads are being received now; retry later");
  int64_t used = 0;
  for (const auto& [_, n] : kept_) used += n;
  if (length && *length > limits_.max_bytes)
    throw UploadRefusal(413, "too_large", "an upload may hold " + std::to_string(limits_.max_bytes >> 20) +
                                              " MiB (--max-upload-mib); this one has " + std::to_string(*length) + " bytes");
  if (length && used + *length > limits_.budget_bytes)
    throw UploadRefusal(507, "upload_budget", "the uploads kept hold " + std::to_string(used >> 20) + " of " +
                                                  std::to_string(limits_.budget_bytes >> 20) +
                                                  " MiB (--upload-budget-mib): delete some first");
  b.tokens -= 1;
  ++receiving_;
  const std::string id = new_id();
  return std::unique_ptr<Ticket>(new Ticket(*this, id, incoming_ / (id + ".body")));
}

std::shared_ptr<VolumeEntry> UploadStore::commit(std::unique_ptr<Ticket> t, const UploadParams& params) {
  std::error_code ec;
  const std::string id = t->id(), name = clean_name(params.name);
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
  // Into place: the data file, and for raw voxels the sidecar the raw reader takes.
  const fs::path file = dir_ / (id + extension_of(format));
  fs::path open = file;
  if (format == UploadFormat::Raw) {
    open = dir_ / (id + ".json");
    std::ofstream(incoming_ / (id + ".json")) << raw_sidecar(*raw, file.filename().string()).dump();
  }
  const int64_t bytes = int64_t(fs::file_size(body));
  {
    std::lock_guard lock(m_);
    int64_t used = 0;
    for (const auto& [_, n] : kept_) used += n;
    if (used + bytes > limits_.budget_bytes)
      throw UploadRefusal(507, "upload_budget", "the uploads kept would exceed " +
                                                    std::to_string(limits_.budget_bytes >> 20) + " MiB (--upload-budget-mib)");
  }
  fs::rename(body, file, ec);
  if (!ec && format == UploadFormat::Raw) fs::rename(incoming_ / (id + ".json"), open, ec);
  if (ec) {
    remove_files(dir_, id);
    throw UploadRefusal(507, "upload_failed", "the upload could not be stored on the server");
  }
  std::shared_ptr<VolumeEntry> entry;
  try {
    entry = volumes_.add_upload(id, open, name);  // read and checked as any volume file
  } catch (const std::exception& e) {
    remove_files(dir_, id);
    // The reader names the file: the client sees the upload's name, never a server path.
    std::string why = e.what();
    for (const std::string& p : {open.string(), file.string(), dir_.string(), open.filename().string(),
                                 file.filename().string()})
      for (size_t at; (at = why.find(p)) != std::string::npos;) why.replace(at, p.size(), name);
    if (dynamic_cast<const VolumeError*>(&e)) throw UploadRefusal(422, "bad_volume", why);
    throw UploadRefusal(500, "upload_failed", why);
  }
  const nlohmann::json meta = {
      {"id", id}, {"name", name}, {"file", open.filename().string()}, {"bytes", bytes}, {"info", entry->info(false)}};
  std::ofstream(dir_ / (id + ".upload.tmp")) << meta.dump();
  fs::rename(dir_ / (id + ".upload.tmp"), dir_ / (id + kMetaSuffix), ec);
  std::lock_guard lock(m_);
  kept_[id] = bytes;
  t->committed_ = true;
  return entry;
}

void UploadStore::remove(const std::string& id) {
  {
    std::lock_guard lock(m_);
    if (!kept_.count(id)) {
      if (volumes_.find(id) || volumes_.known(id))
        throw UploadRefusal(403, "not_an_upload", "'" + id + "' is not an upload: only uploads can be deleted");
      throw UploadRefusal(404, "not_found", "no volume '" + id.substr(0, 200) + "'");
    }
    kept_.erase(id);
  }
  volumes_.remove_upload(id);
  remove_files(dir_, id);
}

int64_t UploadStore::used_bytes() const {
  std::lock_guard lock(m_);
  int64_t used = 0;
  for (const auto& [_, n] : kept_) used += n;
  return used;
}

}  // namespace peakcast
