#pragma once
// What `objmap map` reads: a dataset folder, or a recorded ROS bag in builds with ROS. The
// dispatch on the path lives here, apart from the mapping, so that new kinds of input add a
// branch and their options without touching map_command.cc.

#include <memory>
#include <set>
#include <string>

#include "arguments.h"
#include "dataset/sequence_reader.h"

namespace objmap::cli {

/// How inputs other than a folder are read; an empty field keeps the reader's default.
struct MapInputOptions {
  std::string bag_color_topic;        ///< --bag-color-topic
  std::string bag_depth_topic;        ///< --bag-depth-topic
  std::string bag_camera_info_topic;  ///< --bag-camera-info-topic
  std::string bag_pose_topic;         ///< --bag-pose-topic (PoseStamped instead of TF)
  std::string world_frame;            ///< --world-frame
  std::string camera_frame;           ///< --camera-frame
};

/// Usage lines of the inputs and of the options above, for `objmap map --help`.
extern const char kMapInputUsage[];

/// The options above, for the map command's Arguments (each takes a value).
[[nodiscard]] std::set<std::string> MapInputFlags();

[[nodiscard]] MapInputOptions MapInputOptionsFrom(const Arguments& args);

/// Opens the input of `objmap map`: a path ending in `.bag` as a ROS bag (builds with ROS;
/// others say they were built without it), anything else as a dataset folder (OpenSequence).
/// Returns nullptr and a reason when the input cannot be opened.
[[nodiscard]] std::unique_ptr<SequenceReader> OpenMapInput(const std::string& path,
                                                           const MapInputOptions& options,
                                                           std::string* why);

#ifdef OBJMAP_CLI_WITH_ROSBAG
/// The `.bag` branch, in map_inputs_rosbag.cc (compiled only in builds with ROS).
[[nodiscard]] std::unique_ptr<SequenceReader> OpenBagInput(const std::string& path,
                                                           const MapInputOptions& options,
                                                           std::string* why);
#endif

}  // namespace objmap::cli
