#include "evaluation/trajectory_evaluation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iterator>

namespace objmap {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

// The reference pose nearest `stamp` in `reference` (sorted by stamp), or null when none is
// within `tolerance`.
const TrajectoryPose* Nearest(const std::vector<TrajectoryPose>& reference, double stamp,
                              double tolerance) {
  const auto after = std::lower_bound(
      reference.begin(), reference.end(), stamp,
      [](const TrajectoryPose& pose, double value) { return pose.stamp_s < value; });
  const TrajectoryPose* best = nullptr;
  double best_gap = tolerance;
  for (auto it : {after, after == reference.begin() ? reference.end() : std::prev(after)}) {
    if (it == reference.end()) continue;
    const double gap = std::abs(it->stamp_s - stamp);
    if (gap <= best_gap) {
      best_gap = gap;
      best = &*it;
    }
  }
  return best;
}

double RotationAngleRad(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle();
}

}  // namespace

bool TrajectoryEvaluationConfig::IsValid(std::string* why) const {
  if (!(max_stamp_difference_s >= 0.0) || !std::isfinite(max_stamp_difference_s)) {
    *why = "the stamp tolerance must be finite and >= 0";
    return false;
  }
  if (!(rpe_distance_m > 0.0) || !std::isfinite(rpe_distance_m)) {
    *why = "the relative-error distance must be finite and positive";
    return false;
  }
  return true;
}

bool EvaluateTrajectory(const std::vector<TrajectoryPose>& estimated,
                        const std::vector<TrajectoryPose>& reference,
                        const TrajectoryEvaluationConfig& config, TrajectoryErrors* errors,
                        std::string* why) {
  if (!config.IsValid(why)) return false;
  *errors = TrajectoryErrors{};
  errors->estimated = estimated.size();
  errors->reference = reference.size();
  std::vector<const TrajectoryPose*> matched_estimated, matched_reference;
  for (const TrajectoryPose& pose : estimated) {
    const TrajectoryPose* match = Nearest(reference, pose.stamp_s, config.max_stamp_difference_s);
    if (match == nullptr) continue;
    matched_estimated.push_back(&pose);
    matched_reference.push_back(match);
  }
  const std::size_t n = matched_estimated.size();
  errors->matched = n;
  if (n < 3) {
    *why = std::to_string(n) + " of " + std::to_string(estimated.size()) +
           " estimated poses have a reference pose within " +
           std::to_string(config.max_stamp_difference_s) +
           " s of their stamp; at least 3 are needed to align the trajectories";
    return false;
  }

  // Horn / Umeyama without scale: the rotation and translation that map the estimated positions
  // onto the reference ones in the least-squares sense.
  Eigen::Matrix3Xd from(3, static_cast<Eigen::Index>(n)), to(3, static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    from.col(static_cast<Eigen::Index>(i)) = matched_estimated[i]->T_W_C.translation();
    to.col(static_cast<Eigen::Index>(i)) = matched_reference[i]->T_W_C.translation();
  }
  errors->T_reference_estimated.matrix() = Eigen::umeyama(from, to, /*with_scaling=*/false);

  std::vector<double> distances(n);
  double sum = 0.0, sum_sq = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>(i);
    distances[i] = (errors->T_reference_estimated * from.col(c) - to.col(c)).norm();
    sum += distances[i];
    sum_sq += distances[i] * distances[i];
    errors->ate_per_pose.emplace_back(matched_estimated[i]->stamp_s, distances[i]);
  }
  errors->ate_rmse_m = std::sqrt(sum_sq / static_cast<double>(n));
  errors->ate_mean_m = sum / static_cast<double>(n);
  errors->ate_max_m = *std::max_element(distances.begin(), distances.end());
  std::vector<double> sorted = distances;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n / 2),
                   sorted.end());
  errors->ate_median_m = sorted[n / 2];

  // Relative error: path length along the reference, then from each pose the first pose at
  // least rpe_distance_m of path further on. Alignment does not enter (motions are relative).
  std::vector<double> path(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) {
    path[i] = path[i - 1] + (matched_reference[i]->T_W_C.translation() -
                             matched_reference[i - 1]->T_W_C.translation())
                                .norm();
  }
  double translation_sum = 0.0, rotation_sum = 0.0;
  std::size_t end = 0;
  for (std::size_t start = 0; start < n; ++start) {
    end = std::max(end, start + 1);
    while (end < n && path[end] - path[start] < config.rpe_distance_m) ++end;
    if (end >= n) break;
    const double length = path[end] - path[start];
    const Eigen::Isometry3d reference_motion =
        matched_reference[start]->T_W_C.inverse() * matched_reference[end]->T_W_C;
    const Eigen::Isometry3d estimated_motion =
        matched_estimated[start]->T_W_C.inverse() * matched_estimated[end]->T_W_C;
    const Eigen::Isometry3d error = reference_motion.inverse() * estimated_motion;
    translation_sum += error.translation().norm() / length;
    rotation_sum += RotationAngleRad(error.linear()) * kRadToDeg / length;
    ++errors->rpe_pairs;
  }
  if (errors->rpe_pairs > 0) {
    errors->rpe_translation_percent =
        100.0 * translation_sum / static_cast<double>(errors->rpe_pairs);
    errors->rpe_rotation_deg_per_m = rotation_sum / static_cast<double>(errors->rpe_pairs);
  }
  return true;
}

}  // namespace objmap
