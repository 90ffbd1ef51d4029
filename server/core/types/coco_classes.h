#pragma once

#include <string>
#include <string_view>

namespace objmap {

/// The 80 classes of COCO, in the order of the usual 80-way detector heads.
inline constexpr int kNumCocoClasses = 80;

/// Name of a COCO class index ("dining table"), or "" when out of range.
[[nodiscard]] std::string_view CocoClassName(int class_id);

/// Index of a COCO class name, or -1 when COCO has no such class. Accepts '_' for ' '.
[[nodiscard]] int CocoClassId(std::string_view name);

/// Class name made safe for file names ("dining table" -> "dining_table").
[[nodiscard]] std::string CocoClassFileName(int class_id);

}  // namespace objmap
