#pragma once
// The keyframes of a map whose poses the odometry gave: each remembered as (the odometry keyframe
// it was tracked against, its pose relative to that one). Loop closures move the odometry's
// keyframes; Poses() then gives every map keyframe's corrected pose, ready for a pose update.

#include <Eigen/Geometry>
#include <map>
#include <utility>

#include "odometry/rgbd_odometry.h"

namespace objmap {

/// Where the frame `report` tracked lies on the odometry keyframe it was tracked against.
[[nodiscard]] inline Eigen::Isometry3d PoseOnReferenceKeyframe(const TrackingReport& report,
                                                               const RgbdOdometry& odometry) {
  return odometry.KeyframePose(report.reference_keyframe).inverse() * report.T_W_C;
}

class TrackedKeyframes {
 public:
  /// `report` is the tracking of the frame that became map keyframe `id` (not kLost).
  void Add(KeyframeId id, const TrackingReport& report, const RgbdOdometry& odometry) {
    on_keyframe_[id] = {report.reference_keyframe, PoseOnReferenceKeyframe(report, odometry)};
  }

  /// Map keyframe `id`, `T_K_C` from odometry keyframe `keyframe` (a keyframe held while its
  /// fragment was provisional: where it lies on its keyframe does not change with the frame).
  void AddRelative(KeyframeId id, int keyframe, const Eigen::Isometry3d& T_K_C) {
    on_keyframe_[id] = {keyframe, T_K_C};
  }

  /// Every map keyframe's pose as the odometry's keyframes now stand.
  [[nodiscard]] std::map<KeyframeId, Eigen::Isometry3d> Poses(const RgbdOdometry& odometry) const {
    std::map<KeyframeId, Eigen::Isometry3d> poses;
    for (const auto& [id, on_keyframe] : on_keyframe_) {
      poses.emplace(id, odometry.KeyframePose(on_keyframe.first) * on_keyframe.second);
    }
    return poses;
  }

  [[nodiscard]] bool empty() const { return on_keyframe_.empty(); }

 private:
  std::map<KeyframeId, std::pair<int, Eigen::Isometry3d>> on_keyframe_;
};

}  // namespace objmap
