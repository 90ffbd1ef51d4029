#pragma once
// The poses file of `objmap update-poses`: one keyframe pose a line, in TUM order,
//   keyframe_id tx ty tz qx qy qz qw
// with '#' starting a comment and blank lines ignored. T_W_C maps camera into world points.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "types/frame.h"

namespace objmap::cli {

struct KeyframePoseLine {
  KeyframeId keyframe_id = 0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  int line = 0;  ///< 1-based line number in the file
};

/// Parses the text of a poses file. Quaternions within 1% of unit length are normalized. False
/// with "line N: ..." on a malformed line (field count, a non-number, a non-integer id, NaN,
/// a quaternion far from unit length), a keyframe given twice, or a file without poses.
[[nodiscard]] bool ParsePosesText(const std::string& text, std::vector<KeyframePoseLine>* poses,
                                  std::string* why);

/// One line of a poses file, `keyframe_id tx ty tz qx qy qz qw  # comment\n` (9 significant
/// digits; the quaternion as given), the comment left out when empty.
[[nodiscard]] std::string FormatPoseLine(KeyframeId keyframe_id, const Eigen::Vector3d& t,
                                         const Eigen::Quaterniond& q, const std::string& comment);

/// Reads and parses a poses file; the reason on failure starts with the path.
[[nodiscard]] bool ReadPosesFile(const std::string& path, std::vector<KeyframePoseLine>* poses,
                                 std::string* why);

}  // namespace objmap::cli
