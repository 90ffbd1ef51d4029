#include "map_node.h"

#include <nav_msgs/Path.h>
#include <tf2/exceptions.h>

#include <iomanip>
#include <sstream>

#include "map_node_impl.h"
#include "ros_conversions.h"

namespace objmap::ros_node {
namespace {

// Recent poses kept from the pose topic, to pair with frames by stamp.
constexpr std::size_t kMaxRecentPoses = 1000;

template <typename Policy>
struct IsApproximateTime : std::false_type {};
template <typename... Messages>
struct IsApproximateTime<message_filters::sync_policies::ApproximateTime<Messages...>>
    : std::true_type {};

std::string StampText(const ros::Time& stamp) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << stamp.toSec();
  return text.str();
}

}  // namespace

MapNode::Impl::Impl(const ros::NodeHandle& node_in, const ros::NodeHandle& private_node_in,
                    const NodeConfig& config_in, std::shared_ptr<MapServer> server_in)
    : node(node_in),
      private_node(private_node_in),
      config(config_in),
      server(std::move(server_in)),
      keyframe_selector(config_in.objmap.keyframes) {}

MapNode::MapNode(const ros::NodeHandle& node, const ros::NodeHandle& private_node,
                 const NodeConfig& config, std::shared_ptr<MapServer> server,
                 std::unique_ptr<FrameStream> camera)
    : impl_(std::make_unique<Impl>(node, private_node, config, std::move(server))) {
  impl_->AdvertiseTopics();
  impl_->AdvertiseServices();
  if (impl_->config.estimates_poses()) {
    // The node tracks every camera frame at the camera's rate: loop searches and graph solves
    // run beside tracking instead of holding frames up.
    OdometryConfig odometry = impl_->config.objmap.map_server.odometry;
    odometry.background_loop_closure = true;
    impl_->odometry = std::make_unique<RgbdOdometry>(odometry);
    impl_->tf_broadcaster = std::make_unique<tf2_ros::TransformBroadcaster>();
    impl_->ResumeTracking();
  }
  impl_->camera = std::move(camera);
  if (impl_->camera) {
    if (!impl_->config.openni2.static_camera && !impl_->config.estimates_poses()) {
      impl_->tf_listener = std::make_unique<tf2_ros::TransformListener>(impl_->tf_buffer, node);
    }
    impl_->camera_thread = std::thread([impl = impl_.get()] { impl->ReadCameraLoop(); });
  } else {
    impl_->SubscribeInputs();
  }
  impl_->publisher_thread = std::thread([impl = impl_.get()] { impl->PublishChangesLoop(); });
}

MapNode::~MapNode() {
  impl_->stopping = true;
  if (impl_->frame_spinner) impl_->frame_spinner->stop();
  impl_->pose_arrived.notify_all();
  if (impl_->camera_thread.joinable()) impl_->camera_thread.join();
  if (impl_->publisher_thread.joinable()) impl_->publisher_thread.join();
}

void MapNode::Impl::SubscribeInputs() {
  // The input subscribers deliver on frame_queue, so a keyframe being mapped (hundreds of ms)
  // blocks only the frames behind it, never the services.
  ros::NodeHandle input_node(node);
  input_node.setCallbackQueue(&frame_queue);
  const auto queue = static_cast<std::uint32_t>(config.sync_queue_size);
  color_sub.subscribe(input_node, "rgb/image", queue);
  depth_sub.subscribe(input_node, "depth/image", queue);
  info_sub.subscribe(input_node, "rgb/camera_info", queue);
  using message_filters::sync_policies::ApproximateTime;
  using message_filters::sync_policies::ExactTime;
  using sensor_msgs::CameraInfo;
  using sensor_msgs::Image;
  const bool exact = config.sync_max_interval_s == 0.0;
  if (config.detections_topic.empty()) {
    synchronizer = exact ? Synchronize<ExactTime<Image, Image, CameraInfo>>(
                               &MapNode::Impl::OnImages, color_sub, depth_sub, info_sub)
                         : Synchronize<ApproximateTime<Image, Image, CameraInfo>>(
                               &MapNode::Impl::OnImages, color_sub, depth_sub, info_sub);
  } else {
    using objmap_msgs::DetectionArray;
    detections_sub.subscribe(input_node, config.detections_topic, queue);
    synchronizer =
        exact ? Synchronize<ExactTime<Image, Image, CameraInfo, DetectionArray>>(
                    &MapNode::Impl::OnFrame, color_sub, depth_sub, info_sub, detections_sub)
              : Synchronize<ApproximateTime<Image, Image, CameraInfo, DetectionArray>>(
                    &MapNode::Impl::OnFrame, color_sub, depth_sub, info_sub, detections_sub);
  }
  if (config.estimates_poses()) {
    // Poses are tracked from the frames: neither TF nor a pose topic is read.
  } else if (!config.pose_topic.empty()) {
    // Poses arrive on the global queue: a frame waiting for its pose on frame_queue must not
    // hold back the pose it waits for.
    pose_sub = node.subscribe(config.pose_topic, 100, &MapNode::Impl::OnPose, this);
  } else {
    tf_listener = std::make_unique<tf2_ros::TransformListener>(tf_buffer, node);
  }
  frame_spinner = std::make_unique<ros::AsyncSpinner>(1, &frame_queue);
  frame_spinner->start();
}

template <typename Policy, typename Callback, typename... Subscribers>
std::shared_ptr<void> MapNode::Impl::Synchronize(Callback callback, Subscribers&... subscribers) {
  auto synchronizer = std::make_shared<message_filters::Synchronizer<Policy>>(
      Policy(static_cast<std::uint32_t>(config.sync_queue_size)), subscribers...);
  if constexpr (IsApproximateTime<Policy>::value) {
    synchronizer->setMaxIntervalDuration(ros::Duration(config.sync_max_interval_s));
  }
  synchronizer->registerCallback(callback, this);
  return synchronizer;
}

void MapNode::Impl::OnImages(const sensor_msgs::ImageConstPtr& color,
                             const sensor_msgs::ImageConstPtr& depth,
                             const sensor_msgs::CameraInfoConstPtr& info) {
  OnFrame(color, depth, info, nullptr);
}

void MapNode::Impl::OnPose(const geometry_msgs::PoseStampedConstPtr& pose) {
  {
    std::lock_guard<std::mutex> lock(pose_mutex);
    recent_poses.push_back(*pose);
    if (recent_poses.size() > kMaxRecentPoses) recent_poses.pop_front();
  }
  pose_arrived.notify_all();
}

bool MapNode::Impl::PoseFromTopic(const ros::Time& stamp, Eigen::Isometry3d* T_W_C,
                                  std::string* why) {
  const ros::Duration tolerance(config.sync_max_interval_s);
  std::unique_lock<std::mutex> lock(pose_mutex);
  const geometry_msgs::PoseStamped* best = nullptr;
  // Waits until a pose within the tolerance arrived, or one after it (then none will come).
  const auto settled = [&] {
    best = nullptr;
    for (const auto& pose : recent_poses) {
      const ros::Duration gap = pose.header.stamp - stamp;
      if (std::abs(gap.toSec()) <= tolerance.toSec() &&
          (best == nullptr ||
           std::abs(gap.toSec()) < std::abs((best->header.stamp - stamp).toSec()))) {
        best = &pose;
      }
    }
    return stopping || best != nullptr ||
           (!recent_poses.empty() && recent_poses.back().header.stamp > stamp + tolerance);
  };
  pose_arrived.wait_for(lock, std::chrono::duration<double>(config.pose_timeout_s), settled);
  if (best == nullptr) {
    *why = "no pose on " + config.pose_topic + " within " +
           std::to_string(config.sync_max_interval_s) + " s of t=" + StampText(stamp);
    return false;
  }
  return ros_bridge::PoseFromMsg(best->pose, config.pose_topic + " pose", T_W_C, why);
}

bool MapNode::Impl::CameraPose(const sensor_msgs::Image& color, Eigen::Isometry3d* T_W_C,
                               std::string* why) {
  const ros::Time stamp = color.header.stamp;
  if (!config.pose_topic.empty()) return PoseFromTopic(stamp, T_W_C, why);
  const std::string camera_frame =
      config.camera_frame.empty() ? color.header.frame_id : config.camera_frame;
  if (camera_frame.empty()) {
    *why = "the colour image has no header.frame_id and ~camera_frame is not set";
    return false;
  }
  return PoseFromTf(camera_frame, stamp, T_W_C, why);
}

bool MapNode::Impl::PoseFromTf(const std::string& camera_frame, const ros::Time& stamp,
                               Eigen::Isometry3d* T_W_C, std::string* why) {
  try {
    const geometry_msgs::TransformStamped transform = tf_buffer.lookupTransform(
        config.world_frame, camera_frame, stamp, ros::Duration(config.pose_timeout_s));
    return ros_bridge::TransformFromMsg(
        transform.transform, "TF " + config.world_frame + " <- " + camera_frame, T_W_C, why);
  } catch (const tf2::TransformException& e) {
    *why = "no transform from '" + camera_frame + "' to '" + config.world_frame +
           "' at t=" + StampText(stamp) + ": " + e.what();
    return false;
  }
}

void MapNode::Impl::Reject(const ros::Time& stamp, const std::string& why) {
  ++frames_rejected;
  const std::string message = "frame at t=" + StampText(stamp) + " rejected: " + why;
  ROS_WARN_STREAM("objmap_node: " << message);
  std::lock_guard<std::mutex> lock(rejection_mutex);
  last_rejection = message;
}

void MapNode::Impl::OnFrame(const sensor_msgs::ImageConstPtr& color,
                            const sensor_msgs::ImageConstPtr& depth,
                            const sensor_msgs::CameraInfoConstPtr& info,
                            const objmap_msgs::DetectionArrayConstPtr& detections) {
  // Counted once handled, whatever the outcome: a player that waits for its frame to be taken
  // in watches this count.
  struct CountWhenDone {
    std::atomic<long long>& count;
    ~CountWhenDone() { ++count; }
  } count_when_done{frames_received};
  if (stopping) return;
  const ros::Time stamp = color->header.stamp;
  std::string why;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  if (!config.estimates_poses() && !CameraPose(*color, &T_W_C, &why)) return Reject(stamp, why);
  RgbdFrame frame;
  if (!ros_bridge::FrameFromMsgs(*color, *depth, *info, T_W_C, config.depth_scale, &frame, &why)) {
    return Reject(stamp, why);
  }
  frame.frame_index = frames_received.load();
  frame.name = "frame at t=" + StampText(stamp);
  if (config.estimates_poses()) {
    const std::string camera_frame = !config.camera_frame.empty() ? config.camera_frame
                                     : !color->header.frame_id.empty() ? color->header.frame_id
                                                                        : "camera";
    if (!TrackFrame(&frame, stamp, camera_frame, &why)) return Reject(stamp, why);
  }
  std::optional<std::vector<Detection>> given;
  if (detections) {
    given.emplace();
    for (std::size_t i = 0; i < detections->detections.size(); ++i) {
      Detection detection;
      if (!ros_bridge::DetectionFromMsg(detections->detections[i],
                                        "detections[" + std::to_string(i) + "]", &detection,
                                        &why)) {
        return Reject(stamp, why);
      }
      given->push_back(detection);
    }
  } else if (!config.run_detector) {
    given.emplace();  // structure only
  }
  TakeFrame(std::move(frame), stamp, std::move(given));
}

void MapNode::Impl::ReadCameraLoop() {
  const std::string source = camera->Describe();
  ROS_INFO_STREAM("objmap_node: reading " << source);
  while (!stopping) {
    RgbdFrame frame;
    std::string why;
    const FrameStatus status = camera->Next(&frame, &why);
    // The camera's own clock is not ROS time: a frame is placed at the moment it was read.
    const ros::Time stamp = ros::Time::now();
    if (status == FrameStatus::kEnded) {
      ROS_INFO_STREAM("objmap_node: " << source << " ended; the map is still served");
      return;
    }
    if (status == FrameStatus::kFailed) {
      ROS_ERROR_STREAM("objmap_node: " << source << " failed: " << why
                                       << "; the map is still served");
      std::lock_guard<std::mutex> lock(rejection_mutex);
      last_rejection = source + " failed: " + why;
      return;
    }
    // A static camera needs no pose; otherwise it is tracked or looked up in TF.
    if (status == FrameStatus::kFrame && !config.openni2.static_camera &&
        config.estimates_poses() &&
        !TrackFrame(&frame, stamp, config.camera_frame.empty() ? "camera" : config.camera_frame,
                    &why)) {
      Reject(stamp, why);
    } else if (status == FrameStatus::kFrame && !config.openni2.static_camera &&
               !config.estimates_poses() &&
               !PoseFromTf(config.camera_frame, stamp, &frame.T_W_C, &why)) {
      Reject(stamp, why);
    } else if (status == FrameStatus::kBadFrame) {
      Reject(stamp, why);
    } else {
      frame.stamp_s = stamp.toSec();
      std::optional<std::vector<Detection>> detections;
      if (!config.run_detector) detections.emplace();  // structure only
      TakeFrame(std::move(frame), stamp, std::move(detections));
    }
    ++frames_received;
  }
}

void MapNode::Impl::ResumeTracking() {
  std::string resumed_from;
  tracking_blocked = server->StartTrackingOnStoredMap(odometry.get(), &resumed_from).message;
  if (!tracking_blocked.empty()) {
    ROS_ERROR_STREAM("objmap_node: " << tracking_blocked);
  } else if (!resumed_from.empty()) {
    ROS_INFO_STREAM("objmap_node: tracking resumes from " << resumed_from);
  }
}

bool MapNode::Impl::TrackFrame(RgbdFrame* frame, const ros::Time& stamp,
                               const std::string& camera_frame, std::string* why) {
  last_tracking.reset();
  if (!tracking_blocked.empty()) {
    *why = tracking_blocked;
    return false;
  }
  const TrackingReport report = odometry->Track(*frame);
  if (report.status == TrackingStatus::kLost) {
    *why = "tracking lost: " + report.why;
    return false;
  }
  frame->T_W_C = report.T_W_C;
  if (report.status == TrackingStatus::kProvisional) {
    // Tracked in a frame of its own until a frame is placed in the map: nothing to publish in
    // the map's frame yet; TakeFrame holds it.
    last_tracking = report;
    return true;
  }
  geometry_msgs::TransformStamped transform;
  transform.header.stamp = stamp;
  transform.header.frame_id = config.world_frame;
  transform.child_frame_id = camera_frame;
  transform.transform = ros_bridge::TransformToMsg(report.T_W_C);
  tf_broadcaster->sendTransform(transform);
  if (report.loops_closed > 0 && !tracked_keyframes.empty()) {
    // The loop moved the odometry's keyframes: the mapped keyframes follow, regenerated in the
    // background while queries go on.
    PoseUpdateOutcome update;
    const ServiceStatus moved =
        server->UpdatePoses(tracked_keyframes.Poses(*odometry), /*wait=*/false, &update);
    if (!moved.ok()) {
      ROS_ERROR_STREAM("objmap_node: a loop closed but the map's poses were not updated: "
                       << moved.message);
    }
    PublishTrajectory();
  }
  last_tracking = report;
  return true;
}

void MapNode::Impl::PublishTrajectory() {
  nav_msgs::Path path;
  path.header.stamp = ros::Time::now();
  path.header.frame_id = config.world_frame;
  for (const auto& [id, T_W_C] : tracked_keyframes.Poses(*odometry)) {
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = config.world_frame;
    pose.header.stamp = keyframe_stamps[id];
    pose.pose = ros_bridge::PoseToMsg(T_W_C);
    path.poses.push_back(pose);
  }
  trajectory_pub.publish(path);
}

void MapNode::Impl::TakeFrame(RgbdFrame frame, const ros::Time& stamp,
                              std::optional<std::vector<Detection>> detections) {
  if (last_tracking && last_tracking->status == TrackingStatus::kProvisional) {
    return HoldFrame(std::move(frame), stamp, std::move(detections));
  }
  if (last_tracking && last_tracking->attached_fragment > 0) {
    MapHeldFrames(last_tracking->attached_fragment);
  }
  MapFrame(std::move(frame), stamp, std::move(detections));
}

void MapNode::Impl::HoldFrame(RgbdFrame frame, const ros::Time& stamp,
                              std::optional<std::vector<Detection>> detections) {
  const TrackingReport& report = *last_tracking;
  if (!part_keyframe_selector || part_of_selector != report.fragment) {
    part_keyframe_selector.emplace(config.objmap.keyframes);
    part_of_selector = report.fragment;
  }
  if (!part_keyframe_selector->IsKeyframe(report.T_W_C)) return;
  const auto limit = static_cast<std::size_t>(config.objmap.map_server.max_held_keyframes);
  if (limit == 0) {
    return Reject(stamp, "not placed in the map yet (" + report.why +
                             "), and server.max_held_keyframes is 0: not held");
  }
  const auto dropped =
      held_frames.Hold({std::move(frame), stamp, std::move(detections)}, report, *odometry, limit);
  for (const auto& held : dropped) {
    // The oldest part's first keyframes go: a part that long unplaced is the least likely to be
    // placed.
    Reject(held.payload.stamp, "held " + std::to_string(limit) +
                                   " keyframes of parts of the session not placed in the map "
                                   "(server.max_held_keyframes): the oldest is dropped");
  }
  keyframes_held = static_cast<long long>(held_frames.size());
  ROS_INFO_STREAM_THROTTLE(5.0, "objmap_node: not placed in the map yet ("
                                    << report.why << "); " << held_frames.size()
                                    << " keyframe(s) held until the session's part is placed");
}

void MapNode::Impl::MapHeldFrames(int fragment) {
  auto frames = held_frames.Take(fragment);
  if (frames.empty()) return;
  keyframes_held = static_cast<long long>(held_frames.size());
  for (auto& held : frames) {
    held.payload.frame.T_W_C = held.T_W_C(*odometry);
    if (SendKeyframe(std::move(held.payload.frame), held.payload.stamp,
                     std::move(held.payload.detections), held.odometry_keyframe, held.T_K_C)) {
      ++keyframes_attached;
    }
  }
  ROS_INFO_STREAM("objmap_node: the session's part " << fragment << " is placed in the map; "
                                                     << frames.size()
                                                     << " held keyframe(s) mapped");
  PublishTrajectory();
}

void MapNode::Impl::MapFrame(RgbdFrame frame, const ros::Time& stamp,
                             std::optional<std::vector<Detection>> detections) {
  if (!keyframe_selector.IsKeyframe(frame.T_W_C)) return;
  const bool tracked = config.estimates_poses() && last_tracking;
  const int odometry_keyframe = tracked ? last_tracking->reference_keyframe : -1;
  const Eigen::Isometry3d T_K_C =
      tracked ? PoseOnReferenceKeyframe(*last_tracking, *odometry) : Eigen::Isometry3d::Identity();
  if (SendKeyframe(std::move(frame), stamp, std::move(detections), odometry_keyframe, T_K_C) &&
      tracked) {
    PublishTrajectory();
  }
}

bool MapNode::Impl::SendKeyframe(RgbdFrame frame, const ros::Time& stamp,
                                 std::optional<std::vector<Detection>> detections,
                                 int odometry_keyframe, const Eigen::Isometry3d& T_K_C) {
  AddKeyframeOutcome outcome;
  const ServiceStatus status =
      server->AddKeyframe(std::move(frame), std::move(detections), &outcome);
  if (!status.ok()) {
    Reject(stamp, "the map server refused it: " + status.message);
    return false;
  }
  ++keyframes_sent;
  // A keyframe kept as a revisit of a stored view (thinning) is no keyframe of the map.
  if (odometry_keyframe >= 0 && outcome.keyframe_id != 0) {
    tracked_keyframes.AddRelative(outcome.keyframe_id, odometry_keyframe, T_K_C);
    keyframe_stamps[outcome.keyframe_id] = stamp;
  }
  ROS_DEBUG_STREAM("objmap_node: keyframe " << outcome.keyframe_id << " from t=" << StampText(stamp)
                                            << ", map version " << outcome.map_version);
  return true;
}

}  // namespace objmap::ros_node
