#pragma once
// Where objmap's executables find data installed beside them (the detector model, the viewer's
// web files), from any working directory, installed or run from their build tree.

#include <string>
#include <vector>

namespace objmap {

/// One place looked at, in order, and why it is there.
struct DataCandidate {
  std::string path;    ///< empty when the place does not apply (the variable is not set)
  std::string origin;  ///< "next to the executable", "$VARIABLE", "the source tree (...)"
};

/// The places searched for `share_path` (relative to PREFIX/share/objmap), in order:
///   1. PREFIX/share/objmap/`share_path`, PREFIX being the running executable's folder's parent
///      (an installed objmap: PREFIX/bin/objmap);
///   2. what the environment variable `variable` names;
///   3. `source_path`, only for an executable inside `build_tree` (a copied or installed binary
///      does not reach back into the sources); empty `build_tree`: never.
[[nodiscard]] std::vector<DataCandidate> InstalledDataCandidates(const std::string& share_path,
                                                                 const char* variable,
                                                                 const std::string& build_tree,
                                                                 const std::string& source_path);

}  // namespace objmap
