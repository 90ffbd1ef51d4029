#include "grpc_service/grpc_server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

#include "pem_file.h"

namespace objmap::grpc_service {
namespace {

std::string HostOf(const std::string& address) {
  if (!address.empty() && address[0] == '[') return address.substr(0, address.find(']') + 1);
  return address.substr(0, address.rfind(':'));
}

}  // namespace

bool IsLoopbackAddress(const std::string& listen_address) {
  const std::string host = HostOf(listen_address);
  return host == "localhost" || host == "[::1]" || host.rfind("127.", 0) == 0;
}

bool GrpcServerOptions::ExposedWithoutProtection() const {
  return !IsLoopbackAddress(listen_address) && !(tls() && !tokens_path.empty());
}

bool GrpcServerOptions::IsValid(std::string* why) const {
  if (listen_address.empty() || listen_address.find(':') == std::string::npos) {
    *why = "listen address '" + listen_address + "' must be host:port";
    return false;
  }
  // gRPC takes the limit as an int number of bytes.
  if (max_receive_message_mb <= 0 || max_receive_message_mb > 2047) {
    *why =
        "max message size " + std::to_string(max_receive_message_mb) + " MiB must lie in 1..2047";
    return false;
  }
  if (tls_cert_path.empty() != tls_key_path.empty()) {
    *why = "TLS needs both a certificate and its key (--tls-cert and --tls-key)";
    return false;
  }
  if (!tls_client_ca_path.empty() && !tls()) {
    *why = "client certificates (--tls-client-ca) need TLS (--tls-cert and --tls-key)";
    return false;
  }
  if (ExposedWithoutProtection() && !insecure) {
    *why = "listen address " + listen_address +
           " reaches other machines: serve it with TLS and tokens (--tls-cert, --tls-key, "
           "--tokens), or give --insecure to serve it without";
    return false;
  }
  return true;
}

std::unique_ptr<grpc::Server> StartGrpcServer(const GrpcServerOptions& options,
                                              grpc::Service* service, int* port, std::string* why) {
  if (!options.IsValid(why)) return nullptr;
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (options.tls()) {
    grpc::SslServerCredentialsOptions tls;
    grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
    if (!ReadPemFile(options.tls_cert_path, "server certificate", &pair.cert_chain, why) ||
        !ReadPemFile(options.tls_key_path, "server key", &pair.private_key, why)) {
      return nullptr;
    }
    tls.pem_key_cert_pairs.push_back(std::move(pair));
    if (!options.tls_client_ca_path.empty()) {
      if (!ReadPemFile(options.tls_client_ca_path, "client CA certificate", &tls.pem_root_certs,
                   why)) {
        return nullptr;
      }
      tls.client_certificate_request =
          GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
    }
    credentials = grpc::SslServerCredentials(tls);
  }
  // The standard health service (grpc.health.v1: grpc_health_probe, load balancers) and server
  // reflection (grpcurl, grpc_cli) come with every server; both are set before the builder.
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  *port = 0;
  builder.AddListeningPort(options.listen_address, credentials, port);
  builder.SetMaxReceiveMessageSize(options.max_receive_message_mb * 1024 * 1024);
  // gRPC sets SO_REUSEPORT by default: a second server on a busy port would then start and share
  // its connections with the first (each with its own database) instead of failing.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.RegisterService(service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  // The selected port is only filled in by BuildAndStart; 0 means binding failed.
  if (!server || *port == 0) {
    *why = "cannot listen on " + options.listen_address +
           " (address in use, or not an address of this machine?)";
    if (server) server->Shutdown();
    return nullptr;
  }
  return server;
}

std::string AddressWithPort(const std::string& address, int port) {
  const std::size_t colon = address.rfind(':');
  // "[::1]" without a port: the colon found is inside the brackets.
  if (colon == std::string::npos || address.find(']', colon) != std::string::npos) {
    return address + ":" + std::to_string(port);
  }
  return address.substr(0, colon + 1) + std::to_string(port);
}

}  // namespace objmap::grpc_service
