#pragma once
// Private to server/ros_node: the state shared by the frame input (map_node.cc), the services
// (node_services.cc) and the publishers (node_publishers.cc).

#include <geometry_msgs/PoseStamped.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <objmap_msgs/DetectionArray.h>
#include <objmap_msgs/GetObject.h>
#include <objmap_msgs/GetOctomap.h>
#include <objmap_msgs/Inventory.h>
#include <objmap_msgs/IsFree.h>
#include <objmap_msgs/QueryObjects.h>
#include <objmap_msgs/QueryOccupancy.h>
#include <objmap_msgs/RayCast.h>
#include <objmap_msgs/StartSession.h>
#include <objmap_msgs/Status.h>
#include <objmap_msgs/UpdatePoses.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "dataset/frame_stream.h"
#include "dataset/keyframe_selector.h"
#include "map_node.h"
#include "map_server/map_server.h"
#include "odometry/held_keyframes.h"
#include "odometry/tracked_keyframes.h"

namespace objmap::ros_node {

using ImageSync =
    message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, sensor_msgs::Image,
                                                    sensor_msgs::CameraInfo>;
using ImageDetectionSync = message_filters::sync_policies::ApproximateTime<
    sensor_msgs::Image, sensor_msgs::Image, sensor_msgs::CameraInfo, objmap_msgs::DetectionArray>;

struct MapNode::Impl {
  Impl(const ros::NodeHandle& node_in, const ros::NodeHandle& private_node_in,
       const NodeConfig& config_in, std::shared_ptr<MapServer> server_in);

  // --- input (map_node.cc)
  void SubscribeInputs();
  /// A synchronizer of `Policy` over the subscribers, calling `callback` on this.
  template <typename Policy, typename Callback, typename... Subscribers>
  std::shared_ptr<void> Synchronize(Callback callback, Subscribers&... subscribers);
  /// Synchronised inputs: without and with a detections topic.
  void OnImages(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth,
                const sensor_msgs::CameraInfoConstPtr& info);
  void OnFrame(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth,
               const sensor_msgs::CameraInfoConstPtr& info,
               const objmap_msgs::DetectionArrayConstPtr& detections);
  /// A frame with its pose: keyframe selection, then the map server (detections absent: the
  /// server's detector runs).
  void MapFrame(RgbdFrame frame, const ros::Time& stamp,
                std::optional<std::vector<Detection>> detections);
  /// ~pose_source estimate: tracks `frame` (giving it its pose), publishes the pose on TF as
  /// world_frame -> `camera_frame`, and moves the mapped keyframes when it closes a loop. False
  /// with the reason when the frame cannot be tracked. A frame tracked in a provisional part of
  /// the session (not placed in the map yet) is tracked: TakeFrame holds it.
  bool TrackFrame(RgbdFrame* frame, const ros::Time& stamp, const std::string& camera_frame,
                  std::string* why);
  /// A frame with its pose (and detections) on its way to the map: held while its part of the
  /// session is provisional, mapped otherwise, after the held keyframes of a part it placed.
  void TakeFrame(RgbdFrame frame, const ros::Time& stamp,
                 std::optional<std::vector<Detection>> detections);
  /// Holds a keyframe of the provisional part `last_tracking` tracked it in (keyframe selection
  /// within the part's own frame), dropping the oldest beyond server.max_held_keyframes.
  void HoldFrame(RgbdFrame frame, const ros::Time& stamp,
                 std::optional<std::vector<Detection>> detections);
  /// Maps the keyframes held in provisional part `fragment`, in order, at their poses in the
  /// map now that it is placed.
  void MapHeldFrames(int fragment);
  /// Sends a keyframe with its pose to the map server; with estimated poses, `T_K_C` on odometry
  /// keyframe `odometry_keyframe` (>= 0) is where it lies, which later loop closures move. False,
  /// counted as rejected, when the server refuses it.
  bool SendKeyframe(RgbdFrame frame, const ros::Time& stamp,
                    std::optional<std::vector<Detection>> detections, int odometry_keyframe,
                    const Eigen::Isometry3d& T_K_C);
  /// Starts tracking at the newest stored keyframe (a restart on an existing map).
  void ResumeTracking();
  /// The mapped keyframes' current poses as nav_msgs/Path on ~trajectory.
  void PublishTrajectory();
  void OnPose(const geometry_msgs::PoseStampedConstPtr& pose);
  /// Reads `camera` until it ends, fails or the node stops (input "openni2").
  void ReadCameraLoop();
  /// T_W_C from TF: world_frame <- `camera_frame` at `stamp`, waiting up to pose_timeout_s.
  bool PoseFromTf(const std::string& camera_frame, const ros::Time& stamp, Eigen::Isometry3d* T_W_C,
                  std::string* why);
  bool CameraPose(const sensor_msgs::Image& color, Eigen::Isometry3d* T_W_C, std::string* why);
  bool PoseFromTopic(const ros::Time& stamp, Eigen::Isometry3d* T_W_C, std::string* why);
  void Reject(const ros::Time& stamp, const std::string& why);

  // --- services (node_services.cc)
  void AdvertiseServices();
  bool QueryObjects(objmap_msgs::QueryObjects::Request& request,
                    objmap_msgs::QueryObjects::Response& response);
  bool GetObject(objmap_msgs::GetObject::Request& request,
                 objmap_msgs::GetObject::Response& response);
  bool Inventory(objmap_msgs::Inventory::Request& request,
                 objmap_msgs::Inventory::Response& response);
  bool QueryOccupancy(objmap_msgs::QueryOccupancy::Request& request,
                      objmap_msgs::QueryOccupancy::Response& response);
  bool IsFree(objmap_msgs::IsFree::Request& request, objmap_msgs::IsFree::Response& response);
  bool RayCast(objmap_msgs::RayCast::Request& request, objmap_msgs::RayCast::Response& response);
  bool GetOctomap(objmap_msgs::GetOctomap::Request& request,
                  objmap_msgs::GetOctomap::Response& response);
  bool UpdatePoses(objmap_msgs::UpdatePoses::Request& request,
                   objmap_msgs::UpdatePoses::Response& response);
  bool StartSession(objmap_msgs::StartSession::Request& request,
                    objmap_msgs::StartSession::Response& response);
  bool Status(objmap_msgs::Status::Request& request, objmap_msgs::Status::Response& response);

  // --- publishers (node_publishers.cc)
  void AdvertiseTopics();
  /// Publishes every map change (and markers, occupied cells) until `stopping`.
  void PublishChangesLoop();
  void PublishMarkers(const MapSnapshot& snapshot);
  void PublishOccupiedCells();

  ros::NodeHandle node;
  ros::NodeHandle private_node;
  NodeConfig config;
  std::shared_ptr<MapServer> server;

  // Frames arrive on their own queue and thread, in order.
  ros::CallbackQueue frame_queue;
  std::unique_ptr<ros::AsyncSpinner> frame_spinner;
  tf2_ros::Buffer tf_buffer;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener;
  message_filters::Subscriber<sensor_msgs::Image> color_sub;
  message_filters::Subscriber<sensor_msgs::Image> depth_sub;
  message_filters::Subscriber<sensor_msgs::CameraInfo> info_sub;
  message_filters::Subscriber<objmap_msgs::DetectionArray> detections_sub;
  // The message_filters synchronizer in use (exact or approximate time, with or without
  // detections), kept alive here.
  std::shared_ptr<void> synchronizer;
  ros::Subscriber pose_sub;
  std::unique_ptr<FrameStream> camera;
  std::thread camera_thread;
  KeyframeSelector keyframe_selector;

  // ~pose_source estimate: the node's own camera tracking (frames come from one thread).
  std::unique_ptr<RgbdOdometry> odometry;
  TrackedKeyframes tracked_keyframes;
  std::map<KeyframeId, ros::Time> keyframe_stamps;
  std::optional<TrackingReport> last_tracking;  // of the frame MapFrame is about to map
  // Keyframes of provisional parts of the session, held until their part is placed.
  struct PendingFrame {
    RgbdFrame frame;
    ros::Time stamp;
    std::optional<std::vector<Detection>> detections;
  };
  HeldKeyframes<PendingFrame> held_frames;
  // Keyframe selection within the current provisional part (its poses are in its own frame).
  std::optional<KeyframeSelector> part_keyframe_selector;
  int part_of_selector = 0;
  std::string tracking_blocked;                 // why tracking cannot resume (empty: it can)
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster;
  ros::Publisher trajectory_pub;

  std::mutex pose_mutex;
  std::condition_variable pose_arrived;
  std::deque<geometry_msgs::PoseStamped> recent_poses;  // newest last

  std::atomic<long long> frames_received{0};
  std::atomic<long long> frames_rejected{0};
  std::atomic<long long> keyframes_sent{0};
  std::atomic<long long> keyframes_held{0};      // held now, in parts not placed yet
  std::atomic<long long> keyframes_attached{0};  // held, then mapped when their part was placed
  mutable std::mutex rejection_mutex;
  std::string last_rejection;

  std::vector<ros::ServiceServer> services;
  ros::Publisher markers_pub;
  ros::Publisher occupied_pub;
  ros::Publisher object_cloud_pub;
  ros::Publisher changes_pub;
  ros::Publisher object_changes_pub;  // ~object_changes: one ObjectChange per added, removed, moved
  std::atomic<bool> stopping{false};
  std::thread publisher_thread;
};

}  // namespace objmap::ros_node
