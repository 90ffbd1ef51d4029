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

// The running executable's path, resolved through /proc (Linux); empty when unreadable.
fs::path ExecutablePath() {
  std::error_code error;
  fs::path path = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::path() : path;
}

// True when `path` lies inside `folder` (both absolute and normal).
bool IsInside(const fs::path& path, const fs::path& folder) {
  const fs::path relative = path.lexically_relative(folder);
  return !relative.empty() && *relative.begin() != "..";
}

constexpr char kInstallHint[] =
    "install it with `bash scripts/setup.sh` (or scripts/fetch_model.sh) and `cmake --install "
    "build --prefix PREFIX`, set OBJMAP_MODEL=FILE, or pass --model FILE";

}  // namespace

std::vector<ModelCandidate> DetectorModelCandidates() {
  std::vector<ModelCandidate> candidates;
  const fs::path executable = ExecutablePath();
  if (!executable.empty()) {
    const fs::path prefix = executable.parent_path().parent_path();
    candidates.push_back({(prefix / "share" / "objmap" / "models" / kDetectorModelFile).string(),
                          "next to the executable"});
  }
  const char* variable = std::getenv(kDetectorModelEnv);
  candidates.push_back(
      {variable ? std::string(variable) : std::string(), std::string("$") + kDetectorModelEnv});
#if defined(OBJMAP_BUILD_TREE) && defined(OBJMAP_SOURCE_MODEL_PATH)
  std::error_code error;
  const fs::path build_tree = fs::weakly_canonical(fs::path(OBJMAP_BUILD_TREE), error);
  if (!executable.empty() && !error && IsInside(executable.lexically_normal(), build_tree)) {
    candidates.push_back({OBJMAP_SOURCE_MODEL_PATH, "the source tree (a build-tree run)"});
  }
#else
  (void)IsInside;
#endif
  return candidates;
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
