#include "grpc_service/grpc_server.h"

namespace objmap::grpc_service {

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
  return true;
}

std::unique_ptr<grpc::Server> StartGrpcServer(const GrpcServerOptions& options,
                                              grpc::Service* service, int* port, std::string* why) {
  if (!options.IsValid(why)) return nullptr;
  grpc::ServerBuilder builder;
  *port = 0;
  builder.AddListeningPort(options.listen_address, grpc::InsecureServerCredentials(), port);
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
