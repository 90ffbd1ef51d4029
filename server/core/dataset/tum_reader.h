#pragma once

#include <memory>
#include <string>

#include "dataset/sequence_reader.h"

namespace objmap {

/// How TUM RGB-D streams are paired.
struct TumReaderConfig {
  /// Largest colour/depth timestamp difference accepted for a pair, seconds.
  double max_color_depth_dt_s = 0.02;
  /// Largest gap between the two ground-truth poses a depth stamp is interpolated between.
  double max_pose_gap_s = 0.1;
  /// Raw depth units per metre (TUM: 5000).
  double depth_units_per_metre = 5000.0;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// TUM RGB-D layout: rgb.txt, depth.txt, groundtruth.txt (timestamp tx ty tz qx qy qz qw).
/// Each depth image is paired with the nearest colour image and a pose interpolated from the
/// ground truth; depth images without both are left out. Intrinsics come from
/// camera-intrinsics.txt (3x3) when present, else the ROS defaults (525, 525, 319.5, 239.5).
[[nodiscard]] std::unique_ptr<SequenceReader> OpenTum(const std::string& folder,
                                                      const TumReaderConfig& config,
                                                      std::string* why);

}  // namespace objmap
