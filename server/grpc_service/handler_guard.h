#pragma once
// Private to grpc_service: runs a handler body so that no exception reaches gRPC's threads.

#include <grpcpp/support/status.h>

#include <exception>
#include <string>

namespace objmap::grpc_service {

/// The body's status, or INTERNAL naming the RPC and the exception's what().
template <typename Body>
grpc::Status Guarded(const char* rpc, Body&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, std::string(rpc) + ": " + e.what()};
  } catch (...) {
    return {grpc::StatusCode::INTERNAL, std::string(rpc) + ": unknown exception"};
  }
}

/// INVALID_ARGUMENT with `message` (which names the field).
inline grpc::Status Invalid(std::string message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, std::move(message)};
}

}  // namespace objmap::grpc_service
