#include "odometry/odometry_stream.h"

#include <algorithm>
#include <utility>

namespace objmap {
namespace {

class OdometryStream : public FrameStream {
 public:
  OdometryStream(std::unique_ptr<FrameStream> inner, const OdometryConfig& config,
                 std::shared_ptr<EstimatedTrajectory> log, bool start_at_source_pose)
      : inner_(std::move(inner)),
        odometry_(config),
        log_(std::move(log)),
        start_at_source_pose_(start_at_source_pose) {}

  FrameStatus Next(RgbdFrame* frame, std::string* why) override {
    const FrameStatus status = inner_->Next(frame, why);
    if (status != FrameStatus::kFrame) return status;
    const TrackingReport report = Track(*frame);
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
    log_->loops_closed += report.loops_closed;
    if (report.loops_closed > 0 ||
        static_cast<int>(log_->keyframe_poses.size()) < odometry_.num_keyframes()) {
      log_->keyframe_poses.resize(static_cast<std::size_t>(odometry_.num_keyframes()));
      for (int k = 0; k < odometry_.num_keyframes(); ++k) {
        log_->keyframe_poses[static_cast<std::size_t>(k)] = odometry_.KeyframePose(k);
      }
      log_->graph_edges = odometry_.graph_edges();
    }
    log_->frame_index.push_back(frame->frame_index);
    log_->reference_keyframe.push_back(report.reference_keyframe);
    log_->T_K_C.push_back(odometry_.KeyframePose(report.reference_keyframe).inverse() *
                          report.T_W_C);
    frame->T_W_C = report.T_W_C;
    return FrameStatus::kFrame;
  }

  std::size_t size() const override { return inner_->size(); }
  std::string Describe() const override { return inner_->Describe() + ", poses estimated"; }

 private:
  TrackingReport Track(const RgbdFrame& frame) {
    if (!start_at_source_pose_ || odometry_.num_keyframes() > 0) return odometry_.Track(frame);
    TrackingReport report;
    if (!odometry_.StartFromKnownPose(frame, &report.why)) return report;  // kLost, with why
    report.status = TrackingStatus::kInitialized;
    report.T_W_C = frame.T_W_C;
    report.reference_keyframe = 0;
    report.new_keyframe = true;
    return report;
  }

  std::unique_ptr<FrameStream> inner_;
  RgbdOdometry odometry_;
  std::shared_ptr<EstimatedTrajectory> log_;
  bool start_at_source_pose_;
};

}  // namespace

std::vector<TrajectoryPose> FinalPoses(const EstimatedTrajectory& trajectory) {
  std::vector<TrajectoryPose> poses = trajectory.estimated;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    poses[i].T_W_C =
        trajectory.keyframe_poses[static_cast<std::size_t>(trajectory.reference_keyframe[i])] *
        trajectory.T_K_C[i];
  }
  return poses;
}

bool ConstrainTrajectory(const std::vector<PoseGraphEdge>& extra, EstimatedTrajectory* trajectory,
                         PoseGraphReport* report, std::string* why) {
  PoseGraph graph;
  for (std::size_t k = 0; k < trajectory->keyframe_poses.size(); ++k) {
    graph.AddNode(static_cast<int>(k), trajectory->keyframe_poses[k]);
  }
  for (const PoseGraphEdge& edge : trajectory->graph_edges) {
    if (!graph.AddEdge(edge, why)) return false;
  }
  for (const PoseGraphEdge& edge : extra) {
    if (!graph.AddEdge(edge, why)) return false;
  }
  if (!graph.Optimize(report, why)) return false;
  for (const auto& [k, pose] : graph.poses()) {
    trajectory->keyframe_poses[static_cast<std::size_t>(k)] = pose;
  }
  std::vector<bool> rejected(graph.edges().size(), false);
  for (int e : report->rejected_loops) rejected[static_cast<std::size_t>(e)] = true;
  trajectory->graph_edges.clear();
  for (std::size_t e = 0; e < graph.edges().size(); ++e) {
    if (!rejected[e]) trajectory->graph_edges.push_back(graph.edges()[e]);
  }
  return true;
}

std::optional<KeyframeAnchor> AnchorOfFrame(const EstimatedTrajectory& trajectory,
                                            std::int64_t frame_index) {
  const auto it = std::lower_bound(trajectory.frame_index.begin(), trajectory.frame_index.end(),
                                   frame_index);
  if (it == trajectory.frame_index.end() || *it != frame_index) return std::nullopt;
  const auto i = static_cast<std::size_t>(it - trajectory.frame_index.begin());
  const int node = trajectory.reference_keyframe[i];
  if (node < 0 || static_cast<std::size_t>(node) >= trajectory.keyframe_poses.size()) {
    return std::nullopt;
  }
  return KeyframeAnchor{node, trajectory.keyframe_poses[static_cast<std::size_t>(node)],
                        trajectory.T_K_C[i]};
}

std::unique_ptr<FrameStream> WithEstimatedPoses(std::unique_ptr<FrameStream> inner,
                                                const OdometryConfig& config,
                                                std::shared_ptr<EstimatedTrajectory> log,
                                                bool start_at_source_pose) {
  return std::make_unique<OdometryStream>(std::move(inner), config, std::move(log),
                                          start_at_source_pose);
}

}  // namespace objmap
