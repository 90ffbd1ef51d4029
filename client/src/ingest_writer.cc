#include <grpcpp/grpcpp.h>

#include "client_internal.h"
#include "objmap/client.h"

namespace objmap {

IngestWriter::IngestWriter(v1::MapService::Stub* stub, const MapClientOptions& options,
                           const std::string& options_error)
    : options_(options) {
  if (!options_error.empty()) {
    finished_ = true;
    final_status_ = grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, options_error);
    return;
  }
  internal::SetDeadline(options_.ingest_deadline_s, &context_);
  internal::AddToken(options_.token, &context_);
  writer_ = stub->IngestKeyframes(&context_, &summary_);
}

IngestWriter::~IngestWriter() {
  // An abandoned stream is cancelled, so the server does not take it for a complete ingest.
  if (finished_ || writer_ == nullptr) return;
  context_.TryCancel();
  writer_->Finish().ok();
}

grpc::Status IngestWriter::Write(const RgbdFrame& frame, const std::vector<Detection>* detections) {
  if (finished_) return final_status_;
  v1::AddKeyframeRequest request;
  std::string why;
  if (!MakeAddKeyframeRequest(frame, detections, options_.encoding, &request, &why)) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, why);
  }
  return Write(request);
}

grpc::Status IngestWriter::Write(const v1::AddKeyframeRequest& request) {
  if (finished_) {
    return final_status_.ok()
               ? grpc::Status(grpc::StatusCode::FAILED_PRECONDITION, "ingest stream is finished")
               : final_status_;
  }
  if (writer_->Write(request)) {
    ++written_;
    return grpc::Status::OK;
  }
  // The stream broke: the server's status says why (a rejected keyframe, a shutdown).
  const grpc::Status status = FinishStream();
  if (!status.ok()) return status;
  final_status_ =
      grpc::Status(grpc::StatusCode::UNKNOWN, "the server closed the ingest stream before its end");
  return final_status_;
}

grpc::Status IngestWriter::Finish(v1::IngestSummary* summary) {
  if (!finished_) FinishStream();
  if (final_status_.ok()) *summary = summary_;
  return final_status_;
}

grpc::Status IngestWriter::FinishStream() {
  writer_->WritesDone();
  final_status_ = writer_->Finish();
  finished_ = true;
  return final_status_;
}

}  // namespace objmap
