#pragma once
// Starting a gRPC server for MapServiceImpl: listen address, message size limit, bound port.

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace objmap::grpc_service {

struct GrpcServerOptions {
  /// host:port; port 0 picks a free port (see StartGrpcServer's `port`). Loopback by default:
  /// the service has no authentication.
  std::string listen_address = "127.0.0.1:50051";
  /// Largest request accepted, MiB; bigger ones are refused by gRPC with RESOURCE_EXHAUSTED.
  /// A 640x480 keyframe with PNG depth and JPEG colour takes about 0.5 MiB.
  int max_receive_message_mb = 64;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Builds and starts a server offering `service` (which must outlive it). Returns nullptr with a
/// reason when the options are invalid or the address cannot be bound; `port` receives the
/// bound port.
[[nodiscard]] std::unique_ptr<grpc::Server> StartGrpcServer(const GrpcServerOptions& options,
                                                            grpc::Service* service, int* port,
                                                            std::string* why);

/// `address` ("127.0.0.1:0", "[::1]:0", "localhost:0") with its port replaced by `port`.
[[nodiscard]] std::string AddressWithPort(const std::string& address, int port);

}  // namespace objmap::grpc_service
