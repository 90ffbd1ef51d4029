#pragma once
// The files of an evaluation: ground truth, expected counts, the objects a map directory
// claims, and the changes between two sessions, real and reported. Every reader answers false
// with a reason naming the file and the entry.

#include <map>
#include <string>
#include <vector>

#include "evaluation/change_evaluation.h"
#include "evaluation/evaluation.h"

namespace objmap {

/// ground_truth.json:
///   {"objects": [{"id": 1, "class": "cup",
///                 "pose": [16 numbers: the 4x4 box-to-world transform, row by row],
///                 "size": [x, y, z] (box extents along its axes, metres),
///                 "surface_sample": [[x, y, z], ...] (world frame; optional),
///                 "surface_mesh": {"vertices": [[x, y, z], ...], "triangles": [[i, j, k], ...]}
///                 (world frame; optional: model accuracy is then measured to it)}, ...]}
/// Classes are COCO names.
[[nodiscard]] bool ReadGroundTruth(const std::string& path, std::vector<GroundTruthObject>* objects,
                                   std::string* why);

/// The seen surface a ground-truth file names: {"seen_surface": {"voxel_size_m": 0.01,
/// "structure": "seen_structure.ply", "objects": "seen_objects.ply"}} (paths relative to the
/// file). `*present` is false, and the call true, when the file names none.
[[nodiscard]] bool ReadSeenSurface(const std::string& ground_truth_path, SeenSurface* surface,
                                   bool* present, std::string* why);

/// Expected counts per class, for data without object poses: {"chair": 4, "tv": [1, 2], ...}
/// (a number, or an inclusive [min, max] range).
[[nodiscard]] bool ReadExpectedCounts(const std::string& path, std::map<int, CountRange>* counts,
                                      std::string* why);

/// The objects a map claims, from a directory written by `objmap map --out` (objects.json with
/// "in_inventory", models in objects/<id>_<class>.ply) or by `objmap export --objects`
/// (objects.json with "confirmed" and "ply"): its inventory objects, with their models.
[[nodiscard]] bool ReadMapDirectory(const std::string& dir, std::vector<MappedObject>* objects,
                                    std::string* why);

/// The changes a simulated scene went through between two sessions (changes.json in the second
/// session's folder):
///   {"format": "objmap-changes-1", "kind": "office", "seed": 3,
///    "removed": [{"id": 4, "class": "cup", "position": [x, y, z]}, ...],
///    "moved":   [{"id": 7, "class": "chair", "from": [x, y, z], "to": [x, y, z]}, ...],
///    "added":   [{"id": 21, "class": "book", "position": [x, y, z]}, ...]}
/// (box centres in the world frame, metres; ids of the ground truth; COCO class names; a kind
/// with no changes may be left out; other keys such as "name" are ignored).
[[nodiscard]] bool ReadGroundTruthChanges(const std::string& path,
                                          std::vector<GroundTruthChange>* changes,
                                          std::string* why);

/// The changes a map reports (changes.json in a folder written by `objmap map --map`):
///   {"format": "objmap-map-changes-1",
///    "changes": [{"kind": "added" | "removed" | "moved", "object_id": 12, "class": "cup",
///                 "session_id": 2, "keyframe_id": 57, "stamp": 12.3,
///                 "position": [x, y, z], "from": [x, y, z] (moved only),
///                 "min": [x, y, z], "max": [x, y, z]}, ...]}
/// "session_id", "keyframe_id", "stamp", "min" and "max" are optional; "class" may also be
/// "unknown".
[[nodiscard]] bool ReadReportedChanges(const std::string& path,
                                       std::vector<ReportedChange>* changes, std::string* why);

}  // namespace objmap
