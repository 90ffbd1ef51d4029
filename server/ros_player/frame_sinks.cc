#include "frame_sinks.h"

#include <objmap_msgs/Status.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include <chrono>
#include <thread>

#include "ros_conversions.h"

namespace objmap::ros_player {
namespace {

constexpr char kColorTopic[] = "rgb/image";
constexpr char kDepthTopic[] = "depth/image";
constexpr char kCameraInfoTopic[] = "rgb/camera_info";

tf2_msgs::TFMessage TfMessage(const geometry_msgs::TransformStamped& transform) {
  tf2_msgs::TFMessage message;
  message.transforms.push_back(transform);
  return message;
}

class BagSink : public FrameSink {
 public:
  explicit BagSink(std::unique_ptr<rosbag::Bag> bag) : bag_(std::move(bag)) {}

  bool Send(const FrameMessages& m, std::string* why) override {
    const ros::Time stamp = m.color.header.stamp;
    try {
      // The pose first, as a live TF broadcaster would send it.
      bag_->write("/tf", stamp, TfMessage(m.T_W_C));
      bag_->write(std::string("/") + kCameraInfoTopic, stamp, m.camera_info);
      bag_->write(std::string("/") + kColorTopic, stamp, m.color);
      bag_->write(std::string("/") + kDepthTopic, stamp, m.depth);
    } catch (const rosbag::BagException& e) {
      *why = bag_->getFileName() + ": " + e.what();
      return false;
    }
    return true;
  }

  bool Finish(std::string* why) override {
    try {
      bag_->close();
    } catch (const rosbag::BagException& e) {
      *why = e.what();
      return false;
    }
    return true;
  }

 private:
  std::unique_ptr<rosbag::Bag> bag_;
};

class TopicSink : public FrameSink {
 public:
  TopicSink(ros::NodeHandle& node, const PlayerConfig& config)
      : config_(config),
        node_(node),
        color_(node.advertise<sensor_msgs::Image>(kColorTopic, 5)),
        depth_(node.advertise<sensor_msgs::Image>(kDepthTopic, 5)),
        camera_info_(node.advertise<sensor_msgs::CameraInfo>(kCameraInfoTopic, 5)),
        tf_(node.advertise<tf2_msgs::TFMessage>("/tf", 100)),
        rate_(config.rate_hz) {}

  // Waits for the node's service and for its subscriptions to every topic, so that the first
  // frames are not published into the void.
  bool Start(std::string* why) {
    if (config_.wait_for_node.empty()) return true;
    if (!ros::service::waitForService(config_.wait_for_node,
                                      ros::Duration(config_.wait_timeout_s))) {
      *why = "~wait_for_node: no service " + config_.wait_for_node + " within " +
             std::to_string(config_.wait_timeout_s) + " s";
      return false;
    }
    if (!NodeFramesReceived(&frames_received_at_start_, why)) return false;
    const bool subscribed = WaitUntil([&] {
      return color_.getNumSubscribers() > 0 && depth_.getNumSubscribers() > 0 &&
             camera_info_.getNumSubscribers() > 0 && tf_.getNumSubscribers() > 0;
    });
    if (!subscribed) {
      ROS_WARN_STREAM(
          "objmap_dataset_player: rgb/image, depth/image, rgb/camera_info or /tf "
          "has no subscriber after "
          << config_.wait_timeout_s << " s; playing anyway");
    }
    return true;
  }

  bool Send(const FrameMessages& m, std::string* why) override {
    if (!config_.wait_for_node.empty() && sent_ > 0 && !WaitForPreviousFrame(why)) return false;
    tf_.publish(TfMessage(m.T_W_C));
    camera_info_.publish(m.camera_info);
    color_.publish(m.color);
    depth_.publish(m.depth);
    ++sent_;
    rate_.sleep();
    if (!ros::ok()) {
      *why = "shut down";
      return false;
    }
    return true;
  }

  bool Finish(std::string* why) override {
    if (!config_.wait_for_node.empty() && sent_ > 0) return WaitForPreviousFrame(why);
    return true;
  }

 private:
  // Polled every 10 ms while a frame is being mapped, so over one persistent connection rather
  // than a new TCP connection (and a socket left in TIME_WAIT) per call. One failed call does
  // not end the play: it is retried on a new connection a few times before the node counts as
  // gone.
  bool NodeFramesReceived(std::int64_t* count, std::string* why) {
    constexpr int kAttempts = 5;
    objmap_msgs::Status status;
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
      if (!status_client_.isValid()) {
        status_client_ = node_.serviceClient<objmap_msgs::Status>(config_.wait_for_node,
                                                                  /*persistent=*/true);
      }
      if (status_client_.call(status)) {
        *count = status.response.frames_received;
        return true;
      }
      status_client_.shutdown();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    *why = "~wait_for_node: calling " + config_.wait_for_node + " failed " +
           std::to_string(kAttempts) + " times";
    return false;
  }

  template <typename Condition>
  bool WaitUntil(const Condition& done) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(config_.wait_timeout_s);
    while (ros::ok() && !done()) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return ros::ok();
  }

  // frames_received counts every frame the node handled, mapped or rejected; a frame its
  // synchronizer never completed is not counted, hence the timeout.
  bool WaitForPreviousFrame(std::string* why) {
    std::int64_t received = 0;
    bool failed = false;
    const bool handled = WaitUntil([&] {
      failed = !NodeFramesReceived(&received, why);
      return failed || received >= frames_received_at_start_ + sent_;
    });
    if (failed) return false;
    if (!handled && ros::ok()) {
      ROS_WARN_STREAM("objmap_dataset_player: " << config_.wait_for_node << " reports "
                                                << received - frames_received_at_start_ << " of "
                                                << sent_ << " frames handled after "
                                                << config_.wait_timeout_s << " s; going on");
      frames_received_at_start_ = received - sent_;  // wait for the next frames only
    }
    return true;
  }

  const PlayerConfig& config_;
  ros::NodeHandle node_;
  ros::ServiceClient status_client_;
  ros::Publisher color_, depth_, camera_info_, tf_;
  ros::WallRate rate_;
  std::int64_t frames_received_at_start_ = 0;
  std::int64_t sent_ = 0;
};

}  // namespace

std::unique_ptr<FrameSink> MakeBagSink(const PlayerConfig& config, std::string* why) {
  auto bag = std::make_unique<rosbag::Bag>();
  try {
    bag->open(config.write_bag, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    *why = config.write_bag + ": cannot be created: " + e.what();
    return nullptr;
  }
  return std::make_unique<BagSink>(std::move(bag));
}

std::unique_ptr<FrameSink> MakeTopicSink(ros::NodeHandle& node, const PlayerConfig& config,
                                         std::string* why) {
  auto sink = std::make_unique<TopicSink>(node, config);
  if (!sink->Start(why)) return nullptr;
  return sink;
}

}  // namespace objmap::ros_player
