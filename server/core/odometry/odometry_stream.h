#pragma once
// A frame stream whose poses come from RgbdOdometry: how a camera, a recording or a sequence
// without (or ignoring) its own poses gets them.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dataset/frame_stream.h"
#include "odometry/rgbd_odometry.h"
#include "posegraph/object_constraints.h"
#include "posegraph/pose_graph.h"
#include "types/trajectory_pose.h"

namespace objmap {

/// What tracking a stream found, for a summary and for scoring against the source's poses.
struct EstimatedTrajectory {
  std::vector<TrajectoryPose> estimated;  ///< per tracked frame
  /// The pose each tracked frame came with from its source (a dataset's reference poses; the
  /// identity from a source without any), at the same stamps as `estimated`.
  std::vector<TrajectoryPose> source;
  int frames = 0;
  int lost = 0;
  int relocalized = 0;
  int loops_closed = 0;
  double tracking_ms = 0.0;  ///< in all
  /// Per tracked frame: its index in the source, the keyframe it was tracked against and its
  /// pose relative to that keyframe; and every keyframe's latest pose (loop closures move them).
  std::vector<std::int64_t> frame_index;
  std::vector<int> reference_keyframe;
  std::vector<Eigen::Isometry3d> T_K_C;
  std::vector<Eigen::Isometry3d> keyframe_poses;
  /// The pose graph over the keyframes (node = index into keyframe_poses) as tracking left it.
  std::vector<PoseGraphEdge> graph_edges;
};

/// Every tracked frame's pose after all the loop closures so far: its keyframe's latest pose
/// times its pose relative to it (`estimated` holds the poses as they were when tracked).
[[nodiscard]] std::vector<TrajectoryPose> FinalPoses(const EstimatedTrajectory& trajectory);

/// Optimizes the trajectory's pose graph with `extra` edges between its keyframes added (object
/// constraints, ObjectConstraints) and moves keyframe_poses; the extra edges the graph kept join
/// graph_edges. False with the reason when the graph cannot be solved (trajectory unchanged).
[[nodiscard]] bool ConstrainTrajectory(const std::vector<PoseGraphEdge>& extra,
                                       EstimatedTrajectory* trajectory, PoseGraphReport* report,
                                       std::string* why);

/// The pose-graph anchor of every tracked frame: its keyframe (node), the keyframe's latest pose
/// and the frame's offset from it; by the frame's index in its source.
[[nodiscard]] std::optional<KeyframeAnchor> AnchorOfFrame(const EstimatedTrajectory& trajectory,
                                                          std::int64_t frame_index);

/// Frames of `inner` with T_W_C replaced by the odometry's estimate. The world frame is the first
/// tracked frame's camera frame, or with `start_at_source_pose` the source's own world frame: the
/// first frame keeps the pose it came with and the others are tracked from it (a dataset whose
/// poses only score the estimate: maps and scores then share its frame). A frame the odometry cannot track is a kBadFrame whose reason
/// starts "tracking lost: ", so that the runner skips it with the reason and no wild pose enters
/// the map. Stamps: the frame's, or frame_index / 30 s where the source has none. `log`
/// (not null) receives the trajectories as frames pass.
[[nodiscard]] std::unique_ptr<FrameStream> WithEstimatedPoses(
    std::unique_ptr<FrameStream> inner, const OdometryConfig& config,
    std::shared_ptr<EstimatedTrajectory> log, bool start_at_source_pose = false);

}  // namespace objmap
