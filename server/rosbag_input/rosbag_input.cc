#include "rosbag_input.h"

#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <sensor_msgs/Image.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>

#include "bag_index.h"
#include "bag_topics.h"
#include "ros_conversions.h"

namespace objmap {
namespace {

using rosbag_input::BagIndex;
using rosbag_input::IndexedFrame;

class RosbagSequenceReader : public SequenceReader {
 public:
  RosbagSequenceReader(std::string path, RosbagInputConfig config, std::unique_ptr<rosbag::Bag> bag,
                       BagIndex index)
      : path_(std::move(path)),
        config_(std::move(config)),
        bag_(std::move(bag)),
        index_(std::move(index)) {}

  std::size_t size() const override { return index_.frames.size(); }

  std::string Describe() const override { return "rosbag " + path_ + ": " + index_.summary; }

  bool has_poses() const override { return !index_.without_poses; }

  bool ReadFrame(std::size_t index, RgbdFrame* frame, std::string* why) const override {
    if (index >= index_.frames.size()) {
      *why = "frame index " + std::to_string(index) + " out of range";
      return false;
    }
    const IndexedFrame& entry = index_.frames[index];
    const std::string name = path_ + " frame " + std::to_string(index) +
                             " (t=" + rosbag_input::StampText(entry.stamp) + ")";
    // Without any pose source the caller estimates the poses: frames come at the identity.
    if (!entry.T_W_C && !index_.without_poses) {
      *why = name + ": " + entry.pose_problem;
      return false;
    }
    sensor_msgs::Image::ConstPtr color, depth;
    {
      // rosbag::Bag reads through one file position: one reader at a time.
      std::lock_guard<std::mutex> lock(bag_mutex_);
      color = entry.color.instantiate<sensor_msgs::Image>();
      depth = entry.depth.instantiate<sensor_msgs::Image>();
    }
    if (!color || !depth) {
      *why = name + ": the colour or depth message could not be read";
      return false;
    }
    if (!ros_bridge::FrameFromMsgs(*color, *depth, index_.camera_infos[entry.camera_info],
                                   entry.T_W_C.value_or(Eigen::Isometry3d::Identity()),
                                   config_.depth_scale, frame, why)) {
      *why = name + ": " + *why;
      return false;
    }
    frame->frame_index = static_cast<std::int64_t>(index);
    frame->name = name;
    return true;
  }

 private:
  std::string path_;
  RosbagInputConfig config_;
  std::unique_ptr<rosbag::Bag> bag_;  // the index's message handles point into it
  BagIndex index_;
  mutable std::mutex bag_mutex_;
};

// A bag file is recognised by its first line, "#ROSBAG V2.0": this tells "not a bag" from a
// damaged one in the error message.
bool LooksLikeBag(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return false;
  char magic[9] = {};
  const std::size_t read = std::fread(magic, 1, 8, file);
  std::fclose(file);
  return read == 8 && std::string(magic) == "#ROSBAG ";
}

std::unique_ptr<rosbag::Bag> OpenBag(const std::string& path, std::string* why) {
  if (!std::filesystem::is_regular_file(path)) {
    *why = path + (std::filesystem::exists(path) ? ": not a file" : ": no such file");
    return nullptr;
  }
  if (!LooksLikeBag(path)) {
    *why = path + ": not a ROS bag (no #ROSBAG header)";
    return nullptr;
  }
  auto bag = std::make_unique<rosbag::Bag>();
  try {
    bag->open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    *why = path + ": cannot be read as a ROS bag: " + e.what();
    return nullptr;
  }
  return bag;
}

}  // namespace

bool RosbagInputConfig::IsValid(std::string* why) const {
  if (world_frame.empty()) {
    *why = "world_frame must not be empty";
    return false;
  }
  if (!(max_pair_interval_s >= 0.0) || !std::isfinite(max_pair_interval_s)) {
    *why = "max_pair_interval_s must be >= 0";
    return false;
  }
  if (!(depth_scale > 0.0) || !std::isfinite(depth_scale)) {
    *why = "depth_scale must be positive (0.001: millimetres)";
    return false;
  }
  return true;
}

std::unique_ptr<SequenceReader> OpenRosbagSequence(const std::string& path,
                                                   const RosbagInputConfig& config,
                                                   std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  std::unique_ptr<rosbag::Bag> bag = OpenBag(path, why);
  if (!bag) return nullptr;
  rosbag_input::BagIndex index;
  try {
    const std::vector<rosbag_input::BagTopic> topics = rosbag_input::ListTopics(*bag);
    rosbag_input::ChosenTopics chosen;
    if (!rosbag_input::ChooseTopics(path, topics, config, &chosen, why)) return nullptr;
    if (!rosbag_input::IndexBag(*bag, chosen, config, &index, why)) {
      *why = path + ": " + *why;
      return nullptr;
    }
  } catch (const rosbag::BagException& e) {
    *why = path + ": damaged ROS bag: " + e.what();
    return nullptr;
  }
  return std::make_unique<RosbagSequenceReader>(path, config, std::move(bag), std::move(index));
}

}  // namespace objmap
