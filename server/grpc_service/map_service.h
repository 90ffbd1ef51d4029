#pragma once
// The gRPC face of MapServer: each handler converts the request, calls MapServer and converts
// the answer back. No mapping logic lives here.

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "grpc_service/access_tokens.h"
#include "map_server/map_server.h"
#include "objmap.grpc.pb.h"

namespace objmap::grpc_service {

/// The service registers every method of objmap.proto's MapService itself, with requests
/// received as bytes and decoded here: gRPC's own decoding would answer a request it cannot
/// parse (a name that is not UTF-8, garbage bytes) with INTERNAL and an empty message, and would
/// end an IngestKeyframes stream as if the client had finished it. Here such a request gets
/// INVALID_ARGUMENT naming the request type and its string fields, and a stream ends with it.
///
/// Thread-safety: handlers run concurrently on gRPC's threads; MapServer is thread-safe and the
/// service keeps no state of its own. No exception leaves a handler (INTERNAL instead). Every
/// status message is at most kMaxStatusMessageBytes long.
class MapServiceImpl final : public grpc::Service {
 public:
  /// `server` must outlive the service (and the grpc::Server it is registered with). Requests
  /// are held to server.limits().
  explicit MapServiceImpl(MapServer& server);

  /// From now on every call needs `authorization: Bearer TOKEN` metadata with one of `tokens`
  /// (UNAUTHENTICATED otherwise), and the calls that change the map (AddKeyframe,
  /// IngestKeyframes, UpdatePoses) a read-write one (PERMISSION_DENIED). Call before serving.
  void RequireTokens(AccessTokens tokens);

  grpc::Status AddKeyframe(grpc::ServerContext* context, const v1::AddKeyframeRequest* request,
                           v1::AddKeyframeResponse* response);
  /// Adds the streamed keyframes in order; the first failure (a message that does not decode
  /// included) ends the call with its status, prefixed "keyframe <index in the stream>: ".
  /// Keyframes before it stay stored.
  grpc::Status IngestKeyframes(grpc::ServerContext* context,
                               grpc::ServerReaderInterface<grpc::ByteBuffer>* reader,
                               v1::IngestSummary* summary);
  grpc::Status UpdatePoses(grpc::ServerContext* context, const v1::UpdatePosesRequest* request,
                           v1::UpdatePosesResponse* response);
  grpc::Status ListKeyframes(grpc::ServerContext* context, const v1::ListKeyframesRequest* request,
                             v1::ListKeyframesResponse* response);
  grpc::Status StartSession(grpc::ServerContext* context, const v1::StartSessionRequest* request,
                            v1::Session* response);
  grpc::Status ListSessions(grpc::ServerContext* context, const v1::ListSessionsRequest* request,
                            v1::ListSessionsResponse* response);

  grpc::Status QueryObjects(grpc::ServerContext* context, const v1::QueryObjectsRequest* request,
                            v1::QueryObjectsResponse* response);
  grpc::Status GetObject(grpc::ServerContext* context, const v1::GetObjectRequest* request,
                         v1::Object* response);
  grpc::Status ListChanges(grpc::ServerContext* context, const v1::ListChangesRequest* request,
                           v1::ListChangesResponse* response);
  grpc::Status Inventory(grpc::ServerContext* context, const v1::InventoryRequest* request,
                         v1::InventoryResponse* response);

  grpc::Status QueryOccupancy(grpc::ServerContext* context,
                              const v1::QueryOccupancyRequest* request,
                              v1::QueryOccupancyResponse* response);
  grpc::Status IsFree(grpc::ServerContext* context, const v1::IsFreeRequest* request,
                      v1::IsFreeResponse* response);
  grpc::Status RayCast(grpc::ServerContext* context, const v1::RayCastRequest* request,
                       v1::RayCastResponse* response);
  grpc::Status GetOctomap(grpc::ServerContext* context, const v1::GetOctomapRequest* request,
                          v1::GetOctomapResponse* response);

  grpc::Status Status(grpc::ServerContext* context, const v1::StatusRequest* request,
                      v1::StatusResponse* response);
  /// Streams changes after since_version until the client cancels or the server shuts down
  /// (then UNAVAILABLE, so that clients know to reconnect).
  grpc::Status WatchMap(grpc::ServerContext* context, const v1::WatchMapRequest* request,
                        grpc::ServerWriter<v1::MapChange>* writer);

  /// How long WatchMap waits for changes before it looks at cancellation and shutdown again.
  static constexpr std::chrono::milliseconds kWatchPoll{500};

 private:
  grpc::Status AddOne(const v1::AddKeyframeRequest& request, AddKeyframeOutcome* outcome);

  /// Registers `method` of MapService (its name in objmap.proto) for requests received as bytes;
  /// `writes`: it changes the map.
  template <typename Request, typename Response>
  void AddUnary(const char* method, bool writes,
                grpc::Status (MapServiceImpl::*handler)(grpc::ServerContext*, const Request*,
                                                        Response*));
  /// OK when the call's token allows `method` (see RequireTokens), checked before the request
  /// is decoded.
  [[nodiscard]] grpc::Status Authorize(const grpc::ServerContext& context, const char* method,
                                       bool writes) const;
  void RegisterMethods();
  /// The method's full path, kept for the life of the service (gRPC keeps the pointer).
  const char* MethodPath(const char* method);

  MapServer& server_;
  std::optional<AccessTokens> tokens_;    ///< none: no authentication (loopback)
  std::deque<std::string> method_paths_;  ///< stable addresses: gRPC keeps the char pointers
};

}  // namespace objmap::grpc_service
