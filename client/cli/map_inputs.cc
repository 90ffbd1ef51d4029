#include "map_inputs.h"

#ifdef OBJMAP_CLI_WITH_OPENNI2
#include "openni2/openni2_source.h"
#endif

namespace objmap::cli {
namespace {

constexpr char kOpenNI2Prefix[] = "openni2";

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool IsOpenNI2Argument(const std::string& argument) {
  return argument == kOpenNI2Prefix || argument.rfind(std::string(kOpenNI2Prefix) + ":", 0) == 0 ||
         EndsWith(argument, ".oni");
}

// Gives a camera or recording its poses: from the trajectory file; without one, tracked by the
// odometry (--poses auto or estimate) or none (--poses input: a static camera at the identity).
bool AddPoses(const MapInputOptions& options, MapInput* input, std::string* why) {
  if (options.trajectory_path.empty()) {
    if (options.estimate_missing_poses) {
      input->estimate_poses = true;
      input->note = "no --trajectory";
    } else if (!options.estimate_poses) {
      input->note =
          "no --trajectory: the camera is taken as static at the identity pose (--poses "
          "estimate tracks it)";
    }
    return true;
  }
  std::vector<TrajectoryPose> poses;
  if (!options.trajectory_match.IsValid(why) ||
      !ReadTumTrajectory(options.trajectory_path, &poses, why)) {
    return false;
  }
  input->note =
      "poses from " + options.trajectory_path + " (" + std::to_string(poses.size()) + " poses)";
  input->stream = WithTrajectory(std::move(input->stream), std::move(poses),
                                 options.trajectory_match, options.trajectory_path);
  input->source_has_poses = true;
  return true;
}

// --poses estimate: the odometry replaces whatever poses the stream has.
bool EstimatePoses(const MapInputOptions& options, MapInput* input, std::string* why) {
  if (!options.estimate_poses && !input->estimate_poses) return true;
  input->estimate_poses = true;
  if (!options.odometry.IsValid(why)) return false;
  input->estimated = std::make_shared<EstimatedTrajectory>();
  // With poses of its own the input keeps its world frame: the first frame's pose anchors the
  // estimate, so that the map can be compared with (and scored against) the input's.
  input->stream = WithEstimatedPoses(std::move(input->stream), options.odometry, input->estimated,
                                     /*start_at_source_pose=*/input->source_has_poses);
  input->note += std::string(input->note.empty() ? "" : "; ") +
                 "poses estimated by RGB-D odometry" +
                 (input->source_has_poses
                      ? " from the input's first pose (its other poses only score them)"
                      : "");
  return true;
}

bool OpenOpenNI2(const std::string& argument, MapInput* input, std::string* why) {
#ifdef OBJMAP_CLI_WITH_OPENNI2
  OpenNI2SourceConfig config;
  if (EndsWith(argument, ".oni")) {
    config.oni_path = argument;
  } else if (argument != kOpenNI2Prefix) {
    config.device_uri = argument.substr(sizeof(kOpenNI2Prefix));  // after "openni2:"
  }
  input->stream = OpenNI2Source::Open(config, why);
  return input->stream != nullptr;
#else
  (void)input;
  *why = argument + ": this objmap was built without OpenNI2 (install libopenni2-dev and rebuild)";
  return false;
#endif
}

// A random-access sequence (a folder or a bag) as the stream of the selected frames.
bool StreamSequence(const MapInputOptions& options, MapInput* input, std::string* why) {
  if (!options.trajectory_path.empty()) {
    input->note = "--trajectory ignored: " + input->sequence->Describe() + " has its own poses";
  }
  input->stream =
      SelectSequenceFrames(*input->sequence, options.first_frame, options.max_frames, why);
  input->selection_applied = true;
  input->source_has_poses = input->sequence->has_poses();
  if (!input->source_has_poses) {
    // Only a bag without TF opened for --poses auto / estimate gets here.
    input->estimate_poses = true;
    input->note = "the bag has no /tf or /tf_static messages";
  }
  return input->stream != nullptr;
}

}  // namespace

const char kMapBagUsage[] =
    "  --bag-color-topic T       bag: sensor_msgs/Image colour topic (rgb8, bgr8, rgba8, bgra8)\n"
    "  --bag-depth-topic T       bag: sensor_msgs/Image depth topic (16UC1 mm, 32FC1 m)\n"
    "  --bag-camera-info-topic T bag: sensor_msgs/CameraInfo topic\n"
    "  --bag-pose-topic T        bag: geometry_msgs/PoseStamped T_W_C topic instead of TF\n"
    "  --world-frame F           bag: TF frame of the map (default: map)\n"
    "  --camera-frame F          bag: TF frame of the camera (default: the colour frame_id)\n";

std::set<std::string> MapBagFlags() {
  return {"--bag-color-topic", "--bag-depth-topic", "--bag-camera-info-topic",
          "--bag-pose-topic",  "--world-frame",     "--camera-frame"};
}

void BagOptionsFrom(const Arguments& args, MapInputOptions* options) {
  options->bag_color_topic = args.Get("--bag-color-topic", "");
  options->bag_depth_topic = args.Get("--bag-depth-topic", "");
  options->bag_camera_info_topic = args.Get("--bag-camera-info-topic", "");
  options->bag_pose_topic = args.Get("--bag-pose-topic", "");
  options->world_frame = args.Get("--world-frame", "");
  options->camera_frame = args.Get("--camera-frame", "");
}

bool OpenMapInput(const std::string& argument, const MapInputOptions& options, MapInput* input,
                  std::string* why) {
  if (IsOpenNI2Argument(argument)) {
    return OpenOpenNI2(argument, input, why) && AddPoses(options, input, why) &&
           EstimatePoses(options, input, why);
  }
  if (EndsWith(argument, ".bag")) {
#ifdef OBJMAP_CLI_WITH_ROSBAG
    input->sequence = OpenBagInput(argument, options, why);
#else
    *why = argument +
           ": ROS bags need objmap built with ROS (this one was built without it: "
           "configure with -DOBJMAP_WITH_ROS=ON where ROS1 is installed)";
#endif
  } else {
    input->sequence = OpenSequence(argument, why);
  }
  return input->sequence != nullptr && StreamSequence(options, input, why) &&
         EstimatePoses(options, input, why);
}

}  // namespace objmap::cli
