#pragma once
// Where the detector model is found when no path is given, so that objmap, objmap_server and
// objmap_node work from any directory, installed or run from their build tree.

#include <string>
#include <vector>

#include "types/install_location.h"

namespace objmap {

/// The file name of the converted CenterNet model (scripts/fetch_model.sh writes it).
inline constexpr char kDetectorModelFile[] = "centernet_coco.pb";
/// The environment variable naming a model file.
inline constexpr char kDetectorModelEnv[] = "OBJMAP_MODEL";

using ModelCandidate = DataCandidate;

/// The places searched when no model path is configured, in order:
///   1. PREFIX/share/objmap/models/centernet_coco.pb, PREFIX being the executable's folder's
///      parent (an installed objmap: PREFIX/bin/objmap);
///   2. the file $OBJMAP_MODEL names;
///   3. the source tree's models/centernet_coco.pb, only for an executable inside the build tree
///      it was built in (a copied or installed binary does not reach back into the sources).
[[nodiscard]] std::vector<ModelCandidate> DetectorModelCandidates();

/// The model file to load: `configured` when not empty (a --model flag or detector.model_path;
/// relative to the working directory), else the first candidate that is a file. False with a
/// reason that lists every place looked at and how to install the model.
[[nodiscard]] bool FindDetectorModel(const std::string& configured, std::string* path,
                                     std::string* why);

}  // namespace objmap
