#pragma once
// objmap_dataset_player's settings: read from the node's private ROS parameters when it plays
// to topics, or from the command line when it writes a bag (no rosmaster needed).

#include <string>

namespace ros {
class NodeHandle;
}

namespace objmap::ros_player {

/// What is played, how fast, and where to.
struct PlayerConfig {
  /// 7-Scenes or TUM RGB-D folder (anything OpenSequence reads).
  std::string dataset;
  /// Frames per second when publishing; also the stamp spacing of datasets without stamps
  /// (7-Scenes), whose frame k is stamped start + k / rate_hz.
  double rate_hz = 10.0;
  /// First frame index of the dataset to play.
  int first_frame = 0;
  /// Frames to play from first_frame (counting the ones skipped by every_nth_frame); 0: to
  /// the end.
  int max_frames = 0;
  /// Play frames first_frame, first_frame + n, first_frame + 2n, ...
  int every_nth_frame = 1;
  /// Start again from first_frame after the last frame (stamps keep increasing).
  bool loop = false;
  /// Parent frame of the published camera pose, objmap_node's ~world_frame.
  std::string world_frame = "map";
  /// The images' header.frame_id and the TF child frame (the openni driver's name).
  std::string camera_frame = "camera_rgb_optical_frame";
  /// objmap_msgs/Status service of the node being fed (/objmap_node/status): before each
  /// frame, wait until the node has handled the previous one (frames_received), so that a slow
  /// machine drops nothing. Empty: play at rate_hz without waiting.
  std::string wait_for_node;
  /// Longest wait for the node (its service, its subscriptions, one frame handled); after it
  /// the player warns and goes on.
  double wait_timeout_s = 60.0;
  /// Write the messages into this bag instead of publishing them (topics /rgb/image,
  /// /depth/image, /rgb/camera_info, /tf; the bag time of each message is its stamp).
  std::string write_bag;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Reads ~dataset, ~rate, ~first_frame, ~max_frames, ~every_nth_frame, ~loop, ~world_frame,
/// ~camera_frame, ~wait_for_node, ~wait_timeout_s, ~write_bag over `config`. False with a
/// reason naming the parameter for a mistyped or unknown one; then IsValid.
[[nodiscard]] bool LoadPlayerConfig(const ros::NodeHandle& private_node, PlayerConfig* config,
                                    std::string* why);

/// The same settings from the command line: `DATASET --write-bag FILE [--rate HZ]
/// [--first-frame N] ...` (each parameter as --name-with-dashes). False with a reason for an
/// unknown option, a bad value or a missing dataset; then IsValid.
[[nodiscard]] bool ParsePlayerCommandLine(int argc, char** argv, PlayerConfig* config,
                                          std::string* why);

/// Usage of the command-line form.
extern const char kPlayerUsage[];

}  // namespace objmap::ros_player
