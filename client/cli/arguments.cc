#include "arguments.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace objmap::cli {

Arguments::Arguments(int argc, char** argv, const std::set<std::string>& flags_with_value,
                     const std::set<std::string>& switches,
                     const std::map<std::string, int>& flags_with_values) {
  const auto is_option = [&](const std::string& word) {
    return switches.count(word) > 0 || flags_with_value.count(word) > 0 ||
           flags_with_values.count(word) > 0;
  };
  // The values of `flag` start at argv[i + 1]; false with an error when fewer than n remain.
  const auto has_values = [&](const std::string& flag, int i, int n) {
    for (int k = 1; k <= n; ++k) {
      if (i + k >= argc || is_option(argv[i + k])) {
        SetError(flag + (n == 1 ? " needs a value" : " needs " + std::to_string(n) + " values"));
        return false;
      }
    }
    return true;
  };
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    const auto list = flags_with_values.find(word);
    if (word.rfind("--", 0) != 0) {
      positional_.push_back(word);
    } else if (switches.count(word) > 0) {
      values_[word] = "1";
    } else if (flags_with_value.count(word) > 0) {
      if (!has_values(word, i, 1)) return;
      values_[word] = argv[++i];
    } else if (list != flags_with_values.end()) {
      if (!has_values(word, i, list->second)) return;
      lists_[word].assign(argv + i + 1, argv + i + 1 + list->second);
      i += list->second;
    } else {
      SetError("unknown option " + word);
      return;
    }
  }
}

void Arguments::SetError(const std::string& error) {
  if (error_.empty()) error_ = error;
}

std::string Arguments::Get(const std::string& flag, const std::string& fallback) const {
  auto it = values_.find(flag);
  return it == values_.end() ? fallback : it->second;
}

double Arguments::GetNumber(const std::string& flag, double fallback) {
  auto it = values_.find(flag);
  if (it == values_.end()) return fallback;
  double value = 0.0;
  if (!ParseNumber(it->second, &value)) {
    SetError(flag + " expects a number, got '" + it->second + "'");
    return fallback;
  }
  return value;
}

std::int64_t Arguments::GetInteger(const std::string& flag, std::int64_t fallback,
                                   std::int64_t min_value) {
  auto it = values_.find(flag);
  if (it == values_.end()) return fallback;
  std::int64_t value = 0;
  if (!ParseInteger(it->second, &value) || value < min_value) {
    SetError(flag + " expects a whole number" +
             (min_value == std::numeric_limits<std::int64_t>::min()
                  ? ""
                  : " >= " + std::to_string(min_value)) +
             ", got '" + it->second + "'");
    return fallback;
  }
  return value;
}

std::vector<double> Arguments::GetNumbers(const std::string& flag) {
  auto it = lists_.find(flag);
  if (it == lists_.end()) return {};
  std::vector<double> numbers(it->second.size());
  for (std::size_t k = 0; k < numbers.size(); ++k) {
    if (!ParseNumber(it->second[k], &numbers[k])) {
      SetError(flag + " expects numbers, got '" + it->second[k] + "' as value " +
               std::to_string(k + 1));
      return {};
    }
  }
  return numbers;
}

double Arguments::PositionalNumber(std::size_t index, const std::string& what) {
  double value = 0.0;
  if (index >= positional_.size()) {
    SetError("missing " + what);
  } else if (!ParseNumber(positional_[index], &value)) {
    SetError(what + " expects a number, got '" + positional_[index] + "'");
  }
  return value;
}

bool ParseNumber(const std::string& text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && std::isfinite(*value);
}

bool ParseInteger(const std::string& text, std::int64_t* value) {
  char* end = nullptr;
  errno = 0;
  const long long parsed = std::strtoll(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE) return false;
  *value = parsed;
  return true;
}

}  // namespace objmap::cli
