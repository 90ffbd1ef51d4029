#pragma once
// Private to grpc_service: runs a handler body so that no exception reaches gRPC's threads, and
// keeps every status message short.

#include <grpcpp/support/status.h>

#include <cstddef>
#include <exception>
#include <string>

namespace objmap::grpc_service {

/// Status messages are cut to this many bytes: gRPC carries them in a header, and a client's
/// metadata limit (8 KiB by default) turns a longer one into RESOURCE_EXHAUSTED.
inline constexpr std::size_t kMaxStatusMessageBytes = 480;

/// User text quoted in a message (a keyframe name, a class name) is cut to this many bytes.
inline constexpr std::size_t kMaxQuotedBytes = 64;

/// `text` cut to at most `max_bytes` at a UTF-8 character boundary, with "... (N bytes)" added
/// when cut.
inline std::string Shortened(const std::string& text, std::size_t max_bytes) {
  if (text.size() <= max_bytes) return text;
  std::size_t end = max_bytes;
  // Continuation bytes are 10xxxxxx: step back to the first byte of the character cut through.
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0u) == 0x80u) --end;
  return text.substr(0, end) + "... (" + std::to_string(text.size()) + " bytes)";
}

/// `status` with its message cut to kMaxStatusMessageBytes.
inline grpc::Status Bounded(const grpc::Status& status) {
  if (status.error_message().size() <= kMaxStatusMessageBytes) return status;
  return {status.error_code(), Shortened(status.error_message(), kMaxStatusMessageBytes)};
}

/// The body's status (message bounded), or INTERNAL naming the RPC and the exception's what().
template <typename Body>
grpc::Status Guarded(const char* rpc, Body&& body) {
  try {
    return Bounded(body());
  } catch (const std::exception& e) {
    return Bounded({grpc::StatusCode::INTERNAL, std::string(rpc) + ": " + e.what()});
  } catch (...) {
    return {grpc::StatusCode::INTERNAL, std::string(rpc) + ": unknown exception"};
  }
}

/// INVALID_ARGUMENT with `message` (which names the field).
inline grpc::Status Invalid(std::string message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, std::move(message)};
}

}  // namespace objmap::grpc_service
