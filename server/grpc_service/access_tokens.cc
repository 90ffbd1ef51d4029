#include "grpc_service/access_tokens.h"

#include <sys/stat.h>

#include <fstream>
#include <sstream>

namespace objmap::grpc_service {
namespace {

bool ValidToken(const std::string& token) {
  if (token.size() < AccessTokens::kMinTokenBytes) return false;
  for (const char c : token) {
    if (c <= ' ' || c > '~') return false;
  }
  return true;
}

// Equal in constant time for equal sizes: a client cannot learn a token byte by byte from the
// answer's timing.
bool SameToken(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    difference |= static_cast<unsigned char>(a[i] ^ b[i]);
  }
  return difference == 0;
}

}  // namespace

bool AccessTokens::Parse(const std::string& text, const std::string& source, AccessTokens* tokens,
                         std::string* why) {
  AccessTokens parsed;
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string access, token, extra;
    if (!(words >> access) || access[0] == '#') continue;
    const std::string where = source + ":" + std::to_string(number) + ": ";
    if (access != "read" && access != "write") {
      *why = where + "expected 'read TOKEN' or 'write TOKEN'";
      return false;
    }
    if (!(words >> token) || (words >> extra)) {
      *why = where + "expected one token after '" + access + "'";
      return false;
    }
    if (!ValidToken(token)) {
      *why = where + "a token is at least " + std::to_string(kMinTokenBytes) +
             " printable characters without spaces";
      return false;
    }
    for (const Entry& entry : parsed.entries_) {
      if (entry.token == token) {
        *why = where + "the token appears twice";
        return false;
      }
    }
    parsed.entries_.push_back({token, access == "write" ? Access::kReadWrite : Access::kRead});
  }
  if (parsed.entries_.empty()) {
    *why = source + ": no tokens (lines 'read TOKEN' or 'write TOKEN')";
    return false;
  }
  *tokens = std::move(parsed);
  return true;
}

bool AccessTokens::Load(const std::string& path, AccessTokens* tokens, std::string* why,
                        std::string* warning) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    *why = path + ": cannot read the token file";
    return false;
  }
  std::ostringstream text;
  text << file.rdbuf();
  if (!Parse(text.str(), path, tokens, why)) return false;
  struct stat info {};
  if (warning != nullptr && ::stat(path.c_str(), &info) == 0 && (info.st_mode & 077) != 0) {
    *warning = path + " is readable by other users (chmod 600 it)";
  }
  return true;
}

Access AccessTokens::Find(std::string_view token) const {
  Access found = Access::kNone;
  for (const Entry& entry : entries_) {
    if (SameToken(token, entry.token)) found = entry.access;
  }
  return found;
}

std::string_view BearerToken(std::string_view authorization) {
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization.size() <= kScheme.size() || authorization.substr(0, kScheme.size()) != kScheme) {
    return {};
  }
  return authorization.substr(kScheme.size());
}

}  // namespace objmap::grpc_service
