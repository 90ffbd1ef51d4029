#pragma once
// Scoring an estimated camera trajectory against a reference one (objmap eval-trajectory): the
// absolute trajectory error after the rigid alignment that fits them best (Horn's method, as
// the TUM RGB-D benchmark computes it) and the relative error over stretches of a given length.

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "types/trajectory_pose.h"

namespace objmap {

struct TrajectoryEvaluationConfig {
  /// An estimated pose is paired with the reference pose nearest its stamp when they are at most
  /// this far apart, seconds.
  double max_stamp_difference_s = 0.02;
  /// Relative error over pairs of matched poses this far apart along the reference path, metres
  /// (each matched pose starts one pair: the first pose at least this much path later ends it).
  double rpe_distance_m = 1.0;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

struct TrajectoryErrors {
  std::size_t estimated = 0;  ///< poses in the estimated trajectory
  std::size_t reference = 0;  ///< poses in the reference trajectory
  std::size_t matched = 0;    ///< estimated poses with a reference pose within the tolerance
  /// The rigid transform that maps estimated positions onto reference ones best (least squares);
  /// the absolute errors are measured after it.
  Eigen::Isometry3d T_reference_estimated = Eigen::Isometry3d::Identity();
  /// Absolute trajectory error: distances between aligned estimated and reference positions.
  double ate_rmse_m = 0.0;
  double ate_mean_m = 0.0;
  double ate_median_m = 0.0;
  double ate_max_m = 0.0;
  /// Relative pose error over `rpe_distance_m` stretches: the motion between the two poses of a
  /// pair as estimated against as referenced, translation error per metre travelled (percent)
  /// and rotation error per metre (degrees). No pairs when the path is shorter.
  std::size_t rpe_pairs = 0;
  double rpe_translation_percent = 0.0;  ///< mean over pairs
  double rpe_rotation_deg_per_m = 0.0;   ///< mean over pairs
  /// Per matched pose, in estimated order: its stamp and its absolute error, metres.
  std::vector<std::pair<double, double>> ate_per_pose;
};

/// Scores `estimated` against `reference` (both sorted by stamp, as ReadTumTrajectory returns
/// them). False with the reason when fewer than 3 poses match (no alignment is defined).
[[nodiscard]] bool EvaluateTrajectory(const std::vector<TrajectoryPose>& estimated,
                                      const std::vector<TrajectoryPose>& reference,
                                      const TrajectoryEvaluationConfig& config,
                                      TrajectoryErrors* errors, std::string* why);

}  // namespace objmap
