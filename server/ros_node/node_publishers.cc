// objmap_node's published topics: map changes, object markers and occupied cells, all from one
// thread that follows MapServer::ChangesSince.
#include <nav_msgs/Path.h>
#include <objmap_msgs/MapChange.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "map_node_impl.h"
#include "ros_conversions.h"
#include "types/coco_classes.h"

namespace objmap::ros_node {
namespace {

// How long one wait for changes lasts; bounds how late the loop notices a shutdown.
constexpr std::chrono::milliseconds kChangeWait{200};

// A colour per class, spread around the hue circle by the golden angle so that neighbouring
// class ids differ visibly; the same class always gets the same colour.
std_msgs::ColorRGBA ClassColor(int class_id, float alpha) {
  const double hue = std::fmod(std::max(class_id, 0) * 0.618033988749895, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(hue, 2.0) - 1.0);
  const int sector = static_cast<int>(hue);
  const double rgb[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
  std_msgs::ColorRGBA color;
  color.r = static_cast<float>(0.15 + 0.85 * rgb[sector % 6][0]);
  color.g = static_cast<float>(0.15 + 0.85 * rgb[sector % 6][1]);
  color.b = static_cast<float>(0.15 + 0.85 * rgb[sector % 6][2]);
  color.a = alpha;
  return color;
}

sensor_msgs::PointCloud2 XyzCloud(const std::vector<Eigen::Vector3d>& centers) {
  ColoredPoints points;
  points.points.reserve(centers.size());
  for (const Eigen::Vector3d& center : centers) points.points.push_back(center.cast<float>());
  sensor_msgs::PointCloud2 cloud = ros_bridge::PointsToMsg(points);
  // Occupied cells carry no colour: keep x y z only.
  cloud.fields.resize(3);
  return cloud;
}

}  // namespace

void MapNode::Impl::AdvertiseTopics() {
  // Latched: a visualiser or planner that starts later gets the current state at once.
  markers_pub = private_node.advertise<visualization_msgs::MarkerArray>("objects", 1, true);
  occupied_pub = private_node.advertise<sensor_msgs::PointCloud2>("occupied_cells", 1, true);
  object_cloud_pub = private_node.advertise<sensor_msgs::PointCloud2>("object_cloud", 10);
  changes_pub = private_node.advertise<objmap_msgs::MapChange>("map_changes", 100);
  object_changes_pub = private_node.advertise<objmap_msgs::ObjectChange>("object_changes", 100);
  if (config.estimates_poses()) {
    trajectory_pub = private_node.advertise<nav_msgs::Path>("trajectory", 1, true);
  }
}

void MapNode::Impl::PublishMarkers(const MapSnapshot& snapshot) {
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.header.frame_id = config.world_frame;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);
  const ros::Time now = ros::Time::now();
  for (const auto& [id, view] : snapshot.objects) {
    visualization_msgs::Marker box;
    box.header.frame_id = config.world_frame;
    box.header.stamp = now;
    box.ns = "objects";
    box.id = static_cast<int>(id);
    box.type = visualization_msgs::Marker::CUBE;
    box.action = visualization_msgs::Marker::ADD;
    const Eigen::Vector3f center = 0.5f * (view->min_W + view->max_W);
    const Eigen::Vector3f size = (view->max_W - view->min_W).cwiseMax(0.005f);
    box.pose.position.x = center.x();
    box.pose.position.y = center.y();
    box.pose.position.z = center.z();
    box.pose.orientation.w = 1.0;
    box.scale.x = size.x();
    box.scale.y = size.y();
    box.scale.z = size.z();
    // Objects not (yet) in the inventory are drawn faint.
    box.color = ClassColor(view->class_id, view->confirmed ? 0.5f : 0.15f);
    markers.markers.push_back(box);

    visualization_msgs::Marker label = box;
    label.ns = "labels";
    label.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    label.pose.position.z = view->max_W.z() + 0.05;
    label.scale.x = label.scale.y = 0.0;
    label.scale.z = 0.06;
    label.color.a = 1.0f;
    std::ostringstream text;
    text << ObjectClassName(view->class_id) << " #" << id << " " << std::fixed
         << std::setprecision(2) << view->confidence;
    label.text = text.str();
    markers.markers.push_back(label);
  }
  markers_pub.publish(markers);
}

void MapNode::Impl::PublishOccupiedCells() {
  std::vector<Eigen::Vector3d> centers;
  std::uint64_t version = 0;
  const ServiceStatus status = server->OccupiedCenters(
      static_cast<std::size_t>(config.publish.occupied_max_points), &centers, &version);
  if (!status.ok()) {
    ROS_WARN_STREAM("objmap_node: occupied cells not published: " << status.message);
    return;
  }
  sensor_msgs::PointCloud2 cloud = XyzCloud(centers);
  cloud.header.frame_id = config.world_frame;
  cloud.header.stamp = ros::Time::now();
  occupied_pub.publish(cloud);
}

void MapNode::Impl::PublishChangesLoop() {
  std::uint64_t seen = server->Snapshot()->version;
  int keyframes_since_cells = 0;
  // The state at start (a restored map) is published once.
  if (config.publish.markers) PublishMarkers(*server->Snapshot());
  if (config.publish.occupied_every_keyframes > 0 && seen > 0) PublishOccupiedCells();
  while (!stopping && !server->shutting_down()) {
    const std::vector<MapChange> changes = server->ChangesSince(seen, kChangeWait);
    if (changes.empty()) continue;
    bool regenerated = false;
    for (const MapChange& change : changes) {
      objmap_msgs::MapChange msg;
      ros_bridge::MapChangeToMsg(change, &msg);
      changes_pub.publish(msg);
      for (const objmap_msgs::ObjectChange& object_change : msg.object_changes) {
        object_changes_pub.publish(object_change);
      }
      seen = std::max(seen, change.version);
      if (change.kind == MapChange::Kind::kKeyframeAdded) ++keyframes_since_cells;
      if (change.kind == MapChange::Kind::kPosesUpdated) regenerated = true;
    }
    if (config.publish.markers) PublishMarkers(*server->Snapshot());
    const int every = config.publish.occupied_every_keyframes;
    if (every > 0 && (regenerated || keyframes_since_cells >= every)) {
      PublishOccupiedCells();
      keyframes_since_cells = 0;
    }
  }
}

}  // namespace objmap::ros_node
