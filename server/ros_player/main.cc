// objmap_dataset_player: plays a 7-Scenes or TUM RGB-D folder as the topics objmap_node reads
// (rgb/image, depth/image, rgb/camera_info, /tf), or writes them into a bag with --write-bag.
// Parameters: player_config.h; usage: launch/objmap_dataset.launch.
#include <ros/ros.h>

#include <algorithm>
#include <cstring>
#include <iostream>

#include "dataset/sequence_reader.h"
#include "frame_sinks.h"
#include "player_config.h"

namespace objmap::ros_player {
namespace {

// Stamps: the dataset's own, or start + k / rate for datasets without them; each loop adds the
// length of one pass, so that stamps keep increasing (TF refuses to go back in time).
class Stamper {
 public:
  Stamper(const ros::Time& start, double rate_hz) : start_(start), period_(1.0 / rate_hz) {}

  ros::Time StampOf(const RgbdFrame& frame) {
    const ros::Time own = frame.stamp_s > 0.0 ? ros::Time(frame.stamp_s)
                                              : start_ + ros::Duration(period_ * played_in_pass_);
    ++played_in_pass_;
    if (first_in_pass_.isZero()) first_in_pass_ = own;
    last_in_pass_ = own;
    return own + loop_offset_;
  }

  void NextPass() {
    loop_offset_ += (last_in_pass_ - first_in_pass_) + ros::Duration(period_);
    first_in_pass_ = ros::Time();
    played_in_pass_ = 0;
  }

 private:
  ros::Time start_;
  double period_;
  ros::Duration loop_offset_;
  ros::Time first_in_pass_, last_in_pass_;
  std::size_t played_in_pass_ = 0;
};

// False once a node is asked to stop; the command-line form runs without ros::init, where
// ros::ok() is always false.
bool Running() { return !ros::isInitialized() || ros::ok(); }

// Plays the selected frames once or in a loop; frames that cannot be read are skipped with a
// warning. Returns the process exit code.
int Play(const SequenceReader& reader, const PlayerConfig& config, FrameSink* sink) {
  const std::size_t first = static_cast<std::size_t>(config.first_frame);
  const std::size_t end =
      config.max_frames == 0
          ? reader.size()
          : std::min(reader.size(), first + static_cast<std::size_t>(config.max_frames));
  if (first >= end) {
    ROS_ERROR_STREAM("objmap_dataset_player: no frames selected: first_frame " << first << " of "
                                                                               << reader.size());
    return 2;
  }
  Stamper stamper(ros::Time::now(), config.rate_hz);
  std::size_t sent = 0;
  std::string why;
  do {
    for (std::size_t index = first; index < end && Running();
         index += static_cast<std::size_t>(config.every_nth_frame)) {
      RgbdFrame frame;
      if (!reader.ReadFrame(index, &frame, &why)) {
        ROS_WARN_STREAM("objmap_dataset_player: skipped frame " << index << ": " << why);
        continue;
      }
      if (!sink->Send(ros_bridge::FrameToMsgs(frame, stamper.StampOf(frame), config.world_frame,
                                              config.camera_frame),
                      &why)) {
        ROS_ERROR_STREAM("objmap_dataset_player: frame " << index << ": " << why);
        return 1;
      }
      ++sent;
    }
    stamper.NextPass();
  } while (config.loop && Running());
  if (sent == 0) {
    ROS_ERROR_STREAM("objmap_dataset_player: none of the selected frames could be read");
    return 1;
  }
  if (!sink->Finish(&why)) {
    ROS_ERROR_STREAM("objmap_dataset_player: " << why);
    return 1;
  }
  ROS_INFO_STREAM("objmap_dataset_player: played "
                  << sent << " frames"
                  << (config.write_bag.empty() ? "" : " into " + config.write_bag));
  return 0;
}

int Run(const PlayerConfig& config, ros::NodeHandle* node) {
  std::string why;
  const std::unique_ptr<SequenceReader> reader = OpenSequence(config.dataset, &why);
  if (!reader) {
    ROS_FATAL_STREAM("objmap_dataset_player: " << why);
    return 2;
  }
  const std::unique_ptr<FrameSink> sink =
      config.write_bag.empty() ? MakeTopicSink(*node, config, &why) : MakeBagSink(config, &why);
  if (!sink) {
    ROS_FATAL_STREAM("objmap_dataset_player: " << why);
    return 2;
  }
  ROS_INFO_STREAM("objmap_dataset_player: playing " << reader->Describe());
  return Play(*reader, config, sink.get());
}

bool HasWord(int argc, char** argv, const char* wanted) {
  return std::any_of(argv + 1, argv + argc,
                     [wanted](const char* word) { return std::strcmp(word, wanted) == 0; });
}

}  // namespace
}  // namespace objmap::ros_player

int main(int argc, char** argv) {
  using namespace objmap::ros_player;
  PlayerConfig config;
  std::string why;
  if (HasWord(argc, argv, "--help")) {
    std::cout << kPlayerUsage;
    return 0;
  }
  if (HasWord(argc, argv, "--write-bag")) {
    // Command-line form: no ros::init, so no rosmaster is contacted; wall-clock stamps.
    if (!ParsePlayerCommandLine(argc, argv, &config, &why)) {
      std::cerr << "objmap_dataset_player: " << why << "\n" << kPlayerUsage;
      return 2;
    }
    ros::Time::init();
    return Run(config, nullptr);
  }
  ros::init(argc, argv, "objmap_dataset_player");
  ros::NodeHandle node;
  if (!LoadPlayerConfig(ros::NodeHandle("~"), &config, &why)) {
    ROS_FATAL_STREAM("objmap_dataset_player: bad parameters: " << why);
    return 2;
  }
  return Run(config, &node);
}
