// The write side of MapServiceImpl (AddKeyframe, IngestKeyframes, UpdatePoses) with Status and
// WatchMap; the queries are in map_service_queries.cc.
#include "grpc_service/map_service.h"

#include <google/protobuf/descriptor.h>
#include <grpcpp/support/proto_buffer_reader.h>

#include <algorithm>
#include <stdexcept>

#include "grpc_service/conversions.h"
#include "grpc_service/handler_guard.h"
#include "grpc_service/keyframe_conversions.h"

namespace objmap::grpc_service {
namespace {

const google::protobuf::ServiceDescriptor& MapServiceDescriptor() {
  const google::protobuf::ServiceDescriptor* service =
      google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(
          v1::MapService::service_full_name());
  if (service == nullptr) throw std::logic_error("objmap.proto's MapService is not linked in");
  return *service;
}

// "name, detections.class_name": the text fields of a message and of the messages in it, which
// protobuf refuses to decode when they are not UTF-8.
void AppendStringFields(const google::protobuf::Descriptor& message, const std::string& prefix,
                        int depth, std::string* names) {
  for (int i = 0; i < message.field_count(); ++i) {
    const google::protobuf::FieldDescriptor& field = *message.field(i);
    if (field.type() == google::protobuf::FieldDescriptor::TYPE_STRING) {
      *names += (names->empty() ? "" : ", ") + prefix + field.name();
    } else if (field.message_type() != nullptr && depth < 2) {
      AppendStringFields(*field.message_type(), prefix + field.name() + ".", depth + 1, names);
    }
  }
}

// Decodes a request received as bytes. A message protobuf refuses (not a message of this type,
// or a text field that is not UTF-8, e.g. a Latin-1 file name) is the client's error.
template <typename Message>
grpc::Status DecodeRequest(const grpc::ByteBuffer& bytes, Message* message) {
  grpc::ByteBuffer buffer(bytes);  // shares the slices; the reader needs a mutable buffer
  grpc::ProtoBufferReader reader(&buffer);
  if (reader.status().ok() && message->ParseFromZeroCopyStream(&reader)) return grpc::Status::OK;
  const google::protobuf::Descriptor& type = *Message::descriptor();
  std::string text_fields;
  AppendStringFields(type, "", 0, &text_fields);
  return Invalid(
      "cannot decode the " + type.name() + " (" + std::to_string(bytes.Length()) +
      " bytes): not a " + type.full_name() + " message" +
      (text_fields.empty() ? std::string() : ", or a text field (" + text_fields + ") not UTF-8"));
}

void OutcomeToProto(const AddKeyframeOutcome& outcome, v1::AddKeyframeResponse* response) {
  response->set_keyframe_id(outcome.keyframe_id);
  response->set_map_version(outcome.map_version);
  response->set_detections_used(outcome.detections_used);
  *response->mutable_t_w_c() = PoseToProto(outcome.T_W_C);
  response->set_loops_closed(outcome.loops_closed);
  response->set_relocalized(outcome.relocalized);
  response->set_session_id(outcome.session_id);
  for (const KeyframeId id : outcome.attached) response->add_attached_keyframe_ids(id);
  response->set_repeated_keyframe_id(outcome.repeated_keyframe);
  response->set_explained_fraction(outcome.explained_fraction);
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
std::string StreamPrefix(int index, const v1::AddKeyframeRequest* request) {
  std::string prefix = "keyframe " + std::to_string(index);
  if (request != nullptr && !request->name().empty()) {
    prefix += " (" + Shortened(request->name(), kMaxQuotedBytes) + ")";
  }
  return prefix + ": ";
}

}  // namespace

MapServiceImpl::MapServiceImpl(MapServer& server) : server_(server) { RegisterMethods(); }

void MapServiceImpl::RequireTokens(AccessTokens tokens) { tokens_ = std::move(tokens); }

grpc::Status MapServiceImpl::Authorize(const grpc::ServerContext& context, const char* method,
                                       bool writes) const {
  if (!tokens_) return grpc::Status::OK;
  const auto& metadata = context.client_metadata();
  const auto header = metadata.find("authorization");
  const std::string_view token =
      header == metadata.end()
          ? std::string_view()
          : BearerToken(std::string_view(header->second.data(), header->second.size()));
  const Access access = token.empty() ? Access::kNone : tokens_->Find(token);
  if (access == Access::kNone) {
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                        token.empty() ? "this server needs a bearer token (metadata "
                                        "'authorization: Bearer TOKEN')"
                                      : "unknown bearer token");
  }
  if (writes && access != Access::kReadWrite) {
    return grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                        std::string(method) +
                            " changes the map and needs a read-write token; this one is read-only");
  }
  return grpc::Status::OK;
}

const char* MapServiceImpl::MethodPath(const char* method) {
  if (MapServiceDescriptor().FindMethodByName(method) == nullptr) {
    throw std::logic_error(std::string("objmap.proto's MapService has no method ") + method);
  }
  method_paths_.push_back("/" + std::string(v1::MapService::service_full_name()) + "/" + method);
  return method_paths_.back().c_str();
}

template <typename Request, typename Response>
void MapServiceImpl::AddUnary(const char* method, bool writes,
                              grpc::Status (MapServiceImpl::*handler)(grpc::ServerContext*,
                                                                      const Request*, Response*)) {
  using Handler = grpc::internal::RpcMethodHandler<MapServiceImpl, grpc::ByteBuffer, Response,
                                                   grpc::ByteBuffer, grpc::protobuf::MessageLite>;
  AddMethod(new grpc::internal::RpcServiceMethod(
      MethodPath(method), grpc::internal::RpcMethod::NORMAL_RPC,
      new Handler(
          [handler, method, writes](MapServiceImpl* service, grpc::ServerContext* context,
                                    const grpc::ByteBuffer* bytes, Response* response) {
            const grpc::Status allowed = service->Authorize(*context, method, writes);
            if (!allowed.ok()) return allowed;
            Request request;
            const grpc::Status decoded = Bounded(DecodeRequest(*bytes, &request));
            if (!decoded.ok()) return decoded;
            return (service->*handler)(context, &request, response);
          },
          this)));
}

void MapServiceImpl::RegisterMethods() {
  // In objmap.proto's order; the count is checked against the proto below.
  AddUnary("AddKeyframe", true, &MapServiceImpl::AddKeyframe);
  AddMethod(new grpc::internal::RpcServiceMethod(
      MethodPath("IngestKeyframes"), grpc::internal::RpcMethod::CLIENT_STREAMING,
      new grpc::internal::ClientStreamingHandler<MapServiceImpl, grpc::ByteBuffer,
                                                 v1::IngestSummary>(
          [](MapServiceImpl* service, grpc::ServerContext* context,
             grpc::ServerReader<grpc::ByteBuffer>* reader, v1::IngestSummary* summary) {
            const grpc::Status allowed = service->Authorize(*context, "IngestKeyframes", true);
            if (!allowed.ok()) return allowed;
            return service->IngestKeyframes(context, reader, summary);
          },
          this)));
  AddUnary("UpdatePoses", true, &MapServiceImpl::UpdatePoses);
  AddUnary("ListKeyframes", false, &MapServiceImpl::ListKeyframes);
  AddUnary("StartSession", true, &MapServiceImpl::StartSession);
  AddUnary("ListSessions", false, &MapServiceImpl::ListSessions);
  AddUnary("QueryObjects", false, &MapServiceImpl::QueryObjects);
  AddUnary("GetObject", false, &MapServiceImpl::GetObject);
  AddUnary("ListChanges", false, &MapServiceImpl::ListChanges);
  AddUnary("Inventory", false, &MapServiceImpl::Inventory);
  AddUnary("QueryOccupancy", false, &MapServiceImpl::QueryOccupancy);
  AddUnary("IsFree", false, &MapServiceImpl::IsFree);
  AddUnary("RayCast", false, &MapServiceImpl::RayCast);
  AddUnary("GetOctomap", false, &MapServiceImpl::GetOctomap);
  AddUnary("Status", false, &MapServiceImpl::Status);
  AddMethod(new grpc::internal::RpcServiceMethod(
      MethodPath("WatchMap"), grpc::internal::RpcMethod::SERVER_STREAMING,
      new grpc::internal::ServerStreamingHandler<MapServiceImpl, grpc::ByteBuffer, v1::MapChange>(
          [](MapServiceImpl* service, grpc::ServerContext* context, const grpc::ByteBuffer* bytes,
             grpc::ServerWriter<v1::MapChange>* writer) {
            const grpc::Status allowed = service->Authorize(*context, "WatchMap", false);
            if (!allowed.ok()) return allowed;
            v1::WatchMapRequest request;
            const grpc::Status decoded = Bounded(DecodeRequest(*bytes, &request));
            if (!decoded.ok()) return decoded;
            return service->WatchMap(context, &request, writer);
          },
          this)));
  if (static_cast<int>(method_paths_.size()) != MapServiceDescriptor().method_count()) {
    throw std::logic_error(
        "objmap.proto's MapService has " + std::to_string(MapServiceDescriptor().method_count()) +
        " methods but the service registers " + std::to_string(method_paths_.size()));
  }
}

grpc::Status MapServiceImpl::AddOne(const v1::AddKeyframeRequest& request,
                                    AddKeyframeOutcome* outcome) {
  RgbdFrame frame;
  std::optional<std::vector<Detection>> detections;
  std::string why;
  grpc::StatusCode code = grpc::StatusCode::INVALID_ARGUMENT;
  if (!FrameFromRequest(request, server_.limits(), server_.estimates_poses(), &frame, &detections,
                        &code, &why)) {
    return {code, why};
  }
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
                                             grpc::ServerReaderInterface<grpc::ByteBuffer>* reader,
                                             v1::IngestSummary* summary) {
  return Guarded("IngestKeyframes", [&] {
    grpc::ByteBuffer bytes;
    // The reasons kept for the untracked keyframes skipped: enough to see a pattern.
    constexpr int kMaxUntrackedReasons = 100;
    int index = 0;  // of the message in the stream
    int added = 0;
    int untracked = 0, held = 0, attached = 0, repeated = 0, repeated_in_part = 0;
    int objects_created = 0;
    std::uint64_t map_version = server_.Snapshot()->version;
    for (; reader->Read(&bytes); ++index) {
      v1::AddKeyframeRequest request;
      const grpc::Status decoded = DecodeRequest(bytes, &request);
      if (!decoded.ok()) {
        return grpc::Status(decoded.error_code(),
                            StreamPrefix(index, nullptr) + decoded.error_message());
      }
      AddKeyframeOutcome outcome;
      const grpc::Status status = AddOne(request, &outcome);
      // A keyframe the server cannot place is skipped: a camera's stream goes on past a blank
      // wall or a fast turn, and the next keyframe is placed by relocalisation.
      if (!status.ok() && outcome.untracked) {
        held += outcome.held;
        if (++untracked <= kMaxUntrackedReasons) {
          summary->add_untracked(StreamPrefix(index, &request) + status.error_message());
        }
        continue;
      }
      if (!status.ok()) {
        return grpc::Status(status.error_code(),
                            StreamPrefix(index, &request) + status.error_message());
      }
      // Held keyframes this one's placement mapped came before it; a keyframe kept as a revisit
      // only (keyframe_id 0) is none of the map's.
      const bool is_revisit = outcome.keyframe_id == 0;
      repeated += is_revisit;
      repeated_in_part += !is_revisit && outcome.repeated_keyframe != 0;
      const int mapped = static_cast<int>(outcome.attached.size()) + (is_revisit ? 0 : 1);
      if (mapped > 0) {
        const KeyframeId first_id =
            outcome.attached.empty() ? outcome.keyframe_id : outcome.attached.front();
        if (added == 0) summary->set_first_keyframe_id(first_id);
        summary->set_last_keyframe_id(is_revisit ? outcome.attached.back() : outcome.keyframe_id);
      }
      objects_created += static_cast<int>(outcome.created.size());
      map_version = outcome.map_version;
      attached += static_cast<int>(outcome.attached.size());
      added += mapped;
    }
    summary->set_keyframes_untracked(untracked);
    summary->set_keyframes_held(held);
    summary->set_keyframes_attached(attached);
    summary->set_keyframes_repeated(repeated);
    summary->set_keyframes_repeated_in_part(repeated_in_part);
    summary->set_keyframes_added(added);
    summary->set_objects_created(objects_created);
    summary->set_map_version(map_version);
    return grpc::Status::OK;
  });
}

grpc::Status MapServiceImpl::UpdatePoses(grpc::ServerContext* /*context*/,
                                         const v1::UpdatePosesRequest* request,
                                         v1::UpdatePosesResponse* response) {
  return Guarded("UpdatePoses", [&] {
    if (request->poses_size() > server_.limits().max_poses_per_update) {
      return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                          "poses has " + std::to_string(request->poses_size()) +
                              " entries; the server takes at most " +
                              std::to_string(server_.limits().max_poses_per_update) +
                              " (server.max_poses_per_update)");
    }
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
    response->set_occupancy_bytes(status.occupancy_bytes);
    response->set_occupancy_copies(status.occupancy_copies);
    response->set_session_id(status.session_id);
    response->set_session_name(status.session_name);
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
