#pragma once
// Helpers shared by the client's source files; not installed.

#include <grpcpp/client_context.h>

#include <chrono>
#include <string>

namespace objmap::internal {

/// Adds the bearer token (when there is one) to a call's metadata.
inline void AddToken(const std::string& token, grpc::ClientContext* context) {
  if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
}

/// Sets a deadline `deadline_s` seconds from now; 0 or less leaves the call without one.
inline void SetDeadline(double deadline_s, grpc::ClientContext* context) {
  if (deadline_s <= 0.0) return;
  const auto duration = std::chrono::duration_cast<std::chrono::system_clock::duration>(
      std::chrono::duration<double>(deadline_s));
  context->set_deadline(std::chrono::system_clock::now() + duration);
}

}  // namespace objmap::internal
