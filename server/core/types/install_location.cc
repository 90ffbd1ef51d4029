#include "types/install_location.h"

#include <cstdlib>
#include <filesystem>

namespace objmap {
namespace {

namespace fs = std::filesystem;

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

}  // namespace

std::vector<DataCandidate> InstalledDataCandidates(const std::string& share_path,
                                                   const char* variable,
                                                   const std::string& build_tree,
                                                   const std::string& source_path) {
  std::vector<DataCandidate> candidates;
  const fs::path executable = ExecutablePath();
  if (!executable.empty()) {
    const fs::path prefix = executable.parent_path().parent_path();
    candidates.push_back(
        {(prefix / "share" / "objmap" / share_path).string(), "next to the executable"});
  }
  const char* value = std::getenv(variable);
  candidates.push_back({value ? std::string(value) : std::string(), std::string("$") + variable});
  if (!build_tree.empty() && !executable.empty()) {
    std::error_code error;
    const fs::path tree = fs::weakly_canonical(fs::path(build_tree), error);
    if (!error && IsInside(executable.lexically_normal(), tree)) {
      candidates.push_back({source_path, "the source tree (a build-tree run)"});
    }
  }
  return candidates;
}

}  // namespace objmap
