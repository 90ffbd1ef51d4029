// The write side of MapServiceImpl (AddKeyframe, IngestKeyframes, UpdatePoses) with Status and
// WatchMap; the queries are in map_service_queries.cc.
#include "grpc_service/map_service.h"

#include <algorithm>

#include "grpc_service/conversions.h"
#include "grpc_service/handler_guard.h"
#include "grpc_service/keyframe_conversions.h"

namespace objmap::grpc_service {
namespace {

void OutcomeToProto(const AddKeyframeOutcome& outcome, v1::AddKeyframeResponse* response) {
  response->set_keyframe_id(outcome.keyframe_id);
  response->set_map_version(outcome.map_version);
  response->set_detections_used(outcome.detections_used);
  response->mutable_created_objects()->Add(outcome.created.begin(), outcome.created.end());
  response->mutable_updated_objects()->Add(outcome.updated.begin(), outcome.updated.end());
  response->mutable_removed_objects()->Add(outcome.removed.begin(), outcome.removed.end());
}

bool PosesFromProto(const v1::UpdatePosesRequest& request,
                    std::map<KeyframeId, Eigen::Isometry3d>* poses, std::string* why) {
  for (int i = 0; i < request.poses_size(); ++i) {
    const v1::KeyframePose& entry = request.poses(i);
    const std::string field = "poses[" + std::to_string(i) + "]";
    Eigen::Isometry3d T_W_C;
    if (!PoseFromProto(entry.t_w_c(), field + ".T_W_C", &T_W_C, why)) return false;
    if (!poses->emplace(entry.keyframe_id(), T_W_C).second) {
      *why =
          field + ".keyframe_id " + std::to_string(entry.keyframe_id()) + " appears more than once";
      return false;
    }
  }
  return true;
}

// "keyframe 12 (frame-000120): " for the index-th request of a stream.
std::string StreamPrefix(int index, const v1::AddKeyframeRequest& request) {
  std::string prefix = "keyframe " + std::to_string(index);
  if (!request.name().empty()) prefix += " (" + request.name() + ")";
  return prefix + ": ";
}

}  // namespace

grpc::Status MapServiceImpl::AddOne(const v1::AddKeyframeRequest& request,
                                    AddKeyframeOutcome* outcome) {
  RgbdFrame frame;
  std::optional<std::vector<Detection>> detections;
  std::string why;
  if (!FrameFromRequest(request, &frame, &detections, &why)) return Invalid(why);
  return ToGrpcStatus(server_.AddKeyframe(std::move(frame), std::move(detections), outcome));
}

grpc::Status MapServiceImpl::AddKeyframe(grpc::ServerContext* /*context*/,
                                         const v1::AddKeyframeRequest* request,
                                         v1::AddKeyframeResponse* response) {
  return Guarded("AddKeyframe", [&] {
    AddKeyframeOutcome outcome;
    grpc::Status status = AddOne(*request, &outcome);
    if (status.ok()) OutcomeToProto(outcome, response);
    return status;
  });
}

grpc::Status MapServiceImpl::IngestKeyframes(grpc::ServerContext* /*context*/,
                                             grpc::ServerReader<v1::AddKeyframeRequest>* reader,
                                             v1::IngestSummary* summary) {
  return Guarded("IngestKeyframes", [&] {
    v1::AddKeyframeRequest request;
    int index = 0;
    int objects_created = 0;
    std::uint64_t map_version = server_.Snapshot()->version;
    while (reader->Read(&request)) {
      AddKeyframeOutcome outcome;
      const grpc::Status status = AddOne(request, &outcome);
      if (!status.ok()) {
        return grpc::Status(status.error_code(),
                            StreamPrefix(index, request) + status.error_message());
      }
      if (index == 0) summary->set_first_keyframe_id(outcome.keyframe_id);
      summary->set_last_keyframe_id(outcome.keyframe_id);
      objects_created += static_cast<int>(outcome.created.size());
      map_version = outcome.map_version;
      ++index;
    }
    summary->set_keyframes_added(index);
    summary->set_objects_created(objects_created);
    summary->set_map_version(map_version);
    return grpc::Status::OK;
  });
}

grpc::Status MapServiceImpl::UpdatePoses(grpc::ServerContext* /*context*/,
                                         const v1::UpdatePosesRequest* request,
                                         v1::UpdatePosesResponse* response) {
  return Guarded("UpdatePoses", [&] {
    std::map<KeyframeId, Eigen::Isometry3d> poses;
    std::string why;
    if (!PosesFromProto(*request, &poses, &why)) return Invalid(why);
    PoseUpdateOutcome outcome;
    const grpc::Status status = ToGrpcStatus(server_.UpdatePoses(poses, request->wait(), &outcome));
    if (!status.ok()) return status;
    response->set_map_version(outcome.map_version);
    response->set_regenerated(outcome.regenerated);
    response->set_keyframes_moved(outcome.keyframes_moved);
    response->set_reassociated(outcome.reassociated);
    response->set_objects_before(outcome.objects_before);
    response->set_objects_after(outcome.objects_after);
    response->set_regeneration_ms(outcome.regeneration_ms);
    return status;
  });
}

grpc::Status MapServiceImpl::Status(grpc::ServerContext* /*context*/,
                                    const v1::StatusRequest* /*request*/,
                                    v1::StatusResponse* response) {
  return Guarded("Status", [&] {
    const ServerStatus status = server_.Status();
    response->set_map_version(status.map_version);
    response->set_keyframes(static_cast<std::int64_t>(status.keyframes));
    response->set_objects(static_cast<std::int64_t>(status.objects));
    response->set_confirmed_objects(static_cast<std::int64_t>(status.confirmed_objects));
    response->set_ingest_queue(status.queue_length);
    response->set_regenerating(status.regenerating);
    response->set_last_regeneration_ms(status.last_regeneration_ms);
    response->set_last_regeneration_version(status.last_regeneration_version);
    response->set_database(status.database);
    response->set_database_bytes(status.database_bytes);
    response->set_uptime_s(status.uptime_s);
    response->set_checkpoint_version(status.checkpoint_version);
    response->set_last_checkpoint_ms(status.last_checkpoint_ms);
    response->set_startup_ms(status.startup_ms);
    response->set_startup_keyframes_integrated(status.startup_keyframes_integrated);
    return grpc::Status::OK;
  });
}

grpc::Status MapServiceImpl::WatchMap(grpc::ServerContext* context,
                                      const v1::WatchMapRequest* request,
                                      grpc::ServerWriter<v1::MapChange>* writer) {
  return Guarded("WatchMap", [&] {
    std::uint64_t last = request->since_version();
    // ChangesSince returns at least every kWatchPoll, so cancellation and shutdown are noticed.
    while (!context->IsCancelled()) {
      if (server_.shutting_down()) {
        return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the map server is shutting down");
      }
      for (const MapChange& change : server_.ChangesSince(last, kWatchPoll)) {
        v1::MapChange proto;
        MapChangeToProto(change, &proto);
        if (!writer->Write(proto)) {
          return grpc::Status(grpc::StatusCode::CANCELLED, "the client stopped reading");
        }
        last = std::max(last, change.version);
      }
    }
    return grpc::Status(grpc::StatusCode::CANCELLED, "the client cancelled the watch");
  });
}

}  // namespace objmap::grpc_service
