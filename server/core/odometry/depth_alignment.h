#pragma once
// Dense alignment of two depth images: point-to-plane ICP with projective association on
// sub-sampled depth, coarse to fine. It refines the feature (PnP) pose, whose accuracy is bounded
// by keypoint depths: a keypoint sits on an edge, where the depth is worst (and, with colour not
// registered to depth, read at the wrong pixel).

#include <Eigen/Geometry>
#include <vector>

#include "types/frame.h"

namespace objmap {

/// A depth image reduced to cells of step x step pixels: each cell's 3D point (camera frame) and
/// surface normal, NaN where the cell has no usable depth or no normal.
struct DepthGrid {
  int width = 0;
  int height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  ///< intrinsics of the reduced image
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;

  [[nodiscard]] bool empty() const { return points.empty(); }
};

/// Cells with fewer than half their pixels valid (depth in (0, max_depth_m]) or whose depths
/// spread over more than 1 cm + 2 % (a depth edge inside the cell) have no point, unless the
/// middle 80 % of their depths keep within that (sensor noise, a rim of another surface): then
/// the point is at the mean of those middle depths.
[[nodiscard]] DepthGrid MakeDepthGrid(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                                      int step, double max_depth_m);

struct DepthAlignmentLevel {
  int iterations = 10;
  /// A correspondence is used while its points lie within this distance; it shrinks linearly
  /// from the first to the last value over the iterations (far at first to capture, near at
  /// the end to keep outliers out).
  double first_max_distance_m = 0.08;
  double last_max_distance_m = 0.03;
};

struct DepthAlignmentReport {
  int correspondences = 0;  ///< in the last iteration
  int iterations = 0;       ///< done, over all levels
  double rmse_m = 0.0;      ///< point-to-plane residual of the last iteration
  /// The smallest eigenvalue of the last normal equations over the largest: near 0 when the
  /// geometry leaves a direction free (a single plane, a corridor).
  double conditioning = 0.0;
  /// The last iteration's whitened Hessian (residuals over their depth noise) for increments
  /// that turn about `centre`, the correspondences' centroid (model frame), and their RMS
  /// distance from it: what AlignmentInformation needs for an edge's information.
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius_m = 0.0;
};

/// Refines T_model_frame (maps frame points into the model's camera) by point-to-plane ICP of
/// each level's (model, frame) grids in turn. Residuals are weighted by the depth noise of a
/// structured-light sensor (grows with the square of the range) under a Huber loss. Returns
/// false, leaving the pose as it was, when a level finds fewer than min_correspondences.
bool AlignDepth(const std::vector<const DepthGrid*>& model_levels,
                const std::vector<const DepthGrid*>& frame_levels,
                const std::vector<DepthAlignmentLevel>& levels, int min_correspondences,
                Eigen::Isometry3d* T_model_frame, DepthAlignmentReport* report);

}  // namespace objmap
