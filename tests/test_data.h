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

/// Why a suite that maps `dataset_path` with the detector at `model_path` cannot run on this
/// machine ("SKIPPED: needs ..."), or empty when both are there.
inline std::string DatasetAndModelSkipReason(const std::string& dataset_path,
                                             const std::string& model_path) {
  if (!Exists(dataset_path)) return "SKIPPED: needs " + dataset_path + " (absent on this machine)";
  if (!Exists(model_path)) {
    return "SKIPPED: needs the detector model " + model_path + " (bash scripts/fetch_model.sh)";
  }
  return "";
}

}  // namespace objmap::testing

#define OBJMAP_REQUIRE_PATH(path)                                                     \
  do {                                                                                \
    if (!objmap::testing::Exists(path)) {                                             \
      GTEST_SKIP() << "SKIPPED: needs " << (path) << " (absent on this machine)";     \
    }                                                                                 \
  } while (0)
