#pragma once
// Camera poses from a file, matched to the frames of a stream by timestamp: how a live camera or
// a recording without poses gets them from an external tracker (SLAM, motion capture).

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "dataset/frame_stream.h"
#include "types/trajectory_pose.h"

namespace objmap {

/// Reads a TUM trajectory: lines `stamp tx ty tz qx qy qz qw` (seconds, metres, T_W_C), '#'
/// comments and blank lines ignored, returned sorted by stamp. Quaternions within 1% of unit
/// length are normalized. False with "path:line: ..." on a malformed line, or for a file with no
/// pose.
[[nodiscard]] bool ReadTumTrajectory(const std::string& path, std::vector<TrajectoryPose>* poses,
                                     std::string* why);

/// Writes `poses` as a TUM trajectory (the lines ReadTumTrajectory reads) after a `# comment`
/// line. False with "cannot write PATH" when the file cannot be written.
[[nodiscard]] bool WriteTumTrajectory(const std::string& path,
                                      const std::vector<TrajectoryPose>& poses,
                                      const std::string& comment, std::string* why);

/// How frames are matched to trajectory poses.
struct TrajectoryMatchConfig {
  /// Largest |frame stamp - pose stamp| for the nearest pose to be taken, seconds.
  double max_stamp_difference_s = 0.02;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Gives each frame of `inner` the pose of `poses` (sorted by stamp) nearest its stamp; a frame
/// with no pose within the tolerance is a kBadFrame whose reason names the stamp and `origin`
/// (the trajectory file), so the runner skips it with a message. Poses are not interpolated:
/// the tracker is expected to give a pose per frame, at the frame's stamp.
[[nodiscard]] std::unique_ptr<FrameStream> WithTrajectory(std::unique_ptr<FrameStream> inner,
                                                          std::vector<TrajectoryPose> poses,
                                                          const TrajectoryMatchConfig& config,
                                                          const std::string& origin);

}  // namespace objmap
