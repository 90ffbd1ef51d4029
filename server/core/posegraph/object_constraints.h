#pragma once
// Re-observed objects as pose-graph constraints (the paper's future work, "semantic landmarks"):
// two keyframes that saw the same object from far apart (across a room, after a long detour)
// are tied by aligning the two views of it. Odometry and feature loops rarely link such views
// (the images share little), yet a few centimetres of disagreement between them is what maps a
// screen twice. The alignment is point-to-plane ICP of the two segments; its information matrix
// comes from the segment's geometry, so a flat screen fixes its normal and tilt and leaves the
// in-plane directions to the other edges.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "objects/object_map.h"
#include "posegraph/pose_graph.h"

namespace objmap {

struct ObjectConstraintConfig {
  /// Objects of one label whose centroids lie within this are taken for one object mapped twice
  /// (the duplicate a drifted pose makes), and their views are paired too.
  double same_object_distance_m = 0.3;
  /// Views from cameras closer than this (and views anchored on one pose-graph node) are
  /// already tied by odometry: not paired.
  double min_camera_separation_m = 0.5;
  /// Views with fewer segment points (model voxels) give no constraint.
  int min_segment_points = 100;
  /// Views whose segment lies farther than this (median depth) give no constraint: depth noise
  /// and bias of structured-light sensors grow with the square of the range.
  double max_view_depth_m = 2.0;
  /// Pairs aligned per object (or group of duplicates), largest views first; each view in at
  /// most two pairs.
  int max_pairs_per_object = 6;
  /// ICP: iterations, and the correspondence distance shrinking from first to last.
  int icp_iterations = 30;
  double icp_first_max_distance_m = 0.08;
  double icp_last_max_distance_m = 0.01;
  /// Accepted when this fraction of the smaller view's points lie within icp_last_max_distance_m
  /// of the other's after alignment, and the alignment moved the pose less than the limits (a
  /// larger move is ICP caught by another surface).
  double min_overlap = 0.5;
  double max_correction_m = 0.08;
  double max_correction_deg = 4.0;
  /// Noise of a segment point along the surface normal (model voxels are 5 mm).
  double point_sigma_m = 0.005;
  /// The constraint's information (floor, fixed directions). Its min_eigenvalue_ratio also
  /// says which directions the alignment moves: the free ones (a flat screen's plane) are
  /// neither moved nor claimed.
  AlignmentInformationConfig information;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Where a keyframe's camera sits in the pose graph: on node `node` (at T_W_node) with the
/// fixed offset T_node_C (identity when every keyframe is a node; a tracked frame's offset from
/// its odometry keyframe otherwise).
struct KeyframeAnchor {
  int node = 0;
  Eigen::Isometry3d T_W_node = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_node_C = Eigen::Isometry3d::Identity();
};
/// nullopt: the keyframe is not in the graph (its views are not used).
using KeyframeAnchorLookup = std::function<std::optional<KeyframeAnchor>(KeyframeId)>;

struct ObjectConstraintReport {
  int groups = 0;         ///< objects (or groups of same-label duplicates) with views to pair
  int pairs_tried = 0;    ///< alignments run
  int constraints = 0;    ///< accepted
  double ms = 0.0;
};

/// Loop edges (PoseGraphEdge::loop, so the graph's robust loss and chi-square check apply)
/// between the nodes of keyframes that saw the same labelled object, from aligned views.
/// Unknown objects are left out: grouping duplicates needs a label.
[[nodiscard]] std::vector<PoseGraphEdge> ObjectConstraints(
    const std::vector<const MapObject*>& objects, const KeyframeAnchorLookup& anchor_of,
    const ObjectConstraintConfig& config, ObjectConstraintReport* report);

/// The alignment underneath: refines T_target_source (maps source points into the target's
/// frame) by point-to-plane ICP of `source` onto `target`. Returns false, pose unchanged, when
/// the overlap or the correction fails the config's limits. `information` (may be null): of the
/// refined pose, in the PoseGraphEdge convention, floored as the config says. `overlap` (may be
/// null): the fraction of source points within icp_last_max_distance_m after alignment.
bool AlignSegments(const std::vector<Eigen::Vector3f>& target,
                   const std::vector<Eigen::Vector3f>& source, const ObjectConstraintConfig& config,
                   Eigen::Isometry3d* T_target_source,
                   Eigen::Matrix<double, 6, 6>* information, double* overlap);

}  // namespace objmap
