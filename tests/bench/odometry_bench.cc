// RgbdOdometry on a recorded sequence, its poses ignored: time per frame, frames lost, keyframes,
// and the trajectory scored against the sequence's own poses (ATE after rigid alignment, RPE).
// Writes the estimated trajectory in TUM format (frame index / 30 as the stamp) for
// `objmap eval-trajectory` and for other tools: `out` holds each frame's pose when it was
// tracked, `<out>.final` the poses after every loop closure and `<out>.reference` the
// sequence's own, for per-frame errors (`objmap eval-trajectory ... --errors`).
// With `background`, loops are searched and solved on the odometry's own thread
// (OdometryConfig::background_loop_closure): the time per frame is then tracking alone.
//   odometry_bench [sequence=../shared/data/redkitchen] [frames=all] [out=odometry.txt]
//                  [sync|background]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"
#include "evaluation/trajectory_evaluation.h"
#include "odometry/rgbd_odometry.h"

namespace {

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<std::size_t>(p * (values.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace objmap;
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const long wanted = argc > 2 ? std::atol(argv[2]) : 0;
  const std::string out = argc > 3 ? argv[3] : "odometry.txt";
  std::string why;
  std::unique_ptr<SequenceReader> reader = OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "odometry_bench: %s\n", why.c_str());
    return 1;
  }
  const std::size_t count =
      wanted > 0 ? std::min<std::size_t>(reader->size(), static_cast<std::size_t>(wanted))
                 : reader->size();
  const std::string mode = argc > 4 ? argv[4] : "sync";
  if (mode != "sync" && mode != "background") {
    std::fprintf(stderr, "odometry_bench: mode must be sync or background, not %s\n", mode.c_str());
    return 1;
  }
  OdometryConfig config;
  config.background_loop_closure = mode == "background";
  RgbdOdometry odometry{config};
  std::vector<TrajectoryPose> estimated, reference;
  // Per tracked frame: the keyframe it was tracked against and its pose relative to it, so that
  // the whole trajectory follows the keyframes that loop closures moved.
  std::vector<std::pair<int, Eigen::Isometry3d>> relative;
  std::vector<double> ms;
  std::vector<std::size_t> keyframe_frames;  // per keyframe: the frame it was made from
  std::vector<double> loop_ms;  // per new keyframe: looking for loops (and solving when found)
  int lost = 0, relocalized = 0;
  for (std::size_t i = 0; i < count; ++i) {
    RgbdFrame frame;
    if (!reader->ReadFrame(i, &frame, &why)) {
      std::fprintf(stderr, "odometry_bench: %s\n", why.c_str());
      return 1;
    }
    const double stamp = static_cast<double>(i) / 30.0;
    reference.push_back({stamp, frame.T_W_C});
    const TrackingReport report = odometry.Track(frame);
    ms.push_back(report.ms);
    if (report.status == TrackingStatus::kLost) {
      ++lost;
      std::printf("frame %zu lost: %s\n", i, report.why.c_str());
      continue;
    }
    if (report.status == TrackingStatus::kRelocalized) ++relocalized;
    if (config.background_loop_closure ? report.loops_closed > 0
                                        : report.new_keyframe &&
                                              report.status != TrackingStatus::kInitialized) {
      loop_ms.push_back(report.loop_ms);
    }
    if (report.new_keyframe) {
      keyframe_frames.resize(static_cast<std::size_t>(report.reference_keyframe) + 1, 0);
      keyframe_frames[static_cast<std::size_t>(report.reference_keyframe)] = i;
    }
    estimated.push_back({stamp, report.T_W_C});
    relative.emplace_back(report.reference_keyframe,
                          odometry.KeyframePose(report.reference_keyframe).inverse() * report.T_W_C);
  }
  const int loops_at_end = odometry.FinishLoopClosure();
  std::vector<TrajectoryPose> corrected = estimated;
  for (std::size_t i = 0; i < corrected.size(); ++i) {
    corrected[i].T_W_C = odometry.KeyframePose(relative[i].first) * relative[i].second;
  }
  const std::string header = "stamp tx ty tz qx qy qz qw (RgbdOdometry, " + reader->Describe() + ")";
  if (!WriteTumTrajectory(out, estimated, header, &why) ||
      !WriteTumTrajectory(out + ".final", corrected, header + ", after loop closure", &why) ||
      !WriteTumTrajectory(out + ".reference", reference, "the sequence's own poses", &why)) {
    std::fprintf(stderr, "odometry_bench: %s\n", why.c_str());
    return 1;
  }
  double sum = 0.0;
  for (double value : ms) sum += value;
  std::printf("odometry_bench: %s, %zu frames: %.1f ms per frame mean, p50 %.1f, p99 %.1f; "
              "%d lost, %d relocalized, %d keyframes\n",
              reader->Describe().c_str(), count, sum / std::max<std::size_t>(1, ms.size()),
              Percentile(ms, 0.5), Percentile(ms, 0.99), lost, relocalized,
              odometry.num_keyframes());
  double loop_sum = 0.0;
  for (double value : loop_ms) loop_sum += value;
  if (config.background_loop_closure) {
    std::printf("loops closed: %d (%d of them after the last frame), searched in the background; "
                "search and solve per applied result %.1f ms mean over %zu results\n",
                odometry.loops_closed(), loops_at_end,
                loop_sum / std::max<std::size_t>(1, loop_ms.size()), loop_ms.size());
  } else {
    std::printf("loops closed: %d; loop closure per keyframe (candidates, PnP + ICP, graph solve): "
                "%.1f ms mean, p50 %.1f, p99 %.1f over %zu keyframes\n",
                odometry.loops_closed(), loop_sum / std::max<std::size_t>(1, loop_ms.size()),
                Percentile(loop_ms, 0.5), Percentile(loop_ms, 0.99), loop_ms.size());
  }
  // Each graph edge against the sequence's poses of its two keyframes' frames: how far the
  // measurements the graph is solved from disagree with the reference, odometry and loops apart
  // (reference_check tells how far the reference itself can be trusted).
  for (const bool loops : {false, true}) {
    std::vector<double> cm;
    for (const PoseGraphEdge& edge : odometry.graph_edges()) {
      if (edge.loop != loops) continue;
      const Eigen::Isometry3d& A = reference[keyframe_frames[static_cast<std::size_t>(edge.from)]].T_W_C;
      const Eigen::Isometry3d& B = reference[keyframe_frames[static_cast<std::size_t>(edge.to)]].T_W_C;
      cm.push_back(100.0 * ((A.inverse() * B).inverse() * edge.T_from_to).translation().norm());
    }
    if (cm.empty()) continue;
    double sum_sq = 0.0;
    for (double value : cm) sum_sq += value * value;
    std::printf("%s edges against the reference: %zu, translation differs by RMS %.2f cm, "
                "median %.2f, max %.2f\n", loops ? "loop" : "odometry", cm.size(),
                std::sqrt(sum_sq / static_cast<double>(cm.size())), Percentile(cm, 0.5),
                Percentile(cm, 1.0));
  }
  TrajectoryErrors final_errors;
  if (EvaluateTrajectory(corrected, reference, TrajectoryEvaluationConfig{}, &final_errors, &why)) {
    std::printf("after every loop closure (each frame on its keyframe's final pose): ATE RMSE "
                "%.4f m (max %.4f); RPE over 1 m: %.2f %%, %.3f deg/m\n",
                final_errors.ate_rmse_m, final_errors.ate_max_m,
                final_errors.rpe_translation_percent, final_errors.rpe_rotation_deg_per_m);
  }
  TrajectoryErrors errors;
  if (!EvaluateTrajectory(estimated, reference, TrajectoryEvaluationConfig{}, &errors, &why)) {
    std::printf("no score: %s\n", why.c_str());
    return 0;
  }
  std::printf("online (each frame's pose when tracked): ATE RMSE %.4f m (mean %.4f, max %.4f) "
              "over %zu poses; RPE over 1 m: %.2f %%, "
              "%.3f deg/m (%zu stretches); trajectory in %s\n",
              errors.ate_rmse_m, errors.ate_mean_m, errors.ate_max_m, errors.matched,
              errors.rpe_translation_percent, errors.rpe_rotation_deg_per_m, errors.rpe_pairs,
              out.c_str());
  return 0;
}
