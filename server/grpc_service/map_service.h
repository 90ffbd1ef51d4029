#pragma once
// The gRPC face of MapServer: each handler converts the request, calls MapServer and converts
// the answer back. No mapping logic lives here.

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "map_server/map_server.h"
#include "objmap.grpc.pb.h"

namespace objmap::grpc_service {

/// Thread-safety: handlers run concurrently on gRPC's threads; MapServer is thread-safe and the
/// service keeps no state of its own. No exception leaves a handler (INTERNAL instead).
class MapServiceImpl final : public v1::MapService::Service {
 public:
  /// `server` must outlive the service (and the grpc::Server it is registered with).
  explicit MapServiceImpl(MapServer& server) : server_(server) {}

  grpc::Status AddKeyframe(grpc::ServerContext* context, const v1::AddKeyframeRequest* request,
                           v1::AddKeyframeResponse* response) override;
  /// Adds the streamed keyframes in order; the first failure ends the call with its status,
  /// prefixed "keyframe <index in the stream>: ". Keyframes before it stay stored.
  grpc::Status IngestKeyframes(grpc::ServerContext* context,
                               grpc::ServerReader<v1::AddKeyframeRequest>* reader,
                               v1::IngestSummary* summary) override;
  grpc::Status UpdatePoses(grpc::ServerContext* context, const v1::UpdatePosesRequest* request,
                           v1::UpdatePosesResponse* response) override;
  grpc::Status ListKeyframes(grpc::ServerContext* context,
                             const v1::ListKeyframesRequest* request,
                             v1::ListKeyframesResponse* response) override;

  grpc::Status QueryObjects(grpc::ServerContext* context, const v1::QueryObjectsRequest* request,
                            v1::QueryObjectsResponse* response) override;
  grpc::Status GetObject(grpc::ServerContext* context, const v1::GetObjectRequest* request,
                         v1::Object* response) override;
  grpc::Status Inventory(grpc::ServerContext* context, const v1::InventoryRequest* request,
                         v1::InventoryResponse* response) override;

  grpc::Status QueryOccupancy(grpc::ServerContext* context,
                              const v1::QueryOccupancyRequest* request,
                              v1::QueryOccupancyResponse* response) override;
  grpc::Status IsFree(grpc::ServerContext* context, const v1::IsFreeRequest* request,
                      v1::IsFreeResponse* response) override;
  grpc::Status RayCast(grpc::ServerContext* context, const v1::RayCastRequest* request,
                       v1::RayCastResponse* response) override;
  grpc::Status GetOctomap(grpc::ServerContext* context, const v1::GetOctomapRequest* request,
                          v1::GetOctomapResponse* response) override;

  grpc::Status Status(grpc::ServerContext* context, const v1::StatusRequest* request,
                      v1::StatusResponse* response) override;
  /// Streams changes after since_version until the client cancels or the server shuts down
  /// (then UNAVAILABLE, so that clients know to reconnect).
  grpc::Status WatchMap(grpc::ServerContext* context, const v1::WatchMapRequest* request,
                        grpc::ServerWriter<v1::MapChange>* writer) override;

  /// How long WatchMap waits for changes before it looks at cancellation and shutdown again.
  static constexpr std::chrono::milliseconds kWatchPoll{500};

 private:
  grpc::Status AddOne(const v1::AddKeyframeRequest& request, AddKeyframeOutcome* outcome);

  MapServer& server_;
};

}  // namespace objmap::grpc_service
