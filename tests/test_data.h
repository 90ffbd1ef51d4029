#pragma once
// Where the tests find ../shared data and the converted detector model. Tests that need data
// the machine lacks call GTEST_SKIP() with the path they looked for, so a skip is never silent.

#include <filesystem>
#include <string>

namespace objmap::testing {

inline std::string SharedDataPath(const std::string& relative) {
  return std::string(OBJMAP_SHARED_DIR) + "/data/" + relative;
}

inline bool Exists(const std::string& path) { return std::filesystem::exists(path); }

}  // namespace objmap::testing

#define OBJMAP_REQUIRE_PATH(path)                                                     \
  do {                                                                                \
    if (!objmap::testing::Exists(path)) {                                             \
      GTEST_SKIP() << "SKIPPED: needs " << (path) << " (absent on this machine)";     \
    }                                                                                 \
  } while (0)
