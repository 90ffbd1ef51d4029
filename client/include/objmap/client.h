#pragma once
// The C++ client of objmap's MapService (proto_srv/objmap.proto).
//
//   objmap::MapClient client("127.0.0.1:50051");
//   objmap::v1::QueryObjectsRequest request;
//   request.set_class_name("cup");
//   objmap::v1::QueryObjectsResponse response;
//   const grpc::Status status = client.QueryObjects(request, &response);
//   if (!status.ok()) std::cerr << objmap::DescribeStatus(status) << "\n";
//
// Every call returns the grpc::Status of the RPC; the server answers INVALID_ARGUMENT and
// NOT_FOUND with a message naming the field (docs/api.md lists the codes of each RPC).

#include <chrono>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "objmap.grpc.pb.h"
#include "objmap/keyframe_request.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// Settings of a MapClient.
struct MapClientOptions {
  /// Deadline of each unary call, seconds; 0 means none.
  double deadline_s = 30.0;
  /// Deadline of a whole IngestKeyframes stream, seconds; 0 (default) means none, since a bulk
  /// ingest of a long sequence may take hours.
  double ingest_deadline_s = 0.0;
  /// Largest message sent or received, bytes (the server's default limit is the same).
  int max_message_bytes = 64 * 1024 * 1024;
  /// How AddKeyframe(RgbdFrame) and the ingest writer encode frames.
  KeyframeEncoding encoding;
  /// TLS: verify the server's certificate against this CA certificate (PEM file); empty: a
  /// plain connection.
  std::string tls_ca_path;
  /// Mutual TLS: this client's certificate chain and key (PEM files), for a server that asks
  /// for one (both or neither; they need tls_ca_path).
  std::string tls_cert_path;
  std::string tls_key_path;
  /// Bearer token sent with every call (metadata `authorization: Bearer TOKEN`); empty: none.
  /// Read it from a file (ReadTokenFile), not from the command line.
  std::string token;

  /// False with the offending field named when a value is out of range.
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The token in `path`: its first line that is neither empty nor a # comment, trimmed. False
/// with a reason naming the file otherwise.
[[nodiscard]] bool ReadTokenFile(const std::string& path, std::string* token, std::string* why);

class IngestWriter;

/// A connection to one objmap server. Thread-safety: every method may be called from several
/// threads at once (gRPC channels and stubs are thread-safe); an IngestWriter may not.
/// A client built with invalid options answers every call with INVALID_ARGUMENT naming the field.
class MapClient {
 public:
  /// `address` is "host:port" ("127.0.0.1:50051"); the connection is made lazily, by the first
  /// call or by WaitForServer().
  explicit MapClient(const std::string& address, const MapClientOptions& options = {});
  ~MapClient();
  MapClient(const MapClient&) = delete;
  MapClient& operator=(const MapClient&) = delete;

  /// Connects and waits until the channel is ready; false when `timeout` passes first.
  [[nodiscard]] bool WaitForServer(std::chrono::milliseconds timeout);

  [[nodiscard]] const std::string& address() const { return address_; }
  [[nodiscard]] const MapClientOptions& options() const { return options_; }

  // One method per RPC: the request as the proto has it, the response filled on success.
  grpc::Status AddKeyframe(const v1::AddKeyframeRequest& request,
                           v1::AddKeyframeResponse* response);
  grpc::Status UpdatePoses(const v1::UpdatePosesRequest& request,
                           v1::UpdatePosesResponse* response);
  grpc::Status ListKeyframes(const v1::ListKeyframesRequest& request,
                             v1::ListKeyframesResponse* response);
  grpc::Status StartSession(const v1::StartSessionRequest& request, v1::Session* response);
  grpc::Status ListSessions(const v1::ListSessionsRequest& request,
                            v1::ListSessionsResponse* response);
  grpc::Status QueryObjects(const v1::QueryObjectsRequest& request,
                            v1::QueryObjectsResponse* response);
  grpc::Status GetObject(const v1::GetObjectRequest& request, v1::Object* response);
  grpc::Status ListChanges(const v1::ListChangesRequest& request,
                           v1::ListChangesResponse* response);
  grpc::Status Inventory(const v1::InventoryRequest& request, v1::InventoryResponse* response);
  grpc::Status QueryOccupancy(const v1::QueryOccupancyRequest& request,
                              v1::QueryOccupancyResponse* response);
  grpc::Status IsFree(const v1::IsFreeRequest& request, v1::IsFreeResponse* response);
  grpc::Status RayCast(const v1::RayCastRequest& request, v1::RayCastResponse* response);
  grpc::Status GetOctomap(const v1::GetOctomapRequest& request, v1::GetOctomapResponse* response);
  grpc::Status Status(const v1::StatusRequest& request, v1::StatusResponse* response);

  /// Encodes the frame (colour as PNG or JPEG per options().encoding, depth as a 16-bit PNG in
  /// millimetres) and adds it. `detections` null: the server runs its own detector; non-null
  /// (even empty): these detections are used instead. An encoding failure is INVALID_ARGUMENT.
  grpc::Status AddKeyframe(const RgbdFrame& frame, const std::vector<Detection>* detections,
                           v1::AddKeyframeResponse* response);

  /// Opens a client stream for bulk ingest (IngestKeyframes); nullptr never.
  [[nodiscard]] std::unique_ptr<IngestWriter> StartIngest();

  /// Opens the WatchMap server stream. `context` must outlive the reader; cancel the stream with
  /// context->TryCancel() from another thread. No deadline is set (the stream is long-lived)
  /// unless the caller sets one on `context`.
  [[nodiscard]] std::unique_ptr<grpc::ClientReader<v1::MapChange>> WatchMap(
      const v1::WatchMapRequest& request, grpc::ClientContext* context);

 private:
  using Stub = v1::MapService::Stub;
  template <typename Request, typename Response>
  using UnaryMethod = grpc::Status (Stub::*)(grpc::ClientContext*, const Request&, Response*);

  // One body for every unary RPC: the options check, a fresh context with the deadline, the call.
  template <typename Request, typename Response>
  grpc::Status Call(UnaryMethod<Request, Response> method, const Request& request,
                    Response* response);
  [[nodiscard]] grpc::Status OptionsStatus() const;

  std::string address_;
  MapClientOptions options_;
  std::string options_error_;  // empty when options_ are valid
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<Stub> stub_;
};

/// Bulk ingest over one IngestKeyframes stream: keyframes are sent in order and the server
/// acknowledges all of them at once in Finish(). Thread-safety: none; use from one thread.
class IngestWriter {
 public:
  ~IngestWriter();
  IngestWriter(const IngestWriter&) = delete;
  IngestWriter& operator=(const IngestWriter&) = delete;

  /// Encodes and sends one keyframe (`detections` as in MapClient::AddKeyframe). A frame that
  /// cannot be encoded answers INVALID_ARGUMENT and the stream stays usable. When the stream is
  /// broken (the server rejected a keyframe, the connection dropped) the stream is finished and
  /// the server's status is returned; Finish() returns the same.
  grpc::Status Write(const RgbdFrame& frame, const std::vector<Detection>* detections);
  /// Sends a request as is.
  grpc::Status Write(const v1::AddKeyframeRequest& request);

  /// Closes the stream and waits for the summary; every keyframe written is durable on OK.
  grpc::Status Finish(v1::IngestSummary* summary);

  /// Keyframes written successfully so far (not yet acknowledged before Finish()).
  [[nodiscard]] int written() const { return written_; }

 private:
  friend class MapClient;
  IngestWriter(v1::MapService::Stub* stub, const MapClientOptions& options,
               const std::string& options_error);
  grpc::Status FinishStream();

  MapClientOptions options_;
  grpc::ClientContext context_;
  v1::IngestSummary summary_;
  std::unique_ptr<grpc::ClientWriter<v1::AddKeyframeRequest>> writer_;
  bool finished_ = false;
  grpc::Status final_status_;
  int written_ = 0;
};

/// "INVALID_ARGUMENT", "NOT_FOUND", ... for a gRPC status code.
[[nodiscard]] std::string_view StatusCodeName(grpc::StatusCode code);

/// "INVALID_ARGUMENT: color: ..." (the code name and the message) for printing.
[[nodiscard]] std::string DescribeStatus(const grpc::Status& status);

}  // namespace objmap
