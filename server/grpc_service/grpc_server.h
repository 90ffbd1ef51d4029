#pragma once
// Starting a gRPC server for MapServiceImpl: listen address, message size limit, TLS, bound
// port.

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace objmap::grpc_service {

struct GrpcServerOptions {
  /// host:port; port 0 picks a free port (see StartGrpcServer's `port`). Loopback by default.
  std::string listen_address = "127.0.0.1:50051";
  /// Largest request accepted, MiB; bigger ones are refused by gRPC with RESOURCE_EXHAUSTED.
  /// A 640x480 keyframe with PNG depth and JPEG colour takes about 0.5 MiB.
  int max_receive_message_mb = 64;
  /// TLS: the server's certificate chain and private key, PEM files (both or neither).
  std::string tls_cert_path;
  std::string tls_key_path;
  /// Mutual TLS: clients must present a certificate signed by this CA (PEM); needs TLS.
  std::string tls_client_ca_path;
  /// Bearer tokens (AccessTokens file); empty: calls need no token.
  std::string tokens_path;
  /// Serve an address other machines reach without TLS and tokens. Off: such an address is
  /// refused, since anyone reaching it could move every pose or plant objects.
  bool insecure = false;

  [[nodiscard]] bool tls() const { return !tls_cert_path.empty(); }
  /// True when the listen address serves other machines without TLS and tokens (allowed only
  /// with `insecure`).
  [[nodiscard]] bool ExposedWithoutProtection() const;
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// True for addresses only this machine reaches: 127.0.0.0/8, [::1], localhost.
[[nodiscard]] bool IsLoopbackAddress(const std::string& listen_address);

/// Builds and starts a server offering `service` (which must outlive it), with the standard
/// health service (grpc.health.v1.Health, SERVING while it runs) and server reflection, over TLS
/// when the
/// options give a certificate. Returns nullptr with a reason when the options are invalid, a
/// PEM file cannot be read or the address cannot be bound; `port` receives the bound port.
/// Tokens are the service's (MapServiceImpl::RequireTokens).
[[nodiscard]] std::unique_ptr<grpc::Server> StartGrpcServer(const GrpcServerOptions& options,
                                                            grpc::Service* service, int* port,
                                                            std::string* why);

/// `address` ("127.0.0.1:0", "[::1]:0", "localhost:0") with its port replaced by `port`.
[[nodiscard]] std::string AddressWithPort(const std::string& address, int port);

}  // namespace objmap::grpc_service
