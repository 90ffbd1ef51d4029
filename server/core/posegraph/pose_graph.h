#pragma once
// Keyframe poses corrected by a pose graph: odometry edges between consecutive keyframes, loop
// edges between keyframes that see the same place, all SE(3) with an information matrix,
// optimized with Ceres. Loop edges pass through a robust loss, so a wrong loop (two similar
// places taken for one) is outweighed by the odometry instead of bending the whole map.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace objmap {

struct PoseGraphConfig {
  /// Scale of the Cauchy loss on loop edges, in whitened units (standard deviations): loops
  /// whose residual is well beyond it weigh little.
  double loop_loss_scale = 10.0;
  /// A loop whose whitened residual after optimization exceeds this (chi-square, 6 degrees of
  /// freedom, 99.9 %: 22.46) is reported as rejected.
  double loop_rejection_chi2 = 22.46;
  int max_iterations = 100;
  int threads = 1;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// A relative pose measurement: T_from_to maps `to`'s frame into `from`'s
/// (T_W_to = T_W_from * T_from_to). Information: the inverse covariance of the error
/// [translation (m); rotation (rad, small angles)], both in `from`'s frame, translation first.
struct PoseGraphEdge {
  int from = 0;
  int to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  bool loop = false;
};

struct PoseGraphReport {
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double solve_ms = 0.0;
  int loops = 0;
  /// Loop edges dropped because they disagreed with the rest of the graph (wrong loops), in the
  /// order dropped; indices into edges().
  std::vector<int> rejected_loops;
};

/// How an alignment's Hessian becomes an edge's information (AlignmentInformation).
struct AlignmentInformationConfig {
  /// The least uncertainty an edge claims in any direction: the points of an alignment are not
  /// independent (depth bias, calibration, colour not registered to depth), so the Hessian alone
  /// overstates the accuracy.
  double floor_sigma_m = 0.01;
  double floor_sigma_deg = 0.5;
  /// FixedDirectionsOf's min_ratio: weaker directions keep no information.
  double min_eigenvalue_ratio = 0.05;
};

/// The directions an alignment fixes (Zhang, Kaess and Singh, "On degeneracy of
/// optimization-based state estimation problems", ICRA 2016): the eigenvectors of its
/// Gauss-Newton Hessian H (increments [dt; dtheta] turning about the points' centre), with
/// rotations scaled by the points' radius so that both kinds are metres of point motion, whose
/// eigenvalue reaches min_ratio of the largest. The others (along a flat screen, about its
/// normal) are free: noise in the normals gives them a little curvature that is not information.
struct FixedDirections {
  /// S: scaled increments are S^-1 [dt; dtheta].
  Eigen::Matrix<double, 6, 6> scale = Eigen::Matrix<double, 6, 6>::Identity();
  /// Eigenvectors of S H S, as columns, and their eigenvalues; 0 where the direction is free.
  Eigen::Matrix<double, 6, 6> vectors = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> values = Eigen::Matrix<double, 6, 1>::Zero();
};
[[nodiscard]] FixedDirections FixedDirectionsOf(const Eigen::Matrix<double, 6, 6>& H,
                                                double radius_m, double min_ratio);

/// The information matrix of T_from_to (PoseGraphEdge convention) measured by an alignment of
/// `to`'s points onto `from`'s: H is its whitened Gauss-Newton Hessian (residuals divided by
/// their sigma) at the optimum for increments [dt; dtheta] that move a point q (in `from`'s
/// frame) to q + dt + dtheta x (q - centre); radius_m is the spread of the points about
/// `centre`; to_origin is T_from_to's translation. Free directions keep next to no information
/// (a prior of 1 m and 1 rad), fixed ones at most the floor's.
[[nodiscard]] Eigen::Matrix<double, 6, 6> AlignmentInformation(
    const Eigen::Matrix<double, 6, 6>& H, const Eigen::Vector3d& centre, double radius_m,
    const Eigen::Vector3d& to_origin, const AlignmentInformationConfig& config);

/// Thread-safety: none.
class PoseGraph {
 public:
  explicit PoseGraph(const PoseGraphConfig& config = {});

  /// A node with its initial pose; an id seen again replaces the pose.
  void AddNode(int id, const Eigen::Isometry3d& T_W_N);
  /// False with the reason when a node is unknown or the information matrix is not symmetric
  /// positive definite.
  [[nodiscard]] bool AddEdge(const PoseGraphEdge& edge, std::string* why);
  /// Holds the node where it is. Every node named so is held (the gauge, or a part of the graph
  /// that is already settled, such as a saved map that a new session joins); without any, the
  /// first node added is.
  void SetFixed(int id);

  /// Optimizes every node pose but the fixed one (see loop_rejection_chi2 for wrong loops).
  /// False with the reason when there is nothing to optimize or Ceres fails; poses() are then
  /// unchanged.
  [[nodiscard]] bool Optimize(PoseGraphReport* report, std::string* why);

  [[nodiscard]] const std::map<int, Eigen::Isometry3d>& poses() const { return poses_; }
  [[nodiscard]] const std::vector<PoseGraphEdge>& edges() const { return edges_; }

 private:
  PoseGraphConfig config_;
  std::map<int, Eigen::Isometry3d> poses_;
  std::vector<PoseGraphEdge> edges_;
  std::set<int> fixed_;
  bool fixed_set_ = false;  // SetFixed was called: the first node is no longer held by default
};

}  // namespace objmap
