#include "arguments.h"

#include <cstdlib>

namespace objmap::cli {

Arguments::Arguments(int argc, char** argv, const std::set<std::string>& flags_with_value,
                     const std::set<std::string>& switches) {
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.rfind("--", 0) != 0) {
      positional_.push_back(word);
    } else if (switches.count(word) > 0) {
      values_[word] = "1";
    } else if (flags_with_value.count(word) > 0) {
      if (i + 1 >= argc) {
        error_ = word + " needs a value";
        return;
      }
      values_[word] = argv[++i];
    } else {
      error_ = "unknown option " + word;
      return;
    }
  }
}

std::string Arguments::Get(const std::string& flag, const std::string& fallback) const {
  auto it = values_.find(flag);
  return it == values_.end() ? fallback : it->second;
}

double Arguments::GetNumber(const std::string& flag, double fallback) {
  auto it = values_.find(flag);
  if (it == values_.end()) return fallback;
  char* end = nullptr;
  const double value = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0') {
    error_ = flag + " expects a number, got '" + it->second + "'";
    return fallback;
  }
  return value;
}

}  // namespace objmap::cli
