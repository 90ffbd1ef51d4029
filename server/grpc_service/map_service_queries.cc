// The read side of MapServiceImpl: object, inventory and occupancy queries.
#include "grpc_service/conversions.h"
#include "grpc_service/handler_guard.h"
#include "grpc_service/map_service.h"

namespace objmap::grpc_service {
namespace {

// RayCastRequest.max_range 0 means this many metres.
constexpr double kDefaultRayRangeM = 10.0;

bool FilterFromProto(const v1::QueryObjectsRequest& request, ObjectFilter* filter,
                     std::string* why) {
  if (!request.class_name().empty()) {
    // Map objects may also be "unknown": segmented, never named.
    const int class_id = ObjectClassId(request.class_name());
    if (class_id < 0) {
      *why = "class_name '" + request.class_name() + "' is neither a COCO class nor \"unknown\"";
      return false;
    }
    filter->class_id = class_id;
  }
  if (request.has_region()) {
    std::pair<Eigen::Vector3d, Eigen::Vector3d> region;
    if (!BoxFromProto(request.region(), "region", &region, why)) return false;
    filter->region = region;
  }
  filter->min_confidence = request.min_confidence();
  if (request.has_nearest_to()) filter->nearest_to = Vec3FromProto(request.nearest_to());
  if (request.max_results() < 0) {
    *why = "max_results " + std::to_string(request.max_results()) + " must be >= 0 (0: all)";
    return false;
  }
  filter->max_results = static_cast<std::size_t>(request.max_results());
  filter->include_unconfirmed = request.include_unconfirmed();
  return true;
}

// The box of a request that must have one.
bool RequiredBox(bool has_box, const v1::Box& box,
                 std::pair<Eigen::Vector3d, Eigen::Vector3d>* box_W, std::string* why) {
  if (!has_box) {
    *why = "region is required";
    return false;
  }
  return BoxFromProto(box, "region", box_W, why);
}

}  // namespace

grpc::Status MapServiceImpl::ListKeyframes(grpc::ServerContext* /*context*/,
                                           const v1::ListKeyframesRequest* request,
                                           v1::ListKeyframesResponse* response) {
  return Guarded("ListKeyframes", [&] {
    if (request->max_results() < 0) {
      return Invalid("max_results " + std::to_string(request->max_results()) +
                     " must be >= 0 (0: all)");
    }
    std::vector<KeyframeSummary> keyframes;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(
        server_.ListKeyframes(request->first_id(), static_cast<std::size_t>(request->max_results()),
                              &keyframes, &version));
    if (!status.ok()) return status;
    response->set_map_version(version);
    for (const KeyframeSummary& keyframe : keyframes) {
      v1::KeyframeInfo* info = response->add_keyframes();
      info->set_id(keyframe.id);
      info->set_stamp(keyframe.stamp_s);
      info->set_name(keyframe.name);
      *info->mutable_t_w_c() = PoseToProto(keyframe.T_W_C);
      info->set_session_id(keyframe.session_id);
    }
    return status;
  });
}

grpc::Status MapServiceImpl::StartSession(grpc::ServerContext* /*context*/,
                                          const v1::StartSessionRequest* request,
                                          v1::Session* response) {
  return Guarded("StartSession", [&] {
    SessionSummary started;
    const grpc::Status status = ToGrpcStatus(server_.StartSession(request->name(), &started));
    if (status.ok()) SessionToProto(started, /*current=*/true, response);
    return status;
  });
}

grpc::Status MapServiceImpl::ListSessions(grpc::ServerContext* /*context*/,
                                          const v1::ListSessionsRequest* /*request*/,
                                          v1::ListSessionsResponse* response) {
  return Guarded("ListSessions", [&] {
    std::vector<SessionSummary> sessions;
    SessionId current = 0;
    const grpc::Status status = ToGrpcStatus(server_.ListSessions(&sessions, &current));
    if (!status.ok()) return status;
    for (const SessionSummary& session : sessions) {
      SessionToProto(session, session.session.id == current, response->add_sessions());
    }
    response->set_current_session_id(current);
    return status;
  });
}

grpc::Status MapServiceImpl::QueryObjects(grpc::ServerContext* /*context*/,
                                          const v1::QueryObjectsRequest* request,
                                          v1::QueryObjectsResponse* response) {
  return Guarded("QueryObjects", [&] {
    ObjectFilter filter;
    std::string why;
    if (!FilterFromProto(*request, &filter, &why)) return Invalid(why);
    std::vector<std::shared_ptr<const ObjectView>> objects;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(server_.QueryObjects(filter, &objects, &version));
    if (!status.ok()) return status;
    response->set_map_version(version);
    for (const auto& view : objects) {
      ObjectToProto(*view, request->include_model(), response->add_objects());
    }
    return status;
  });
}

grpc::Status MapServiceImpl::GetObject(grpc::ServerContext* /*context*/,
                                       const v1::GetObjectRequest* request, v1::Object* response) {
  return Guarded("GetObject", [&] {
    std::shared_ptr<const ObjectView> view;
    const grpc::Status status = ToGrpcStatus(server_.GetObject(request->id(), &view));
    if (status.ok()) ObjectToProto(*view, request->include_model(), response);
    return status;
  });
}

grpc::Status MapServiceImpl::ListChanges(grpc::ServerContext* /*context*/,
                                         const v1::ListChangesRequest* request,
                                         v1::ListChangesResponse* response) {
  return Guarded("ListChanges", [&] {
    ChangeFilter filter;
    if (request->has_since_version()) filter.since_version = request->since_version();
    if (request->has_since_stamp()) filter.since_stamp_s = request->since_stamp();
    if (request->has_since_session()) filter.since_session = request->since_session();
    std::vector<MapObjectChange> changes;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(server_.ListChanges(filter, &changes, &version));
    if (!status.ok()) return status;
    for (const MapObjectChange& change : changes) {
      ObjectChangeToProto(change, response->add_changes());
    }
    response->set_map_version(version);
    return status;
  });
}

grpc::Status MapServiceImpl::Inventory(grpc::ServerContext* /*context*/,
                                       const v1::InventoryRequest* request,
                                       v1::InventoryResponse* response) {
  return Guarded("Inventory", [&] {
    std::optional<std::uint64_t> since;
    if (request->has_since_version()) since = request->since_version();
    std::vector<InventoryEntry> entries;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(server_.Inventory(since, &entries, &version));
    if (!status.ok()) return status;
    response->set_map_version(version);
    for (const InventoryEntry& entry : entries) {
      InventoryEntryToProto(entry, response->add_entries());
    }
    return status;
  });
}

grpc::Status MapServiceImpl::QueryOccupancy(grpc::ServerContext* /*context*/,
                                            const v1::QueryOccupancyRequest* request,
                                            v1::QueryOccupancyResponse* response) {
  return Guarded("QueryOccupancy", [&] {
    std::pair<Eigen::Vector3d, Eigen::Vector3d> box_W;
    std::string why;
    if (!RequiredBox(request->has_region(), request->region(), &box_W, &why)) return Invalid(why);
    if (request->max_voxels() < 0) {
      return Invalid("max_voxels " + std::to_string(request->max_voxels()) +
                     " must be >= 0 (0: the server's limit)");
    }
    RegionOccupancy region;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(server_.QueryOccupancy(
        box_W.first, box_W.second, request->resolution(), request->include_voxels(),
        static_cast<std::size_t>(request->max_voxels()), &region, &version));
    if (!status.ok()) return status;
    response->set_map_version(version);
    response->set_resolution(region.resolution_m);
    response->set_occupied(region.occupied);
    response->set_free(region.free);
    response->set_unknown(region.unknown);
    response->set_truncated(region.truncated);
    for (const RegionOccupancy::Cell& cell : region.known_cells) {
      v1::Voxel* voxel = response->add_voxels();
      *voxel->mutable_center() = Vec3ToProto(cell.center_W);
      voxel->set_size(region.resolution_m);
      voxel->set_state(VoxelStateToProto(cell.state));
    }
    return status;
  });
}

grpc::Status MapServiceImpl::IsFree(grpc::ServerContext* /*context*/,
                                    const v1::IsFreeRequest* request,
                                    v1::IsFreeResponse* response) {
  return Guarded("IsFree", [&] {
    std::pair<Eigen::Vector3d, Eigen::Vector3d> box_W;
    std::string why;
    if (!RequiredBox(request->has_region(), request->region(), &box_W, &why)) return Invalid(why);
    bool free = false;
    RegionOccupancy counts;
    std::uint64_t version = 0;
    std::vector<ObjectId> objects;
    const grpc::Status status = ToGrpcStatus(server_.IsFree(
        box_W.first, box_W.second, request->unknown_is_free(), &free, &counts, &objects, &version));
    if (!status.ok()) return status;
    response->set_free(free);
    response->set_occupied(counts.occupied);
    response->set_unknown(counts.unknown);
    response->mutable_object_ids()->Add(objects.begin(), objects.end());
    response->set_map_version(version);
    return status;
  });
}

grpc::Status MapServiceImpl::RayCast(grpc::ServerContext* /*context*/,
                                     const v1::RayCastRequest* request,
                                     v1::RayCastResponse* response) {
  return Guarded("RayCast", [&] {
    const double max_range_m =
        request->max_range() == 0.0 ? kDefaultRayRangeM : request->max_range();
    RayHit hit;
    ObjectId object_hit = 0;
    std::uint64_t version = 0;
    const grpc::Status status = ToGrpcStatus(
        server_.CastRay(Vec3FromProto(request->origin()), Vec3FromProto(request->direction()),
                        max_range_m, request->unknown_stops(), &hit, &object_hit, &version));
    if (!status.ok()) return status;
    response->set_hit(hit.hit);
    if (hit.hit) {
      *response->mutable_hit_point() = Vec3ToProto(hit.voxel_center_W);
      response->set_hit_state(VoxelStateToProto(hit.state));
      response->set_distance(hit.distance_m);
      response->set_object_id(object_hit);
    }
    response->set_map_version(version);
    return status;
  });
}

grpc::Status MapServiceImpl::GetOctomap(grpc::ServerContext* /*context*/,
                                        const v1::GetOctomapRequest* request,
                                        v1::GetOctomapResponse* response) {
  return Guarded("GetOctomap", [&] {
    std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> region;
    std::string why;
    if (request->has_region()) {
      region.emplace();
      if (!BoxFromProto(request->region(), "region", &*region, &why)) return Invalid(why);
    }
    std::size_t leaf_count = 0;
    std::uint64_t version = 0;
    const grpc::Status status =
        ToGrpcStatus(server_.OctomapBytes(region, response->mutable_bt(), &leaf_count, &version));
    if (!status.ok()) return status;
    response->set_map_version(version);
    response->set_leaf_count(leaf_count);
    return status;
  });
}

}  // namespace objmap::grpc_service
