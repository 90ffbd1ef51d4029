#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "mapper/mapper.h"

namespace objmap {

/// When a keyframe was taken: its session and camera stamp (0: not known).
struct KeyframeWhen {
  std::int64_t session_id = 0;
  double stamp_s = 0.0;
};
using KeyframeWhenLookup = std::function<KeyframeWhen(KeyframeId)>;

/// Writes a mapping result into `out_dir` (created if needed):
///  - map.bt: the occupancy of the non-object structure (standard OctoMap binary, octovis opens it)
///  - objects.json: every object of the present map under its published id (Mapper::Changes:
///    a moved object keeps its first id): class, confidence, per-class scores, observations, the
///    number of keyframes whose view holds it, centroid, bounding box, in_inventory, state
///    (present, moved) and the places it stood before; `removed`: the tombstones
///  - changes.json: every change (ChangeList), with the session and stamp of its keyframe when
///    `when` is given
///  - objects/<id>_<class>.ply: the coloured 5 mm model of every object in the inventory (other
///    .ply files there, from an earlier write of the folder, are removed).
/// False with a reason naming the file on any I/O error.
[[nodiscard]] bool WriteMapOutputs(const Mapper& mapper, const std::string& out_dir,
                                   std::string* why, const KeyframeWhenLookup& when = nullptr);

/// The objects.json document as text (also used by tests).
[[nodiscard]] std::string ObjectsJson(const Mapper& mapper);
/// The changes.json document as text: {"format": "objmap-map-changes-1", "changes": [{"kind",
/// "object_id", "class", "keyframe_id", "session_id", "stamp", "position", "min", "max",
/// "from" (moved)}]}.
[[nodiscard]] std::string ChangesJson(const Mapper& mapper,
                                      const KeyframeWhenLookup& when = nullptr);

}  // namespace objmap
