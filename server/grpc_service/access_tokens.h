#pragma once
// Bearer tokens of the map service: who may read the map, and who may also change it.

#include <string>
#include <string_view>
#include <vector>

namespace objmap::grpc_service {

enum class Access { kNone, kRead, kReadWrite };

/// Tokens read from a file, one per line: `read TOKEN` or `write TOKEN` (read and write);
/// empty lines and lines starting with # are skipped. Tokens are at least kMinTokenBytes of
/// printable ASCII without spaces. Tokens come from a file, never from the command line, where
/// every user of the machine could read them in the process list.
class AccessTokens {
 public:
  static constexpr std::size_t kMinTokenBytes = 16;

  /// False with a reason naming the file and the line. `warning` (may be null) receives a note
  /// when the file is readable by other users.
  [[nodiscard]] static bool Load(const std::string& path, AccessTokens* tokens, std::string* why,
                                 std::string* warning);
  /// Parses the file's text; `source` names it in reasons.
  [[nodiscard]] static bool Parse(const std::string& text, const std::string& source,
                                  AccessTokens* tokens, std::string* why);

  /// What `token` may do; every stored token is compared in full (time independent of where a
  /// guess differs).
  [[nodiscard]] Access Find(std::string_view token) const;
  [[nodiscard]] bool empty() const { return entries_.empty(); }

 private:
  struct Entry {
    std::string token;
    Access access;
  };
  std::vector<Entry> entries_;
};

/// The token of an `authorization: Bearer TOKEN` metadata value; empty when it is not one.
[[nodiscard]] std::string_view BearerToken(std::string_view authorization);

}  // namespace objmap::grpc_service
