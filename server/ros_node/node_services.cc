// objmap_node's services: the gRPC API's queries over ROS. Every service call succeeds at the
// ROS level and carries `ok` and `error` (the reason, naming the field) in its response, so that
// a refused request is an answer a client can read, not a failed call.
#include "map_node_impl.h"
#include "ros_conversions.h"
#include "types/coco_classes.h"

namespace objmap::ros_node {
namespace {

// RayCast.max_range 0 means this many metres (as in the gRPC API).
constexpr double kDefaultRayRangeM = 10.0;

using ros_bridge::PointFromMsg;
using ros_bridge::PointToMsg;

std::uint8_t VoxelStateToMsg(VoxelState state) {
  switch (state) {
    case VoxelState::kFree:
      return objmap_msgs::Voxel::FREE;
    case VoxelState::kOccupied:
      return objmap_msgs::Voxel::OCCUPIED;
    default:
      return objmap_msgs::Voxel::UNKNOWN;
  }
}

// Sets ok / error from a status and logs refusals; always true (the call itself succeeded).
template <typename Response>
bool Answer(const char* service, const ServiceStatus& status, Response* response) {
  response->ok = status.ok();
  response->error = status.message;
  if (!status.ok()) ROS_WARN_STREAM("objmap_node: " << service << " refused: " << status.message);
  return true;
}

}  // namespace

void MapNode::Impl::AdvertiseServices() {
  services.push_back(
      private_node.advertiseService("query_objects", &MapNode::Impl::QueryObjects, this));
  services.push_back(private_node.advertiseService("get_object", &MapNode::Impl::GetObject, this));
  services.push_back(private_node.advertiseService("inventory", &MapNode::Impl::Inventory, this));
  services.push_back(
      private_node.advertiseService("query_occupancy", &MapNode::Impl::QueryOccupancy, this));
  services.push_back(private_node.advertiseService("is_free", &MapNode::Impl::IsFree, this));
  services.push_back(private_node.advertiseService("ray_cast", &MapNode::Impl::RayCast, this));
  services.push_back(
      private_node.advertiseService("get_octomap", &MapNode::Impl::GetOctomap, this));
  services.push_back(
      private_node.advertiseService("update_poses", &MapNode::Impl::UpdatePoses, this));
  services.push_back(
      private_node.advertiseService("start_session", &MapNode::Impl::StartSession, this));
  services.push_back(private_node.advertiseService("status", &MapNode::Impl::Status, this));
}

bool MapNode::Impl::QueryObjects(objmap_msgs::QueryObjects::Request& request,
                                 objmap_msgs::QueryObjects::Response& response) {
  ObjectFilter filter;
  if (!request.class_name.empty()) {
    // Map objects may also be "unknown": segmented, never named.
    const int class_id = ObjectClassId(request.class_name);
    if (class_id < 0) {
      return Answer("query_objects",
                    ServiceStatus::Invalid("class_name '" + request.class_name +
                                           "' is neither a COCO class nor \"unknown\""),
                    &response);
    }
    filter.class_id = class_id;
  }
  if (request.use_region) {
    std::string why;
    const Eigen::Vector3d min_W = PointFromMsg(request.region_min);
    const Eigen::Vector3d max_W = PointFromMsg(request.region_max);
    if (!ValidateBox(min_W, max_W, "region", &why)) {
      return Answer("query_objects", ServiceStatus::Invalid(why), &response);
    }
    filter.region = std::make_pair(min_W, max_W);
  }
  if (request.max_results < 0) {
    return Answer("query_objects",
                  ServiceStatus::Invalid("max_results " + std::to_string(request.max_results) +
                                         " must be >= 0 (0: all)"),
                  &response);
  }
  filter.min_confidence = request.min_confidence;
  if (request.use_nearest) filter.nearest_to = PointFromMsg(request.nearest_to);
  filter.max_results = static_cast<std::size_t>(request.max_results);
  filter.include_unconfirmed = request.include_unconfirmed;
  std::vector<std::shared_ptr<const ObjectView>> objects;
  const ServiceStatus status = server->QueryObjects(filter, &objects, &response.map_version);
  for (const auto& view : objects) {
    response.objects.emplace_back();
    ros_bridge::ObjectToMsg(*view, request.include_model, &response.objects.back());
  }
  return Answer("query_objects", status, &response);
}

bool MapNode::Impl::GetObject(objmap_msgs::GetObject::Request& request,
                              objmap_msgs::GetObject::Response& response) {
  std::shared_ptr<const ObjectView> view;
  response.map_version = server->Snapshot()->version;
  const ServiceStatus status = server->GetObject(request.id, &view);
  if (status.ok()) {
    ros_bridge::ObjectToMsg(*view, request.include_model || request.publish_model,
                            &response.object);
    if (request.publish_model) {
      sensor_msgs::PointCloud2 cloud = response.object.model;
      cloud.header.frame_id = config.world_frame;
      cloud.header.stamp = ros::Time::now();
      object_cloud_pub.publish(cloud);
      if (!request.include_model) response.object.model = sensor_msgs::PointCloud2();
    }
  }
  return Answer("get_object", status, &response);
}

bool MapNode::Impl::Inventory(objmap_msgs::Inventory::Request& request,
                              objmap_msgs::Inventory::Response& response) {
  std::optional<std::uint64_t> since;
  if (request.use_since_version) since = request.since_version;
  std::vector<InventoryEntry> entries;
  const ServiceStatus status = server->Inventory(since, &entries, &response.map_version);
  for (const InventoryEntry& entry : entries) {
    response.entries.emplace_back();
    ros_bridge::InventoryEntryToMsg(entry, &response.entries.back());
  }
  return Answer("inventory", status, &response);
}

bool MapNode::Impl::QueryOccupancy(objmap_msgs::QueryOccupancy::Request& request,
                                   objmap_msgs::QueryOccupancy::Response& response) {
  if (request.max_voxels < 0) {
    return Answer("query_occupancy",
                  ServiceStatus::Invalid("max_voxels " + std::to_string(request.max_voxels) +
                                         " must be >= 0 (0: the node's limit)"),
                  &response);
  }
  RegionOccupancy region;
  const ServiceStatus status = server->QueryOccupancy(
      PointFromMsg(request.region_min), PointFromMsg(request.region_max), request.resolution,
      request.include_voxels, static_cast<std::size_t>(request.max_voxels), &region,
      &response.map_version);
  if (status.ok()) {
    response.resolution = region.resolution_m;
    response.occupied = region.occupied;
    response.free = region.free;
    response.unknown = region.unknown;
    response.truncated = region.truncated;
    response.voxels.reserve(region.known_cells.size());
    for (const RegionOccupancy::Cell& cell : region.known_cells) {
      objmap_msgs::Voxel voxel;
      voxel.center = PointToMsg(cell.center_W);
      voxel.size = region.resolution_m;
      voxel.state = VoxelStateToMsg(cell.state);
      response.voxels.push_back(voxel);
    }
  }
  return Answer("query_occupancy", status, &response);
}

bool MapNode::Impl::IsFree(objmap_msgs::IsFree::Request& request,
                           objmap_msgs::IsFree::Response& response) {
  bool free = false;
  RegionOccupancy counts;
  std::vector<ObjectId> objects;
  const ServiceStatus status =
      server->IsFree(PointFromMsg(request.region_min), PointFromMsg(request.region_max),
                     request.unknown_is_free, &free, &counts, &objects, &response.map_version);
  if (status.ok()) {
    response.free = free;
    response.occupied = counts.occupied;
    response.unknown = counts.unknown;
    response.object_ids.assign(objects.begin(), objects.end());
  }
  return Answer("is_free", status, &response);
}

bool MapNode::Impl::RayCast(objmap_msgs::RayCast::Request& request,
                            objmap_msgs::RayCast::Response& response) {
  const double max_range_m = request.max_range == 0.0 ? kDefaultRayRangeM : request.max_range;
  RayHit hit;
  ObjectId object_hit = 0;
  const Eigen::Vector3d direction(request.direction.x, request.direction.y, request.direction.z);
  const ServiceStatus status =
      server->CastRay(PointFromMsg(request.origin), direction, max_range_m, request.unknown_stops,
                      &hit, &object_hit, &response.map_version);
  if (status.ok()) {
    response.hit = hit.hit;
    if (hit.hit) {
      response.hit_point = PointToMsg(hit.voxel_center_W);
      response.hit_state = VoxelStateToMsg(hit.state);
      response.distance = hit.distance_m;
      response.object_id = object_hit;
    }
  }
  return Answer("ray_cast", status, &response);
}

bool MapNode::Impl::GetOctomap(objmap_msgs::GetOctomap::Request& request,
                               objmap_msgs::GetOctomap::Response& response) {
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> region;
  if (request.use_region)
    region.emplace(PointFromMsg(request.region_min), PointFromMsg(request.region_max));
  std::string bytes;
  std::size_t leaf_count = 0;
  const ServiceStatus status =
      server->OctomapBytes(region, &bytes, &leaf_count, &response.map_version);
  if (status.ok()) {
    response.bt.assign(bytes.begin(), bytes.end());
    response.leaf_count = leaf_count;
  }
  return Answer("get_octomap", status, &response);
}

bool MapNode::Impl::UpdatePoses(objmap_msgs::UpdatePoses::Request& request,
                                objmap_msgs::UpdatePoses::Response& response) {
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (std::size_t i = 0; i < request.poses.size(); ++i) {
    const objmap_msgs::KeyframePose& pose = request.poses[i];
    std::string why;
    Eigen::Isometry3d T_W_C;
    if (!ros_bridge::PoseFromMsg(pose.T_W_C, "poses[" + std::to_string(i) + "].T_W_C", &T_W_C,
                                 &why)) {
      return Answer("update_poses", ServiceStatus::Invalid(why), &response);
    }
    if (!poses.emplace(pose.keyframe_id, T_W_C).second) {
      return Answer("update_poses",
                    ServiceStatus::Invalid("poses[" + std::to_string(i) + "]: keyframe " +
                                           std::to_string(pose.keyframe_id) + " appears twice"),
                    &response);
    }
  }
  PoseUpdateOutcome outcome;
  const ServiceStatus status = server->UpdatePoses(poses, request.wait, &outcome);
  if (status.ok()) {
    response.map_version = outcome.map_version;
    response.regenerated = outcome.regenerated;
    response.keyframes_moved = outcome.keyframes_moved;
    response.regeneration_ms = outcome.regeneration_ms;
    response.reassociated = outcome.reassociated;
    response.objects_before = outcome.objects_before;
    response.objects_after = outcome.objects_after;
  }
  return Answer("update_poses", status, &response);
}

bool MapNode::Impl::StartSession(objmap_msgs::StartSession::Request& request,
                                 objmap_msgs::StartSession::Response& response) {
  SessionSummary started;
  const ServiceStatus status = server->StartSession(request.name, &started);
  if (status.ok()) {
    response.session_id = started.session.id;
    response.session_name = started.session.name;
  }
  return Answer("start_session", status, &response);
}

bool MapNode::Impl::Status(objmap_msgs::Status::Request& /*request*/,
                           objmap_msgs::Status::Response& response) {
  const ServerStatus status = server->Status();
  response.map_version = status.map_version;
  response.keyframes = static_cast<std::int64_t>(status.keyframes);
  response.objects = static_cast<std::int64_t>(status.objects);
  response.confirmed_objects = static_cast<std::int64_t>(status.confirmed_objects);
  response.ingest_queue = status.queue_length;
  response.regenerating = status.regenerating;
  response.last_regeneration_ms = status.last_regeneration_ms;
  response.database = status.database;
  response.database_bytes = status.database_bytes;
  response.uptime_s = status.uptime_s;
  response.session_id = status.session_id;
  response.session_name = status.session_name;
  response.frames_received = frames_received;
  response.frames_rejected = frames_rejected;
  response.keyframes_sent = keyframes_sent;
  response.keyframes_held = keyframes_held;
  response.keyframes_attached = keyframes_attached;
  {
    std::lock_guard<std::mutex> lock(rejection_mutex);
    response.last_rejection = last_rejection;
  }
  return Answer("status", ServiceStatus::Ok(), &response);
}

}  // namespace objmap::ros_node
