// `objmap map`: an RGB-D sequence, recording or live camera in, an object map out.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "arguments.h"
#include "commands.h"
#include "config/objmap_config.h"
#include "detection/centernet_detector.h"
#include "detection/detections_file.h"
#include "detection/model_location.h"
#include "evaluation/trajectory_evaluation.h"
#include "map_folder.h"
#include "map_inputs.h"
#include "map_run_outputs.h"
#include "mapper/map_export.h"
#include "pipeline/sequence_runner.h"
#include "poses_file.h"
#include "progress_bar.h"
#include "types/coco_classes.h"

namespace objmap::cli {
namespace {

constexpr char kMapUsage[] =
    "objmap map: builds an object map (OctoMap + objects with classes) from an RGB-D sequence,\n"
    "recording or live camera, locally, without a server.\n"
    "usage: objmap map <input> --out <dir> [options]\n"
    "       objmap map <input> --map <dir> [--session NAME] [options]\n"
    "       objmap map --print-config [--config FILE] [--set SECTION.KEY=V ...]\n"
    "  <input>                   7-Scenes folder (frame-NNNNNN.*) or TUM RGB-D folder;\n"
    "                            openni2 | openni2:<device-uri>: a live OpenNI2 camera (runs\n"
    "                            until --max-frames or Ctrl-C, then writes the map);\n"
    "                            FILE.oni: an OpenNI2 recording;\n"
    "                            FILE.bag: a ROS1 bag (builds with ROS): colour, depth and\n"
    "                            camera info paired by stamp, poses from /tf + /tf_static at\n"
    "                            each colour stamp; topics left unset are auto-detected\n"
    "  --out DIR                 output folder: map.bt, objects.json, objects/*.ply, timings.csv\n"
    "                            keyframes.txt, keyframes/<id>.jpg (what `objmap view` shows)\n"
    "  --map DIR                 instead of --out: add this run to the map in DIR (its map.db,\n"
    "                            the store objmap_server keeps; created when missing) as a new\n"
    "                            session, then write DIR's files again from the whole map. With\n"
    "                            estimated poses the session may start anywhere in the saved\n"
    "                            map: its first keyframe is placed by relocalisation\n"
    "  --session NAME            --map: the new session's name (default: session N)\n"
    "  --config FILE             objmap's configuration file, the same as objmap_server --config\n"
    "                            and objmap_node's parameters (every key with its default:\n"
    "                            PREFIX/share/objmap/objmap.example.yaml); the flags below win\n"
    "  --set SECTION.KEY=V       one configuration key after the file, e.g.\n"
    "                            --set occupancy.resolution_m=0.02 (repeatable)\n"
    "  --print-config            print the effective configuration as YAML and exit\n"
    "  --model FILE              CenterNet GraphDef (default: PREFIX/share/objmap/models/\n"
    "                            centernet_coco.pb, then $OBJMAP_MODEL, then the source tree's\n"
    "                            models/ for a build-tree run)\n"
    "  --detections FILE         take detections from a JSON file instead of the network\n"
    "  --save-detections FILE    write the detections used, to replay a run\n"
    "  --score-threshold S       detector peak threshold (default: detector.score_threshold)\n"
    "  --first-frame N           first frame index (default 0)\n"
    "  --max-frames N            number of frames to read (default: all)\n"
    "  --trajectory FILE         camera / recording: poses, TUM lines `stamp tx ty tz qx qy qz\n"
    "                            qw` (T_W_C), the nearest in stamp taken; frames without one\n"
    "                            are skipped. Without it the poses are estimated\n"
    "                            (--poses auto)\n"
    "  --trajectory-tolerance S  largest frame/pose stamp difference, seconds (default 0.02)\n"
    "  --poses SOURCE            input: the input's poses (a dataset's, a bag's, --trajectory;\n"
    "                            a camera without --trajectory is static at the identity);\n"
    "                            estimate: tracked by RGB-D odometry from the frames alone\n"
    "                            (frames it cannot track are skipped with the reason); with a\n"
    "                            dataset, the estimate is scored against its poses (ATE, RPE)\n"
    "                            and written to <out>/trajectory.txt; auto (default): estimate\n"
    "                            for a camera or .oni without --trajectory, else input\n"
    "  --object-constraints on|off  estimated poses: re-observed objects tie the keyframes\n"
    "                            that saw them into the pose graph, solved again after the\n"
    "                            run (default off: on redkitchen it raised the ATE,\n"
    "                            docs/evaluation.md)\n"
    "  --min-translation M       keyframe after this much motion, metres (keyframes section)\n"
    "  --min-rotation DEG        keyframe after this much rotation, degrees (keyframes section)\n"
    "  --every-frame             every frame is a keyframe\n"
    "  --every-nth-frame N       frames 0, N, 2N, ... are the keyframes, whatever the motion\n"
    "  --min-evidence E          inventory: evidence an object needs from the views that\n"
    "                            could see it: + detection score, - misses (default 0.3)\n"
    "  --min-confidence C        inventory: confidence an object needs (default 0.2)\n"
    "  --min-observations N      inventory: observations an object needs (default 1)\n"
    "                            (the three: inventory section)\n"
    "  --stop-on-error           stop at the first bad frame instead of skipping it\n"
    "  --corrected-poses FILE    after the run, apply these poses as a pose-graph update (lines\n"
    "                            `frame_index tx ty tz qx qy qz qw`, T_W_C) and regenerate the\n"
    "                            map; keyframes whose frame has no line keep their pose\n";

// Set by SIGINT while a run is in progress. A signal handler can only reach a flag of static
// storage; it is lock-free and touched by nothing else.
std::atomic<bool> interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the SIGINT flag must be lock-free");

void OnInterrupt(int) { interrupted.store(true); }

// Ends a stream cleanly after Ctrl-C, so that a live camera run still writes its map. The
// previous SIGINT handler comes back when the run is over.
class InterruptibleStream : public FrameStream {
 public:
  explicit InterruptibleStream(FrameStream* inner) : inner_(inner) {
    interrupted.store(false);
    previous_ = std::signal(SIGINT, OnInterrupt);
  }
  ~InterruptibleStream() override { std::signal(SIGINT, previous_); }
  FrameStatus Next(RgbdFrame* frame, std::string* why) override {
    if (interrupted.load()) return FrameStatus::kEnded;
    const FrameStatus status = inner_->Next(frame, why);
    // A read cut short by the signal is the end asked for, not a failure.
    return interrupted.load() ? FrameStatus::kEnded : status;
  }
  std::size_t size() const override { return inner_->size(); }
  std::string Describe() const override { return inner_->Describe(); }
  [[nodiscard]] bool was_interrupted() const { return interrupted.load(); }

 private:
  FrameStream* inner_;
  void (*previous_)(int) = SIG_DFL;
};

std::unique_ptr<Detector> MakeDetector(Arguments& args, const CenterNetConfig& configured,
                                       std::string* why) {
  if (args.Has("--detections")) {
    DetectionsFileConfig config;
    config.path = args.Get("--detections", "");
    return MakeDetectionsFileDetector(config, why);
  }
  CenterNetConfig config = configured;
  if (!FindDetectorModel(configured.model_path, &config.model_path, why)) {
    *why += " (or --detections FILE)";
    return nullptr;
  }
  std::cout << "detector model: " << config.model_path << "\n";
  return MakeCenterNetDetector(config, why);
}

struct StageMedians {
  double detection_ms, segmentation_ms, association_ms, occupancy_ms, total_ms;
};

StageMedians Medians(const SequenceRunReport& report) {
  std::vector<double> det, seg, assoc, occ, total;
  for (const KeyframeReport& k : report.keyframes) {
    det.push_back(k.detection_ms);
    seg.push_back(k.result.timings.segmentation_ms);
    assoc.push_back(k.result.timings.association_ms);
    occ.push_back(k.result.timings.occupancy_ms);
    total.push_back(k.detection_ms + k.result.timings.segmentation_ms +
                    k.result.timings.association_ms + k.result.timings.occupancy_ms);
  }
  return {Median(det), Median(seg), Median(assoc), Median(occ), Median(total)};
}

void PrintSummary(const Mapper& mapper, const SequenceRunReport& report, double wall_s) {
  std::cout << "\nkeyframes: " << report.keyframes.size() << " of " << report.frames_read
            << " frames read; skipped frames: " << report.skipped.size() << "\n";
  // The first evidence computation projects every object into every keyframe (later ones, as a
  // server makes them after each keyframe, only the new keyframe and the changed objects).
  const auto evidence_start = std::chrono::steady_clock::now();
  const std::vector<const MapObject*> confirmed_objects = mapper.ConfirmedObjects();
  const auto confirmed_unknown =
      std::count_if(confirmed_objects.begin(), confirmed_objects.end(),
                    [](const MapObject* object) { return object->Label() == kUnknownClassId; });
  const std::size_t confirmed =
      confirmed_objects.size() -
      (mapper.config().inventory.count_unknown ? 0 : static_cast<std::size_t>(confirmed_unknown));
  const double evidence_ms = std::chrono::duration<double, std::milli>(
                                 std::chrono::steady_clock::now() - evidence_start)
                                 .count();
  std::cout << "objects in the map: " << mapper.objects().size()
            << ", in the inventory (evidence >= " << mapper.config().inventory.min_evidence
            << ", confidence >= " << mapper.config().inventory.min_confidence
            << ", observations >= " << mapper.config().inventory.min_observations
            << "): " << confirmed << " (evidence of all objects from all keyframes: "
            << std::fixed << std::setprecision(1) << evidence_ms << " ms)\n";
  std::cout << "unknown objects (never named, segmented in >= "
            << mapper.config().inventory.unknown_min_views << " views): " << confirmed_unknown
            << "\n\n";
  std::cout << std::left << std::setw(16) << "class" << std::right << std::setw(6) << "count"
            << std::setw(17) << "mean confidence"
            << "\n";
  for (const InventoryEntry& entry : mapper.Inventory()) {
    std::cout << std::left << std::setw(16) << ObjectClassName(entry.class_id) << std::right
              << std::setw(6) << entry.count << std::setw(17) << std::fixed << std::setprecision(3)
              << entry.mean_confidence << "\n";
  }
  const StageMedians m = Medians(report);
  std::cout << "\nmedian ms per keyframe: detection " << std::setprecision(1) << m.detection_ms
            << ", segmentation " << m.segmentation_ms << ", association " << m.association_ms
            << ", occupancy " << m.occupancy_ms << ", total " << m.total_ms << "\n";
  std::cout << "wall time: " << std::setprecision(1) << wall_s << " s\n";
}

// The keyframes' final poses in the poses-file format (`objmap update-poses`, `objmap render`
// takes the world's up from them), with the frame each was made from.
bool WriteKeyframePoses(const SequenceRunReport& report, const Mapper& mapper,
                        const std::string& path, std::string* why) {
  std::ofstream out(path);
  out << "# keyframe_id tx ty tz qx qy qz qw (T_W_C, camera to world)  # frame index\n";
  for (const KeyframeReport& keyframe : report.keyframes) {
    const KeyframeRecord* record = mapper.FindKeyframe(keyframe.result.keyframe_id);
    if (record == nullptr) continue;
    out << FormatPoseLine(keyframe.result.keyframe_id, record->T_W_C.translation(),
                          Eigen::Quaterniond(record->T_W_C.rotation()),
                          "frame " + std::to_string(keyframe.frame_index));
  }
  if (!out) {
    *why = path + ": write failed";
    return false;
  }
  return true;
}

// The configuration: the defaults, then --config FILE, then --set keys, then the other flags.
bool ConfigFrom(Arguments& args, const std::vector<std::string>& assignments, ObjmapConfig* config,
                std::string* why) {
  if (!ReadObjmapConfig(args.Get("--config", ""), assignments, config, why)) return false;
  InventoryConfig& inventory = config->map_server.mapper.inventory;
  inventory.min_observations =
      static_cast<int>(args.GetNumber("--min-observations", inventory.min_observations));
  inventory.min_confidence =
      static_cast<float>(args.GetNumber("--min-confidence", inventory.min_confidence));
  inventory.min_evidence =
      static_cast<float>(args.GetNumber("--min-evidence", inventory.min_evidence));
  KeyframeSelectorConfig& keyframes = config->keyframes;
  keyframes.min_translation_m = args.GetNumber("--min-translation", keyframes.min_translation_m);
  keyframes.min_rotation_deg = args.GetNumber("--min-rotation", keyframes.min_rotation_deg);
  if (args.Has("--every-frame")) {
    keyframes.every_nth_frame = 1;
  } else if (args.Has("--every-nth-frame")) {
    keyframes.every_nth_frame =
        static_cast<int>(args.GetNumber("--every-nth-frame", keyframes.every_nth_frame));
  }
  CenterNetConfig& detector = config->detector;
  detector.model_path = args.Get("--model", detector.model_path);
  detector.score_threshold =
      static_cast<float>(args.GetNumber("--score-threshold", detector.score_threshold));
  if (!args.error().empty()) return true;  // reported with the usage by the caller
  return config->IsValid(why);
}

SequenceRunConfig RunConfigFrom(Arguments& args, const ObjmapConfig& objmap_config) {
  SequenceRunConfig config;
  config.first_frame = static_cast<std::size_t>(args.GetNumber("--first-frame", 0));
  config.max_frames = static_cast<std::size_t>(args.GetNumber("--max-frames", 0));
  config.keyframes = objmap_config.keyframes;
  config.stop_on_bad_frame = args.Has("--stop-on-error");
  return config;
}

MapInputOptions InputOptionsFrom(Arguments& args, const SequenceRunConfig& run_config) {
  MapInputOptions options;
  options.first_frame = run_config.first_frame;
  options.max_frames = run_config.max_frames;
  options.trajectory_path = args.Get("--trajectory", "");
  options.trajectory_match.max_stamp_difference_s =
      args.GetNumber("--trajectory-tolerance", options.trajectory_match.max_stamp_difference_s);
  const std::string poses = args.Get("--poses", "auto");
  if (poses != "auto" && poses != "input" && poses != "estimate") {
    args.SetError("--poses must be auto, input or estimate, not " + poses);
  }
  options.estimate_poses = poses == "estimate";
  options.estimate_missing_poses = poses == "auto";
  BagOptionsFrom(args, &options);
  return options;
}

// The score line of `poses` against the input's own, or why there is none.
std::string ScoreAgainstInput(const std::vector<TrajectoryPose>& poses,
                              const std::vector<TrajectoryPose>& source) {
  TrajectoryErrors errors;
  std::string reason;
  if (!EvaluateTrajectory(poses, source, TrajectoryEvaluationConfig{}, &errors, &reason)) {
    return "not scored (" + reason + ")";
  }
  char text[256];
  std::snprintf(text, sizeof(text),
                "ATE RMSE %.4f m (max %.4f) over %zu poses; RPE over 1 m: %.2f %%, %.3f deg/m",
                errors.ate_rmse_m, errors.ate_max_m, errors.matched,
                errors.rpe_translation_percent, errors.rpe_rotation_deg_per_m);
  return text;
}

// Moves the mapped keyframes to the trajectory's poses (a pose-graph update: the map is
// regenerated).
bool MoveMappedKeyframes(const std::vector<TrajectoryPose>& final_poses,
                         const EstimatedTrajectory& trajectory, const SequenceRunReport& report,
                         Mapper* mapper, PoseUpdateReport* update, std::string* why) {
  std::map<std::int64_t, Eigen::Isometry3d> by_frame;
  for (std::size_t i = 0; i < final_poses.size(); ++i) {
    by_frame[trajectory.frame_index[i]] = final_poses[i].T_W_C;
  }
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (const KeyframeReport& keyframe : report.keyframes) {
    const auto it = by_frame.find(static_cast<std::int64_t>(keyframe.frame_index));
    if (it != by_frame.end()) poses[keyframe.result.keyframe_id] = it->second;
  }
  return poses.empty() || mapper->UpdatePoses(poses, why, update);
}

// Re-observed objects tie the keyframes that saw them (ObjectConstraints): their edges join the
// odometry's pose graph, which is solved again, and the map follows. Returns false only when
// the map update fails; a graph without object edges leaves everything as it is.
bool ConstrainByObjects(const ObjectConstraintConfig& config, const SequenceRunReport& report,
                        EstimatedTrajectory* trajectory, Mapper* mapper, std::string* why) {
  std::map<KeyframeId, std::int64_t> frame_of;
  for (const KeyframeReport& keyframe : report.keyframes) {
    frame_of[keyframe.result.keyframe_id] = static_cast<std::int64_t>(keyframe.frame_index);
  }
  const auto anchor_of = [&](KeyframeId id) -> std::optional<KeyframeAnchor> {
    const auto it = frame_of.find(id);
    if (it == frame_of.end()) return std::nullopt;
    return AnchorOfFrame(*trajectory, it->second);
  };
  std::vector<const MapObject*> objects;
  for (const auto& [id, object] : mapper->objects().objects()) objects.push_back(&object);
  ObjectConstraintReport found;
  const std::vector<PoseGraphEdge> edges = ObjectConstraints(objects, anchor_of, config, &found);
  std::printf(
      "object constraints: %d objects with distant views, %d view pairs aligned, %d "
      "constraints (%.0f ms)",
      found.groups, found.pairs_tried, found.constraints, found.ms);
  if (edges.empty()) {
    std::printf("\n");
    return true;
  }
  const std::size_t edges_before = trajectory->graph_edges.size();
  PoseGraphReport solved;
  std::string unsolved;
  if (!ConstrainTrajectory(edges, trajectory, &solved, &unsolved)) {
    std::printf("; pose graph not solved (%s), poses kept\n", unsolved.c_str());
    return true;
  }
  const int rejected = static_cast<int>(
      std::count_if(solved.rejected_loops.begin(), solved.rejected_loops.end(),
                    [&](int e) { return static_cast<std::size_t>(e) >= edges_before; }));
  std::printf(", %d rejected by the graph (%.0f ms)\n", rejected, solved.solve_ms);
  PoseUpdateReport update;
  if (!MoveMappedKeyframes(FinalPoses(*trajectory), *trajectory, report, mapper, &update, why)) {
    return false;
  }
  std::printf("object constraints: %d keyframes of the map moved, map regenerated\n",
              update.keyframes_moved);
  return true;
}

// After a run with estimated poses: moves the mapped keyframes to their poses after every loop
// closure and the object constraints (pose-graph updates, which regenerate the map), prints how
// tracking went and, when the input had poses of its own, the estimate's errors against them;
// writes the final trajectory.
bool FinishEstimatedTrajectory(EstimatedTrajectory trajectory, bool source_has_poses,
                               const ObjectConstraintConfig* object_constraints,
                               const SequenceRunReport& report, Mapper* mapper,
                               const std::string& path, std::string* why) {
  std::printf(
      "odometry: %d frames, %d tracked, %d lost, %d relocalized, %d loops closed, %.1f ms per "
      "frame\n",
      trajectory.frames, trajectory.frames - trajectory.lost, trajectory.lost,
      trajectory.relocalized, trajectory.loops_closed,
      trajectory.tracking_ms / std::max(1, trajectory.frames));
  const std::vector<TrajectoryPose> loop_poses = FinalPoses(trajectory);
  if (trajectory.loops_closed > 0) {
    PoseUpdateReport update;
    if (!MoveMappedKeyframes(loop_poses, trajectory, report, mapper, &update, why)) return false;
    std::printf("loop closures: %d keyframes of the map moved, map regenerated\n",
                update.keyframes_moved);
  }
  if (object_constraints != nullptr &&
      !ConstrainByObjects(*object_constraints, report, &trajectory, mapper, why)) {
    return false;
  }
  const std::vector<TrajectoryPose> final_poses = FinalPoses(trajectory);
  if (source_has_poses) {
    std::printf("odometry against the input's poses, as tracked: %s\n",
                ScoreAgainstInput(trajectory.estimated, trajectory.source).c_str());
    std::printf("odometry against the input's poses, after loop closures: %s\n",
                ScoreAgainstInput(loop_poses, trajectory.source).c_str());
    if (object_constraints != nullptr) {
      std::printf("odometry against the input's poses, after object constraints: %s\n",
                  ScoreAgainstInput(final_poses, trajectory.source).c_str());
    }
  }
  std::error_code ignored;  // a folder that cannot be made shows as the file not written
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ignored);
  return WriteTumTrajectory(path, final_poses,
                            "stamp tx ty tz qx qy qz qw: T_W_C estimated by objmap's RGB-D odometry",
                            why);
}

int Fail(const std::string& message) {
  std::cerr << "objmap map: " << message << "\n";
  return 1;
}

// A loop closure after the run: the corrected poses of the frames that became keyframes, applied
// with Mapper::UpdatePoses (which regenerates the object models and the OctoMap).
bool ApplyCorrectedPoses(const std::string& path, const SequenceRunReport& report, Mapper* mapper,
                         std::string* why) {
  std::vector<KeyframePoseLine> lines;
  if (!ReadPosesFile(path, &lines, why)) return false;
  std::map<std::size_t, Eigen::Isometry3d> by_frame;
  for (const KeyframePoseLine& line : lines) {
    by_frame[static_cast<std::size_t>(line.keyframe_id)] = line.T_W_C;
  }
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (const KeyframeReport& keyframe : report.keyframes) {
    const auto it = by_frame.find(keyframe.frame_index);
    if (it != by_frame.end()) poses[keyframe.result.keyframe_id] = it->second;
  }
  PoseUpdateReport update;
  const auto start = std::chrono::steady_clock::now();
  if (!mapper->UpdatePoses(poses, why, &update)) {
    *why = path + ": " + *why;
    return false;
  }
  std::cout << "corrected poses: " << update.keyframes_moved << " of " << report.keyframes.size()
            << " keyframes moved; ";
  if (update.reassociated) {
    std::cout << "objects re-associated (" << update.objects_before << " -> "
              << update.objects_after << "), ";
  }
  std::cout << "map regenerated in " << std::fixed << std::setprecision(1)
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
            << " s\n";
  return true;
}

}  // namespace

// The values of every "--set" in argv, in order (Arguments keeps one value per flag), and argv
// without them.
std::vector<std::string> TakeSetFlags(int argc, char** argv, std::vector<char*>* rest) {
  std::vector<std::string> assignments;
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--set" && i + 1 < argc) {
      assignments.push_back(argv[++i]);
    } else if (word.rfind("--set=", 0) == 0) {
      assignments.push_back(word.substr(6));
    } else {
      rest->push_back(argv[i]);
    }
  }
  return assignments;
}

int RunMapCommand(int argc, char** argv) {
  std::vector<char*> words;
  const std::vector<std::string> assignments = TakeSetFlags(argc, argv, &words);
  std::set<std::string> flags_with_value(
      {"--out", "--config", "--set", "--model", "--detections", "--save-detections",
       "--score-threshold", "--first-frame", "--max-frames", "--min-translation", "--min-rotation",
       "--every-nth-frame", "--min-observations", "--min-confidence", "--min-evidence",
       "--corrected-poses", "--trajectory", "--trajectory-tolerance", "--poses",
       "--object-constraints", "--map", "--session"});
  flags_with_value.merge(MapBagFlags());
  Arguments args(static_cast<int>(words.size()), words.data(), flags_with_value,
                 {"--every-frame", "--stop-on-error", "--print-config", "--help"});
  if (args.Has("--help")) {
    std::cout << kMapUsage << kMapBagUsage;
    return 0;
  }
  std::string why;
  ObjmapConfig objmap_config;
  if (!ConfigFrom(args, assignments, &objmap_config, &why)) return Fail(why);
  if (args.error().empty() && args.Has("--print-config")) {
    std::cout << ObjmapConfigToYaml(objmap_config);
    return 0;
  }
  MapperConfig mapper_config = objmap_config.map_server.mapper;
  // Nothing queries this map while it is made: one OctoMap copy is enough.
  mapper_config.occupancy_second_copy = false;
  SequenceRunConfig run_config = RunConfigFrom(args, objmap_config);
  MapInputOptions input_options = InputOptionsFrom(args, run_config);
  // --map: the map server tracks the frames itself (its odometry knows the saved map), so the
  // input is read with its own poses and the choice of estimating is made below.
  const bool estimate_flag = input_options.estimate_poses;
  const bool estimate_missing_flag = input_options.estimate_missing_poses;
  if (args.Has("--map")) {
    input_options.estimate_poses = false;
    input_options.estimate_missing_poses = false;
  }
  const std::string object_constraints_flag = args.Get("--object-constraints", "off");
  if (object_constraints_flag != "on" && object_constraints_flag != "off") {
    args.SetError("--object-constraints must be on or off, not " + object_constraints_flag);
  }
  const bool object_constraints = object_constraints_flag == "on";
  const ObjectConstraintConfig object_constraint_config;
  const bool into_map_folder = args.Has("--map");
  if (into_map_folder && args.Has("--out")) args.SetError("--out and --map exclude each other");
  if (into_map_folder && (args.Has("--corrected-poses") || object_constraints)) {
    args.SetError("--map keeps the map in its store: correct poses with objmap_server and "
                  "`objmap update-poses`, not --corrected-poses or --object-constraints");
  }
  if (!args.error().empty() || args.positional().size() != 1 ||
      !(args.Has("--out") || into_map_folder)) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << kMapUsage << kMapBagUsage;
    return 2;
  }
  if (!mapper_config.IsValid(&why) || !run_config.IsValid(&why)) return Fail(why);
  MapInput input;
  if (!OpenMapInput(args.positional()[0], input_options, &input, &why)) return Fail(why);
  if (input.selection_applied) {
    run_config.first_frame = 0;
    run_config.max_frames = 0;
  }
  auto detector = MakeDetector(args, objmap_config.detector, &why);
  if (!detector) return Fail(why);
  auto recorder = std::make_unique<RecordingDetector>(std::move(detector));
  if (into_map_folder) {
    MapFolderRun folder;
    folder.dir = args.Get("--map", "");
    folder.session_name = args.Get("--session", "");
    folder.server = objmap_config.map_server;
    const bool estimate = estimate_flag || (estimate_missing_flag && !input.source_has_poses);
    folder.server.pose_source = estimate ? PoseSource::kEstimate : PoseSource::kRequest;
    // As with --out: the estimate starts at the input's first pose, so that the map and the
    // input's own poses (and its ground truth) share a frame.
    folder.server.estimate_from_first_pose = estimate && input.source_has_poses;
    folder.source_has_poses = input.source_has_poses;
    folder.run = run_config;
    // Without poses of its own the input cannot pick keyframes by motion (the server tracks
    // them later): every 10th frame, a third of a second at 30 Hz, unless configured.
    if (estimate && !input.source_has_poses && folder.run.keyframes.every_nth_frame == 0) {
      folder.run.keyframes.every_nth_frame = 10;
    }
    std::cout << "mapping " << input.stream->Describe() << " with the " << recorder->Name()
              << " detector\n";
    InterruptibleStream stream(input.stream.get());
    const int code = RunIntoMapFolder(folder, &stream, recorder.get());
    if (args.Has("--save-detections") &&
        !WriteDetectionsFile(args.Get("--save-detections", ""), recorder->recorded(), &why)) {
      return Fail(why);
    }
    return code;
  }
  std::cout << "mapping " << input.stream->Describe() << " with the " << recorder->Name()
            << " detector\n";
  if (!input.note.empty()) std::cout << input.note << "\n";

  Mapper mapper(mapper_config);
  SequenceRunReport report;
  ProgressBar bar;
  const auto progress = [&bar](std::size_t done, std::size_t total, std::size_t keyframes) {
    bar.Update(done, total, keyframes);
  };
  const auto start = std::chrono::steady_clock::now();
  InterruptibleStream stream(input.stream.get());
  const bool completed =
      RunSequence(&stream, recorder.get(), &mapper, run_config, progress, &report, &why);
  if (stream.was_interrupted()) std::cerr << "\ninterrupted: writing the map of the frames read\n";
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const std::string& message : report.skipped) std::cerr << "skipped " << message << "\n";
  if (!completed) std::cerr << "\nobjmap map: stopped at " << why << "\n";
  if (args.Has("--corrected-poses") &&
      !ApplyCorrectedPoses(args.Get("--corrected-poses", ""), report, &mapper, &why)) {
    return Fail(why);
  }
  if (input.estimated &&
      !FinishEstimatedTrajectory(*input.estimated, input.source_has_poses,
                                 object_constraints ? &object_constraint_config : nullptr, report,
                                 &mapper,
                                 args.Get("--out", "") + "/trajectory.txt", &why)) {
    return Fail(why);
  }
  PrintSummary(mapper, report, wall_s);

  const std::string out_dir = args.Get("--out", "");
  if (!WriteMapOutputs(mapper, out_dir, &why) ||
      !WriteTimings(report, out_dir + "/timings.csv", &why) ||
      !WriteKeyframePoses(report, mapper, out_dir + "/keyframes.txt", &why) ||
      !WriteKeyframeImages(report, recorder->keyframe_jpegs(), out_dir + "/keyframes", &why)) {
    return Fail(why);
  }
  if (args.Has("--save-detections") &&
      !WriteDetectionsFile(args.Get("--save-detections", ""), recorder->recorded(), &why)) {
    return Fail(why);
  }
  std::cout << "wrote " << out_dir
            << "/map.bt, objects.json, objects/*.ply, timings.csv, keyframes.txt, keyframes/*.jpg"
            << (input.estimated ? ", trajectory.txt" : "") << "\n";
  return completed ? 0 : 1;
}

}  // namespace objmap::cli
