#include "detection/model_location.h"

#include <cstdlib>
#include <filesystem>

namespace objmap {
namespace {

namespace fs = std::filesystem;

bool IsFile(const std::string& path) {
  std::error_code error;
  return !path.empty() && fs::is_regular_file(path, error);
}

constexpr char kInstallHint[] =
    "install it with `bash scripts/setup.sh` (or scripts/fetch_model.sh) and `cmake --install "
    "build --prefix PREFIX`, set OBJMAP_MODEL=FILE, or pass --model FILE";

}  // namespace

std::vector<ModelCandidate> DetectorModelCandidates() {
#if defined(OBJMAP_BUILD_TREE) && defined(OBJMAP_SOURCE_MODEL_PATH)
  return InstalledDataCandidates(std::string("models/") + kDetectorModelFile, kDetectorModelEnv,
                                 OBJMAP_BUILD_TREE, OBJMAP_SOURCE_MODEL_PATH);
#else
  return InstalledDataCandidates(std::string("models/") + kDetectorModelFile, kDetectorModelEnv,
                                 "", "");
#endif
}

bool FindDetectorModel(const std::string& configured, std::string* path, std::string* why) {
  if (!configured.empty()) {
    if (IsFile(configured)) {
      *path = configured;
      return true;
    }
    *why = "detector model " + configured +
           " not found (the path given by --model or "
           "detector.model_path); " +
           kInstallHint;
    return false;
  }
  std::string looked;
  for (const ModelCandidate& candidate : DetectorModelCandidates()) {
    if (IsFile(candidate.path)) {
      *path = candidate.path;
      return true;
    }
    looked += "\n  " + candidate.origin + ": " +
              (candidate.path.empty() ? std::string("not set") : candidate.path + " (absent)");
  }
  *why = std::string("detector model ") + kDetectorModelFile + " not found; looked in:" + looked +
         "\n" + kInstallHint;
  return false;
}

}  // namespace objmap
