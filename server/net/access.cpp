#include "net/access.h"

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/log.h"
#include "net/http_text.h"
#include "session/limits.h"

namespace peakcast::net {
namespace {

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

bool printable(const std::string& s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) return false;
  return true;
}

}  // namespace

Access::Access(std::string admin_token, std::vector<UserToken> users)
    : admin_(std::move(admin_token)), users_(std::move(users)) {}

Principal Access::who(const std::string& token) const {
  if (!required()) return {true, true, ""};
  Principal p;
  // Every configured token is compared, whichever matches: the time tells nothing of which.
  if (!admin_.empty() && tokens_equal(token, admin_)) p = {true, true, "admin"};
  for (const auto& u : users_)
    if (tokens_equal(token, u.token) && !p.authorized) p = {true, false, u.name};
  return p;
}

std::string read_token_file(const std::filesystem::path& file) {
  std::error_code ec;
  const auto perms = std::filesystem::status(file, ec).permissions();
  if (!ec && (perms & (std::filesystem::perms::group_read | std::filesystem::perms::others_read)) !=
                 std::filesystem::perms::none)
    log::warn("the token file can be read by other users: chmod 600 it", {{"file", file.string()}});
  std::ifstream in(file);
  if (!in) throw std::invalid_argument("--token-file " + file.string() + " cannot be read");
  std::string line;
  std::getline(in, line);
  line = trim(line);
  if (line.empty()) throw std::invalid_argument("--token-file " + file.string() + ": the first line holds no token");
  if (line.size() > limits::kMaxTokenLength || !printable(line))
    throw std::invalid_argument("--token-file " + file.string() + ": a token is 1.." +
                                std::to_string(limits::kMaxTokenLength) + " printable characters without spaces");
  return line;
}

std::vector<UserToken> read_user_tokens(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::invalid_argument("--user-token-file " + file.string() + " cannot be read");
  std::vector<UserToken> out;
  std::set<std::string> names;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    UserToken u;
    std::string extra;
    words >> u.name >> u.token >> extra;
    const std::string where = "--user-token-file " + file.string() + " line " + std::to_string(n);
    if (u.token.empty() || !extra.empty()) throw std::invalid_argument(where + ": expected NAME TOKEN");
    if (u.name == "admin" || u.name.size() > 64 || !printable(u.name))
      throw std::invalid_argument(where + ": a name is 1..64 printable characters, not 'admin'");
    if (u.token.size() > limits::kMaxTokenLength) throw std::invalid_argument(where + ": the token is too long");
    if (!names.insert(u.name).second) throw std::invalid_argument(where + ": the name " + u.name + " is used twice");
    out.push_back(std::move(u));
  }
  return out;
}

}  // namespace peakcast::net
