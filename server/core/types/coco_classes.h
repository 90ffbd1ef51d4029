#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace objmap {

/// The 80 classes of COCO, in the order of the usual 80-way detector heads.
inline constexpr int kNumCocoClasses = 80;

/// Name of a COCO class index ("dining table"), or "" when out of range.
[[nodiscard]] std::string_view CocoClassName(int class_id);

/// Index of a COCO class name, or -1 when COCO has no such class. Accepts '_' for ' '.
[[nodiscard]] int CocoClassId(std::string_view name);

/// Class name made safe for file names ("dining table" -> "dining_table"; "unknown" for
/// kUnknownClassId and out-of-range ids).
[[nodiscard]] std::string CocoClassFileName(int class_id);

/// The file of an object's model in a map folder's objects/ ("12_dining_table.ply"): what
/// `objmap map` writes and what the readers of its folders (eval, render, view) open.
[[nodiscard]] std::string ObjectModelFileName(std::int64_t object_id, int class_id);

/// The class of a map object that something persistent stands for but no detector has named
/// (an object-like segment on a supporting plane). Not a COCO class: detectors never report it.
inline constexpr int kUnknownClassId = kNumCocoClasses;
/// Classes a map object may have: the COCO classes and kUnknownClassId.
inline constexpr int kNumObjectClasses = kNumCocoClasses + 1;

/// Name of a map object's class: a COCO name, "unknown" for kUnknownClassId, "" out of range.
[[nodiscard]] std::string_view ObjectClassName(int class_id);

/// Index of a map object's class name: a COCO class, kUnknownClassId for "unknown", -1 otherwise.
[[nodiscard]] int ObjectClassId(std::string_view name);

}  // namespace objmap
