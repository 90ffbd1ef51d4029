#pragma once
// The files of an evaluation: ground truth, expected counts, and the objects a map directory
// claims. Every reader answers false with a reason naming the file and the entry.

#include <map>
#include <string>
#include <vector>

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

}  // namespace objmap
