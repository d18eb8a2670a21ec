// Who a request is (docs/security.md): the admin token (--token, --token-file) may do everything;
// each user token (--user-token-file, lines "NAME TOKEN") may view, render and upload, and delete
// only the uploads it made. With no token configured the server is open: every client is the
// admin. Tokens are compared in constant time (tokens_equal), each against every configured one.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace peakcast::net {

struct UserToken {
  std::string name, token;
};

struct Principal {
  bool authorized = false;
  bool admin = false;
  std::string name;  // "admin", a user's name; empty on an open server
};

class Access {
 public:
  Access() = default;
  Access(std::string admin_token, std::vector<UserToken> users);
  bool required() const { return !admin_.empty() || !users_.empty(); }
  Principal who(const std::string& token) const;

 private:
  std::string admin_;
  std::vector<UserToken> users_;
};

// The first line of `file`, trimmed; throws std::invalid_argument when the file cannot be read or
// holds no token.
std::string read_token_file(const std::filesystem::path& file);
// "NAME TOKEN" a line; blank lines and lines starting with '#' skipped. Throws
// std::invalid_argument naming the line that is wrong (the token itself is never repeated).
std::vector<UserToken> read_user_tokens(const std::filesystem::path& file);

}  // namespace peakcast::net
