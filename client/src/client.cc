#include "objmap/client.h"

#include <grpcpp/grpcpp.h>

#include <cmath>
#include <fstream>

#include "client_internal.h"
#include "pem_file.h"

namespace objmap {
namespace {

// Plain, or TLS verified against the options' CA (with the client's certificate for mutual TLS).
bool MakeCredentials(const MapClientOptions& options,
                     std::shared_ptr<grpc::ChannelCredentials>* credentials, std::string* why) {
  if (options.tls_ca_path.empty()) {
    *credentials = grpc::InsecureChannelCredentials();
    return true;
  }
  grpc::SslCredentialsOptions tls;
  if (!ReadPemFile(options.tls_ca_path, "CA certificate", &tls.pem_root_certs, why)) return false;
  if (!options.tls_cert_path.empty() &&
      (!ReadPemFile(options.tls_cert_path, "client certificate", &tls.pem_cert_chain, why) ||
       !ReadPemFile(options.tls_key_path, "client key", &tls.pem_private_key, why))) {
    return false;
  }
  *credentials = grpc::SslCredentials(tls);
  return true;
}

std::shared_ptr<grpc::Channel> MakeChannel(const std::string& address,
                                           const MapClientOptions& options,
                                           std::shared_ptr<grpc::ChannelCredentials> credentials) {
  grpc::ChannelArguments arguments;
  arguments.SetMaxReceiveMessageSize(options.max_message_bytes);
  arguments.SetMaxSendMessageSize(options.max_message_bytes);
  return grpc::CreateCustomChannel(address, std::move(credentials), arguments);
}

}  // namespace

bool ReadTokenFile(const std::string& path, std::string* token, std::string* why) {
  std::ifstream file(path);
  if (!file) {
    *why = path + ": cannot read the token file";
    return false;
  }
  std::string line;
  while (std::getline(file, line)) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::size_t last = line.find_last_not_of(" \t\r");
    *token = line.substr(first, last - first + 1);
    return true;
  }
  *why = path + ": no token in the file";
  return false;
}

bool MapClientOptions::IsValid(std::string* why) const {
  if (!std::isfinite(deadline_s) || deadline_s < 0.0) {
    *why = "deadline_s must be finite and >= 0";
    return false;
  }
  if (!std::isfinite(ingest_deadline_s) || ingest_deadline_s < 0.0) {
    *why = "ingest_deadline_s must be finite and >= 0";
    return false;
  }
  if (max_message_bytes < 1024) {
    *why = "max_message_bytes must be at least 1024";
    return false;
  }
  if (tls_cert_path.empty() != tls_key_path.empty()) {
    *why = "tls_cert_path and tls_key_path go together (mutual TLS)";
    return false;
  }
  if (!tls_cert_path.empty() && tls_ca_path.empty()) {
    *why = "a client certificate (tls_cert_path) needs TLS (tls_ca_path)";
    return false;
  }
  if (token.find_first_of("\r\n") != std::string::npos) {
    *why = "token must be one line";
    return false;
  }
  return encoding.IsValid(why);
}

MapClient::MapClient(const std::string& address, const MapClientOptions& options)
    : address_(address), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) {
    options_error_ = "MapClientOptions: " + why;
    options_.max_message_bytes = MapClientOptions().max_message_bytes;
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (!MakeCredentials(options_, &credentials, &why)) {
    if (options_error_.empty()) options_error_ = "MapClientOptions: " + why;
    credentials = grpc::InsecureChannelCredentials();
  }
  channel_ = MakeChannel(address_, options_, std::move(credentials));
  stub_ = v1::MapService::NewStub(channel_);
}

MapClient::~MapClient() = default;

bool MapClient::WaitForServer(std::chrono::milliseconds timeout) {
  return channel_->WaitForConnected(std::chrono::system_clock::now() + timeout);
}

grpc::Status MapClient::OptionsStatus() const {
  return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, options_error_);
}

template <typename Request, typename Response>
grpc::Status MapClient::Call(UnaryMethod<Request, Response> method, const Request& request,
                             Response* response) {
  if (!options_error_.empty()) return OptionsStatus();
  grpc::ClientContext context;
  internal::SetDeadline(options_.deadline_s, &context);
  internal::AddToken(options_.token, &context);
  return (stub_.get()->*method)(&context, request, response);
}

grpc::Status MapClient::AddKeyframe(const v1::AddKeyframeRequest& request,
                                    v1::AddKeyframeResponse* response) {
  return Call(&Stub::AddKeyframe, request, response);
}

grpc::Status MapClient::UpdatePoses(const v1::UpdatePosesRequest& request,
                                    v1::UpdatePosesResponse* response) {
  return Call(&Stub::UpdatePoses, request, response);
}

grpc::Status MapClient::ListKeyframes(const v1::ListKeyframesRequest& request,
                                      v1::ListKeyframesResponse* response) {
  return Call(&Stub::ListKeyframes, request, response);
}

grpc::Status MapClient::StartSession(const v1::StartSessionRequest& request,
                                     v1::Session* response) {
  return Call(&Stub::StartSession, request, response);
}

grpc::Status MapClient::ListSessions(const v1::ListSessionsRequest& request,
                                     v1::ListSessionsResponse* response) {
  return Call(&Stub::ListSessions, request, response);
}

grpc::Status MapClient::QueryObjects(const v1::QueryObjectsRequest& request,
                                     v1::QueryObjectsResponse* response) {
  return Call(&Stub::QueryObjects, request, response);
}

grpc::Status MapClient::GetObject(const v1::GetObjectRequest& request, v1::Object* response) {
  return Call(&Stub::GetObject, request, response);
}

grpc::Status MapClient::ListChanges(const v1::ListChangesRequest& request,
                                    v1::ListChangesResponse* response) {
  return Call(&Stub::ListChanges, request, response);
}

grpc::Status MapClient::Inventory(const v1::InventoryRequest& request,
                                  v1::InventoryResponse* response) {
  return Call(&Stub::Inventory, request, response);
}

grpc::Status MapClient::QueryOccupancy(const v1::QueryOccupancyRequest& request,
                                       v1::QueryOccupancyResponse* response) {
  return Call(&Stub::QueryOccupancy, request, response);
}

grpc::Status MapClient::IsFree(const v1::IsFreeRequest& request, v1::IsFreeResponse* response) {
  return Call(&Stub::IsFree, request, response);
}

grpc::Status MapClient::RayCast(const v1::RayCastRequest& request, v1::RayCastResponse* response) {
  return Call(&Stub::RayCast, request, response);
}

grpc::Status MapClient::GetOctomap(const v1::GetOctomapRequest& request,
                                   v1::GetOctomapResponse* response) {
  return Call(&Stub::GetOctomap, request, response);
}

grpc::Status MapClient::Status(const v1::StatusRequest& request, v1::StatusResponse* response) {
  return Call(&Stub::Status, request, response);
}

grpc::Status MapClient::AddKeyframe(const RgbdFrame& frame,
                                    const std::vector<Detection>* detections,
                                    v1::AddKeyframeResponse* response) {
  if (!options_error_.empty()) return OptionsStatus();
  v1::AddKeyframeRequest request;
  std::string why;
  if (!MakeAddKeyframeRequest(frame, detections, options_.encoding, &request, &why)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, why);
  }
  return AddKeyframe(request, response);
}

std::unique_ptr<IngestWriter> MapClient::StartIngest() {
  return std::unique_ptr<IngestWriter>(new IngestWriter(stub_.get(), options_, options_error_));
}

std::unique_ptr<grpc::ClientReader<v1::MapChange>> MapClient::WatchMap(
    const v1::WatchMapRequest& request, grpc::ClientContext* context) {
  internal::AddToken(options_.token, context);
  return stub_->WatchMap(context, request);
}

}  // namespace objmap
