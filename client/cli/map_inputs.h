#pragma once
// What `objmap map` reads: the one place that turns its input argument into a FrameStream (a
// dataset folder, an OpenNI2 camera or recording, a ROS bag in builds with ROS), so that a new
// kind of input adds a branch and its options here without touching map_command.cc.

#include <memory>
#include <set>
#include <string>

#include "arguments.h"
#include "dataset/frame_stream.h"
#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"
#include "odometry/odometry_stream.h"

namespace objmap::cli {

/// Options of `objmap map` that shape the input, whatever its kind.
struct MapInputOptions {
  /// First frame and number of frames (0: all); a sequence folder selects them by index.
  std::size_t first_frame = 0;
  std::size_t max_frames = 0;
  /// TUM trajectory giving the poses of a camera or recording; empty: a static camera at the
  /// identity pose. Sequence folders bring their own poses and ignore it.
  std::string trajectory_path;
  TrajectoryMatchConfig trajectory_match;
  /// --poses estimate: every frame's pose from RgbdOdometry, whatever the input brings (a
  /// dataset's own poses are kept to score the estimate against).
  bool estimate_poses = false;
  /// --poses auto (the default): the estimate for an input without poses of its own (a camera
  /// or .oni recording without --trajectory), the input's poses otherwise.
  bool estimate_missing_poses = true;
  OdometryConfig odometry;
  /// ROS bags; an empty field keeps the reader's default (topics: auto-detected).
  std::string bag_color_topic;        ///< --bag-color-topic
  std::string bag_depth_topic;        ///< --bag-depth-topic
  std::string bag_camera_info_topic;  ///< --bag-camera-info-topic
  std::string bag_pose_topic;         ///< --bag-pose-topic (PoseStamped instead of TF)
  std::string world_frame;            ///< --world-frame
  std::string camera_frame;           ///< --camera-frame
};

/// Usage lines of the bag options above, for `objmap map --help`.
extern const char kMapBagUsage[];

/// The bag options above, for the map command's Arguments (each takes a value).
[[nodiscard]] std::set<std::string> MapBagFlags();

/// Fills the bag options of `options` from the command line.
void BagOptionsFrom(const Arguments& args, MapInputOptions* options);

/// An opened input: the stream, and the sequence behind it when there is one (it must outlive the
/// stream, which reads from it).
struct MapInput {
  std::unique_ptr<SequenceReader> sequence;
  std::unique_ptr<FrameStream> stream;
  /// True when the stream's selection already applies first_frame and max_frames.
  bool selection_applied = false;
  /// Printed before the run: how poses are obtained, when the user should know.
  std::string note;
  /// The poses come from the odometry: --poses estimate, or auto on an input without poses.
  bool estimate_poses = false;
  /// With estimate_poses: the tracked trajectory, filled as frames are read.
  std::shared_ptr<EstimatedTrajectory> estimated;
  /// The source's own poses are real (a dataset's, a bag's, a --trajectory's), so the estimate
  /// can be scored against them.
  bool source_has_poses = false;
};

/// Opens `argument`: `openni2` (the first OpenNI2 device), `openni2:<uri>`, a path ending in
/// `.oni` (an OpenNI2 recording), a path ending in `.bag` (a ROS1 bag), else a sequence folder
/// (7-Scenes or TUM RGB-D). False with a reason, e.g. "no OpenNI2 device found: ...", or for
/// OpenNI2 or bag inputs in a build without OpenNI2 or ROS.
[[nodiscard]] bool OpenMapInput(const std::string& argument, const MapInputOptions& options,
                                MapInput* input, std::string* why);

#ifdef OBJMAP_CLI_WITH_ROSBAG
/// The `.bag` branch, in map_inputs_rosbag.cc (compiled only in builds with ROS).
[[nodiscard]] std::unique_ptr<SequenceReader> OpenBagInput(const std::string& path,
                                                           const MapInputOptions& options,
                                                           std::string* why);
#endif

}  // namespace objmap::cli
