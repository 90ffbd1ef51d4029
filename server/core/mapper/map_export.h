#pragma once

#include <string>

#include "mapper/mapper.h"

namespace objmap {

/// Writes a mapping result into `out_dir` (created if needed):
///  - map.bt: the occupancy of the non-object structure (standard OctoMap binary, octovis opens it)
///  - objects.json: every object (id, class, confidence, per-class scores, observations, the
///    number of keyframes whose view holds it, centroid, bounding box, in_inventory)
///  - objects/<id>_<class>.ply: the coloured 5 mm model of every object in the inventory (other
///    .ply files there, from an earlier write of the folder, are removed).
/// False with a reason naming the file on any I/O error.
[[nodiscard]] bool WriteMapOutputs(const Mapper& mapper, const std::string& out_dir,
                                   std::string* why);

/// The objects.json document as text (also used by tests).
[[nodiscard]] std::string ObjectsJson(const Mapper& mapper);

}  // namespace objmap
