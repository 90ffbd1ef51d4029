#pragma once
// A small command-line parser: positional arguments and --flag [value...] options.

#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace objmap::cli {

class Arguments {
 public:
  /// `flags_with_value` take the next word as their value; `switches` take none;
  /// `flags_with_values` take the given number of words ("--region" -> 6). Anything else
  /// starting with "--" is an error, reported by error(), and so is a flag whose value is
  /// missing (the words run out, or the next word is another known option).
  Arguments(int argc, char** argv, const std::set<std::string>& flags_with_value,
            const std::set<std::string>& switches,
            const std::map<std::string, int>& flags_with_values = {});

  [[nodiscard]] const std::vector<std::string>& positional() const { return positional_; }
  [[nodiscard]] bool Has(const std::string& flag) const {
    return values_.count(flag) > 0 || lists_.count(flag) > 0;
  }
  [[nodiscard]] std::string Get(const std::string& flag, const std::string& fallback) const;
  /// Parses a finite number; records an error naming the flag when the value is not one.
  [[nodiscard]] double GetNumber(const std::string& flag, double fallback);
  /// Parses a whole number >= min_value; records an error naming the flag otherwise.
  [[nodiscard]] std::int64_t GetInteger(
      const std::string& flag, std::int64_t fallback,
      std::int64_t min_value = std::numeric_limits<std::int64_t>::min());
  /// The values of a flag from `flags_with_values` as finite numbers (empty when the flag is
  /// absent); records an error naming the flag when one is not a number.
  [[nodiscard]] std::vector<double> GetNumbers(const std::string& flag);
  /// Positional argument `index` as a finite number; records an error naming it as `what`
  /// ("X0") when it is missing or not a number.
  [[nodiscard]] double PositionalNumber(std::size_t index, const std::string& what);
  /// The first error met while parsing or converting; empty when there was none.
  [[nodiscard]] const std::string& error() const { return error_; }
  /// Records an error found by the caller (a value out of range); the first error is kept,
  /// since later ones are often consequences of it.
  void SetError(const std::string& error);

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::map<std::string, std::vector<std::string>> lists_;
  std::string error_;
};

/// Parses all of `text` as a finite number (no trailing characters, no NaN or infinity).
[[nodiscard]] bool ParseNumber(const std::string& text, double* value);

/// Parses all of `text` as a decimal integer that fits in 64 bits.
[[nodiscard]] bool ParseInteger(const std::string& text, std::int64_t* value);

}  // namespace objmap::cli
