#pragma once
// Recorded ROS1 bags as a SequenceReader: `objmap map recording.bag` maps them like a dataset
// folder. The ROS headers stay in the .cc files, so that the `objmap` CLI compiles against this
// header without them.

#include <memory>
#include <string>

#include "dataset/sequence_reader.h"

namespace objmap {

/// Which messages of a bag make the frames, and how they are paired and posed.
///
/// A topic left empty is auto-detected: the bag's only topic of the right type (colour:
/// sensor_msgs/Image in rgb8, bgr8, rgba8 or bgra8; depth: sensor_msgs/Image in 16UC1, mono16
/// or 32FC1; camera info: sensor_msgs/CameraInfo). When several qualify, the usual names of the
/// openni/openni2, RealSense and objmap_dataset_player drivers decide (for camera info, first the
/// one beside the colour topic); otherwise opening fails and lists the candidates.
struct RosbagInputConfig {
  /// sensor_msgs/Image colour topic; empty: auto-detected.
  std::string color_topic;
  /// sensor_msgs/Image depth topic, registered to the colour image; empty: auto-detected.
  std::string depth_topic;
  /// sensor_msgs/CameraInfo of the colour (= registered depth) camera; empty: auto-detected.
  std::string camera_info_topic;
  /// Frame of the map: T_W_C maps camera points into it. "map" is what objmap_node and
  /// objmap_dataset_player use by default (TUM RGB-D's own bags use "/world": pass that).
  std::string world_frame = "map";
  /// Camera frame looked up in TF; empty: the colour image's header.frame_id.
  std::string camera_frame;
  /// geometry_msgs/PoseStamped topic holding T_W_C (its frame_id taken as world_frame) instead
  /// of /tf and /tf_static; empty: TF.
  std::string pose_topic;
  /// A colour image is paired with the depth image nearest in stamp when they are at most this
  /// far apart, in seconds; colour images without such a depth image are left out.
  double max_pair_interval_s = 0.02;
  /// Metres per unit of 16UC1 / mono16 depth images (0.001: millimetres).
  double depth_scale = 0.001;
  /// For a caller that estimates the poses itself: a bag without /tf, /tf_static (and without
  /// pose_topic) opens, and its frames are read at the identity pose (has_poses() false). A bag
  /// with TF keeps its poses, and a frame TF does not cover is still refused.
  bool poses_optional = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Opens and indexes a bag: colour images paired with depth and camera info by nearest stamp,
/// and every /tf, /tf_static (or pose topic) message loaded into one transform buffer covering
/// the whole bag, so that each frame's pose is interpolated at its colour stamp. ReadFrame(i)
/// is then random access (frame i: the i-th paired colour image in stamp order); a frame
/// without a pose is refused with a reason naming the missing transform. ReadFrame may be
/// called from several threads (bag reads are serialized by a mutex).
///
/// Returns nullptr and a reason for a missing file, a file that is not a bag, a topic that is
/// not in the bag (the reason lists the bag's topics), an ambiguous or absent auto-detected
/// topic, a bag without pose messages (unless config.poses_optional), and a bag in which no
/// colour image pairs with a depth one.
[[nodiscard]] std::unique_ptr<SequenceReader> OpenRosbagSequence(const std::string& path,
                                                                 const RosbagInputConfig& config,
                                                                 std::string* why);

}  // namespace objmap
