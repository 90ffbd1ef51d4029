#include "odometry/odometry_stream.h"

#include <utility>

namespace objmap {
namespace {

class OdometryStream : public FrameStream {
 public:
  OdometryStream(std::unique_ptr<FrameStream> inner, const OdometryConfig& config,
                 std::shared_ptr<EstimatedTrajectory> log)
      : inner_(std::move(inner)), odometry_(config), log_(std::move(log)) {}

  FrameStatus Next(RgbdFrame* frame, std::string* why) override {
    const FrameStatus status = inner_->Next(frame, why);
    if (status != FrameStatus::kFrame) return status;
    const TrackingReport report = odometry_.Track(*frame);
    ++log_->frames;
    log_->tracking_ms += report.ms;
    if (report.status == TrackingStatus::kLost) {
      ++log_->lost;
      *why = frame->name + ": tracking lost: " + report.why;
      return FrameStatus::kBadFrame;
    }
    if (report.status == TrackingStatus::kRelocalized) ++log_->relocalized;
    const double stamp =
        frame->stamp_s > 0.0 ? frame->stamp_s : static_cast<double>(frame->frame_index) / 30.0;
    log_->source.push_back({stamp, frame->T_W_C});
    log_->estimated.push_back({stamp, report.T_W_C});
    frame->T_W_C = report.T_W_C;
    return FrameStatus::kFrame;
  }

  std::size_t size() const override { return inner_->size(); }
  std::string Describe() const override { return inner_->Describe() + ", poses estimated"; }

 private:
  std::unique_ptr<FrameStream> inner_;
  RgbdOdometry odometry_;
  std::shared_ptr<EstimatedTrajectory> log_;
};

}  // namespace

std::unique_ptr<FrameStream> WithEstimatedPoses(std::unique_ptr<FrameStream> inner,
                                                const OdometryConfig& config,
                                                std::shared_ptr<EstimatedTrajectory> log) {
  return std::make_unique<OdometryStream>(std::move(inner), config, std::move(log));
}

}  // namespace objmap
