#include "map_folder.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>

#include "evaluation/trajectory_evaluation.h"
#include "poses_file.h"
#include "progress_bar.h"
#include "types/coco_classes.h"

namespace objmap::cli {
namespace {

namespace fs = std::filesystem;

int Fail(const std::string& message) {
  std::cerr << "objmap map: " << message << "\n";
  return 1;
}

// keyframes.txt: every stored keyframe (all sessions) at its current pose, in the poses-file
// format, with its name and session.
bool WriteAllKeyframePoses(const std::vector<KeyframeSummary>& keyframes, const std::string& path,
                           std::string* why) {
  std::ofstream out(path);
  out << "# keyframe_id tx ty tz qx qy qz qw (T_W_C, camera to world)  # name, session\n";
  for (const KeyframeSummary& keyframe : keyframes) {
    out << FormatPoseLine(keyframe.id, keyframe.T_W_C.translation(),
                          Eigen::Quaterniond(keyframe.T_W_C.rotation()),
                          keyframe.name + ", session " + std::to_string(keyframe.session_id));
  }
  if (!out) *why = path + ": write failed";
  return static_cast<bool>(out);
}

// The ATE of this run's keyframes (their poses in the map now) against the input's own poses,
// paired by keyframe id.
std::string ScoreRun(const std::map<KeyframeId, Eigen::Isometry3d>& input_poses,
                     const std::vector<KeyframeSummary>& keyframes) {
  std::vector<TrajectoryPose> estimated, reference;
  for (const KeyframeSummary& keyframe : keyframes) {
    const auto it = input_poses.find(keyframe.id);
    if (it == input_poses.end()) continue;
    const double order = static_cast<double>(keyframe.id);  // pairs by id, not by stamp
    estimated.push_back({order, keyframe.T_W_C});
    reference.push_back({order, it->second});
  }
  TrajectoryErrors errors;
  std::string reason;
  if (!EvaluateTrajectory(estimated, reference, TrajectoryEvaluationConfig{}, &errors, &reason)) {
    return "not scored (" + reason + ")";
  }
  char text[160];
  std::snprintf(text, sizeof(text), "ATE RMSE %.4f m (max %.4f) over %zu keyframes",
                errors.ate_rmse_m, errors.ate_max_m, errors.matched);
  return text;
}

void PrintInventory(const MapServer& server) {
  std::vector<InventoryEntry> entries;
  std::uint64_t version = 0;
  if (!server.Inventory(std::nullopt, &entries, &version).ok()) return;
  std::cout << "\n" << std::left << std::setw(16) << "class" << std::right << std::setw(6)
            << "count" << std::setw(17) << "mean confidence\n";
  for (const InventoryEntry& entry : entries) {
    std::cout << std::left << std::setw(16) << ObjectClassName(entry.class_id) << std::right
              << std::setw(6) << entry.count << std::setw(17) << std::fixed
              << std::setprecision(3) << entry.mean_confidence << "\n";
  }
}

}  // namespace

int RunIntoMapFolder(const MapFolderRun& config, FrameStream* stream,
                     RecordingDetector* detector) {
  std::error_code error;
  fs::create_directories(config.dir, error);
  if (error) return Fail(config.dir + ": " + error.message());
  const std::string db_path = (fs::path(config.dir) / "map.db").string();
  const bool existed = fs::exists(db_path);
  std::string why;
  // The CLI runs the detector (RunSequence): the server gets each keyframe's detections.
  std::unique_ptr<MapServer> server = MapServer::Open(config.server, db_path, nullptr, &why);
  if (!server) return Fail(db_path + ": " + why);
  SessionSummary started;
  const ServiceStatus session = server->StartSession(config.session_name, &started);
  if (!session.ok()) return Fail("--session: " + session.message);
  const ServerStatus before = server->Status();
  std::cout << (existed ? "adding to the map in " : "a new map in ") << config.dir << " ("
            << before.keyframes << " keyframes, " << before.objects << " objects): session "
            << started.session.id << " \"" << started.session.name << "\", poses "
            << started.session.pose_source << "\n";

  std::map<KeyframeId, Eigen::Isometry3d> input_poses;
  int relocalized = 0, attached = 0, repeated = 0, repeated_in_part = 0;
  const KeyframeSink sink = [&](const RgbdFrame& frame, const std::vector<Detection>& detections,
                                KeyframeResult* result, std::string* reason) {
    AddKeyframeOutcome outcome;
    const ServiceStatus added = server->AddKeyframe(frame, detections, &outcome);
    if (!added.ok()) {
      *reason = added.message;
      return false;
    }
    result->keyframe_id = outcome.keyframe_id;
    result->detections_used = outcome.detections_used;
    result->created = outcome.created;
    result->updated = outcome.updated;
    if (outcome.relocalized) ++relocalized;
    if (outcome.keyframe_id == 0) {
      ++repeated;  // a revisit of a stored view, no keyframe of the map
    } else {
      input_poses[outcome.keyframe_id] = frame.T_W_C;
      if (outcome.repeated_keyframe != 0) ++repeated_in_part;
    }
    // Held keyframes of a provisional part this one placed: mapped now (their input poses are
    // not at hand here, so they are not scored).
    attached += static_cast<int>(outcome.attached.size());
    return true;
  };
  SequenceRunReport report;
  ProgressBar bar;
  const auto progress = [&bar](std::size_t done, std::size_t total, std::size_t keyframes) {
    bar.Update(done, total, keyframes);
  };
  const auto start = std::chrono::steady_clock::now();
  const bool completed =
      RunSequence(stream, detector, sink, config.run, progress, &report, &why);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const std::string& message : report.skipped) std::cerr << "skipped " << message << "\n";
  if (!completed) std::cerr << "\nobjmap map: stopped at " << why << "\n";

  std::vector<KeyframeSummary> keyframes;
  std::uint64_t version = 0;
  ServiceStatus listed = server->ListKeyframes(0, 0, &keyframes, &version);
  if (!listed.ok()) return Fail(listed.message);
  const ServerStatus after = server->Status();
  std::cout << "\nsession " << started.session.id << ": "
            << report.keyframes.size() + static_cast<std::size_t>(attached) -
                   static_cast<std::size_t>(repeated)
            << " keyframes mapped of " << report.frames_read << " frames read";
  if (repeated > 0 || repeated_in_part > 0) {
    std::cout << " (" << repeated_in_part
              << " of them with only the part new to the map: the rest repeated stored views), "
              << repeated << " kept as revisits of stored views (the same view, nothing changed)";
  }
  if (config.server.pose_source == PoseSource::kEstimate) {
    std::cout << " (" << relocalized << " placed in the saved map by relocalisation, " << attached
              << " held until a later keyframe placed them)";
  }
  std::cout << "; skipped frames: " << report.skipped.size() << "\n"
            << "the map: " << after.keyframes << " keyframes, " << after.objects << " objects, "
            << after.confirmed_objects << " in the inventory\n";
  if (config.server.pose_source == PoseSource::kEstimate && config.source_has_poses) {
    std::cout << "estimated poses of this session against the input's: "
              << ScoreRun(input_poses, keyframes) << "\n";
  }
  PrintInventory(*server);
  std::cout << "wall time: " << std::fixed << std::setprecision(1) << wall_s << " s\n";

  const ServiceStatus written = server->WriteMapFolder(config.dir);
  if (!written.ok()) return Fail(written.message);
  if (!WriteAllKeyframePoses(keyframes, config.dir + "/keyframes.txt", &why) ||
      !WriteKeyframeImages(report, detector->keyframe_jpegs(), config.dir + "/keyframes", &why)) {
    return Fail(why);
  }
  std::cout << "wrote " << config.dir
            << "/map.bt, objects.json, objects/*.ply, keyframes.txt, keyframes/*.jpg (the map "
               "itself: map.db)\n";
  return completed ? 0 : 1;
}

}  // namespace objmap::cli
