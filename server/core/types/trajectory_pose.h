#pragma once

#include <Eigen/Geometry>

namespace objmap {

/// One pose of a camera trajectory: T_W_C at `stamp_s` (seconds).
struct TrajectoryPose {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

}  // namespace objmap
