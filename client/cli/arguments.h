#pragma once
// A small command-line parser: positional arguments and --flag [value] options.

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace objmap::cli {

class Arguments {
 public:
  /// `flags_with_value` take the next word as their value; `switches` take none. Anything else
  /// starting with "--" is an error, reported by error().
  Arguments(int argc, char** argv, const std::set<std::string>& flags_with_value,
            const std::set<std::string>& switches);

  [[nodiscard]] const std::vector<std::string>& positional() const { return positional_; }
  [[nodiscard]] bool Has(const std::string& flag) const { return values_.count(flag) > 0; }
  [[nodiscard]] std::string Get(const std::string& flag, const std::string& fallback) const;
  /// Parses a number; records an error naming the flag when the value is not one.
  [[nodiscard]] double GetNumber(const std::string& flag, double fallback);
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::string error_;
};

}  // namespace objmap::cli
