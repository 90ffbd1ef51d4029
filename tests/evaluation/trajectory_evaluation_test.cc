// EvaluateTrajectory against trajectories whose errors are known by construction: a rigidly
// moved copy (no error after alignment), known position noise, a known drift, missing stamps.

#include "evaluation/trajectory_evaluation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace objmap {
namespace {

// A camera on a 2 m circle at 0.1 m per pose, looking at the centre; stamps 1/30 s apart.
std::vector<TrajectoryPose> Circle(int count) {
  std::vector<TrajectoryPose> poses;
  for (int i = 0; i < count; ++i) {
    const double angle = 0.05 * i;
    TrajectoryPose pose;
    pose.stamp_s = 100.0 + i / 30.0;
    pose.T_W_C.translation() = Eigen::Vector3d(2.0 * std::cos(angle), 2.0 * std::sin(angle), 1.2);
    pose.T_W_C.linear() = Eigen::AngleAxisd(angle + M_PI, Eigen::Vector3d::UnitZ()).matrix();
    poses.push_back(pose);
  }
  return poses;
}

TEST(TrajectoryEvaluation, ARigidlyMovedCopyHasNoErrorAfterAlignment) {
  const std::vector<TrajectoryPose> reference = Circle(120);
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.5, 1.0).normalized()).matrix();
  moved.translation() = Eigen::Vector3d(3.0, -1.0, 0.4);
  std::vector<TrajectoryPose> estimated = reference;
  for (TrajectoryPose& pose : estimated) {
    pose.T_W_C = moved * pose.T_W_C;
    pose.stamp_s += 0.004;  // within the default tolerance
  }
  TrajectoryErrors errors;
  std::string why;
  ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
  EXPECT_EQ(errors.matched, 120u);
  EXPECT_LT(errors.ate_rmse_m, 1e-9);
  EXPECT_LT(errors.ate_max_m, 1e-9);
  EXPECT_TRUE(errors.T_reference_estimated.isApprox(moved.inverse(), 1e-9));
  EXPECT_GT(errors.rpe_pairs, 50u);
  EXPECT_LT(errors.rpe_translation_percent, 1e-7);
  EXPECT_LT(errors.rpe_rotation_deg_per_m, 1e-7);
}

TEST(TrajectoryEvaluation, PositionNoiseGivesItsRootMeanSquare) {
  const std::vector<TrajectoryPose> reference = Circle(400);
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 random(seed);
    std::normal_distribution<double> noise(0.0, 0.01);
    std::vector<TrajectoryPose> estimated = reference;
    for (TrajectoryPose& pose : estimated) {
      pose.T_W_C.translation() += Eigen::Vector3d(noise(random), noise(random), noise(random));
    }
    TrajectoryErrors errors;
    std::string why;
    ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
    // 1 cm per axis: sqrt(3) cm in 3D, less the little the alignment fits to the noise.
    EXPECT_NEAR(errors.ate_rmse_m, 0.01 * std::sqrt(3.0), 0.0015) << "seed " << seed;
    EXPECT_GT(errors.ate_max_m, errors.ate_rmse_m);
    EXPECT_LE(errors.ate_median_m, errors.ate_max_m);
  }
}

TEST(TrajectoryEvaluation, ADriftShowsInTheRelativeError) {
  // Along a straight line, every step 1 % too long: the relative translation error is 1 % of
  // the distance whatever the distance, and there is no rotation error.
  std::vector<TrajectoryPose> reference = Circle(200);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    reference[i].T_W_C.translation() = Eigen::Vector3d(0.02 * static_cast<double>(i), 0.5, 1.0);
    reference[i].T_W_C.linear() = reference[0].T_W_C.linear();
  }
  std::vector<TrajectoryPose> estimated = reference;
  for (std::size_t i = 1; i < estimated.size(); ++i) {
    const Eigen::Isometry3d step = reference[i - 1].T_W_C.inverse() * reference[i].T_W_C;
    Eigen::Isometry3d longer = step;
    longer.translation() *= 1.01;
    estimated[i].T_W_C = estimated[i - 1].T_W_C * longer;
  }
  for (double distance : {0.5, 1.0, 2.0}) {
    TrajectoryEvaluationConfig config;
    config.rpe_distance_m = distance;
    TrajectoryErrors errors;
    std::string why;
    ASSERT_TRUE(EvaluateTrajectory(estimated, reference, config, &errors, &why)) << why;
    EXPECT_NEAR(errors.rpe_translation_percent, 1.0, 0.01) << distance;
    EXPECT_LT(errors.rpe_rotation_deg_per_m, 1e-6);
    EXPECT_GT(errors.ate_rmse_m, 0.005);  // a line 1 % longer does not align exactly
  }
}

TEST(TrajectoryEvaluation, OnlyPosesWithAReferenceNearTheirStampCount) {
  const std::vector<TrajectoryPose> reference = Circle(60);
  std::vector<TrajectoryPose> estimated = reference;
  // Half a frame off the reference's stamps for every other pose.
  for (std::size_t i = 0; i < estimated.size(); i += 2) estimated[i].stamp_s += 0.5 + 1.0 / 60;
  std::sort(estimated.begin(), estimated.end(),
            [](const TrajectoryPose& a, const TrajectoryPose& b) { return a.stamp_s < b.stamp_s; });
  TrajectoryEvaluationConfig config;
  config.max_stamp_difference_s = 0.001;
  TrajectoryErrors errors;
  std::string why;
  ASSERT_TRUE(EvaluateTrajectory(estimated, reference, config, &errors, &why)) << why;
  EXPECT_EQ(errors.matched, 30u);
  EXPECT_EQ(errors.estimated, 60u);

  // Too few pairs: the reason says how many matched.
  const std::vector<TrajectoryPose> two(reference.begin(), reference.begin() + 2);
  EXPECT_FALSE(EvaluateTrajectory(two, reference, {}, &errors, &why));
  EXPECT_NE(why.find("2 of 2"), std::string::npos) << why;
  config.rpe_distance_m = 0.0;
  EXPECT_FALSE(EvaluateTrajectory(estimated, reference, config, &errors, &why));
}

}  // namespace
}  // namespace objmap
