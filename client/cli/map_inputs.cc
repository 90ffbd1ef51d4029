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

// Gives a camera or recording its poses: from the trajectory file, or none (identity).
bool AddPoses(const MapInputOptions& options, MapInput* input, std::string* why) {
  if (options.trajectory_path.empty()) {
    input->note = "no --trajectory: the camera is taken as static at the identity pose";
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

}  // namespace

bool OpenMapInput(const std::string& argument, const MapInputOptions& options, MapInput* input,
                  std::string* why) {
  if (IsOpenNI2Argument(argument)) {
    return OpenOpenNI2(argument, input, why) && AddPoses(options, input, why);
  }
  input->sequence = OpenSequence(argument, why);
  if (!input->sequence) return false;
  if (!options.trajectory_path.empty()) {
    input->note = "--trajectory ignored: " + input->sequence->Describe() + " has its own poses";
  }
  if (options.first_frame >= input->sequence->size()) {
    *why = "no frames selected: first frame " + std::to_string(options.first_frame) + " of " +
           std::to_string(input->sequence->size());
    return false;
  }
  input->stream = MakeSequenceStream(*input->sequence, options.first_frame, options.max_frames);
  input->selection_applied = true;
  return true;
}

}  // namespace objmap::cli
