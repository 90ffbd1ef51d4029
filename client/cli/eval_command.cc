// `objmap eval`: a map scored against ground truth (object poses) or expected counts per class.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "arguments.h"
#include "commands.h"
#include "evaluation/evaluation.h"
#include "evaluation/evaluation_io.h"
#include "occupancy/occupancy_map.h"
#include "types/coco_classes.h"
#ifdef OBJMAP_CLI_WITH_SERVER
#include "objmap/conversions.h"
#include "server_common.h"
#endif

namespace objmap::cli {
namespace {

constexpr char kEvalUsage[] =
    "objmap eval: scores a map (a map folder or a running server) against ground-truth objects\n"
    "or inventory counts, and the changes a map folder reports between sessions against the\n"
    "changes the scene went through.\n"
    "usage: objmap eval <map-dir | ADDR> (--gt ground_truth.json | --inventory counts.json)\n"
    "       objmap eval <map-dir> --changes changes.json [--since-session S]\n"
    "                   [--gt-before ground_truth.json] [--gt ground_truth.json]\n"
    "                   [--lookalikes-as-written]\n"
    "  <map-dir>                 folder written by `objmap map --out` or `objmap export\n"
    "                            --objects` (objects.json and the .ply models); with\n"
    "                            --changes, by `objmap map --map` (its changes.json)\n"
    "  ADDR                      host:port of a running objmap_server (its inventory objects)\n"
    "  --gt FILE                 real objects with poses, sizes and surface samples (with\n"
    "                            --changes: those of the second session, which also give the\n"
    "                            sizes of added and moved objects)\n"
    "  --inventory FILE          expected count per class: {\"chair\": 4, \"tv\": [1, 2]}\n"
    "  --octomap FILE.bt         the map's OctoMap (default: map.bt in <map-dir>, or the\n"
    "                            server's); scored when the ground truth has a seen surface\n"
    "  --changes FILE            the real changes (the simulator's changes.json of the second\n"
    "                            session: removed, moved, added objects)\n"
    "  --since-session S         count only the changes the map reports in sessions >= S\n"
    "                            (default: every session)\n"
    "  --gt-before FILE          ground_truth.json of the first session: sizes of removed\n"
    "                            objects and of moved ones at their old place\n"
    "  --lookalikes-as-written   score the changes of look-alike objects (same class, mesh and\n"
    "                            size) as the ground truth writes them (default: read them\n"
    "                            the way that matches the reports best, see below)\n"
    "  --json                    print the scores as JSON (with --changes and --gt or\n"
    "                            --inventory: the change scores under \"changes\")\n"
    "Objects are matched per class (see docs/evaluation.md); the table has per class the real\n"
    "and mapped objects, true and false positives, misses, duplicates, merges, wrong labels,\n"
    "precision and recall.\n"
    "Changes are matched per kind and class: a report matches a real change within\n"
    "max(0.25 m, half the object's largest size when a ground truth gives it) of its place (a\n"
    "move: of both places), nearest pairs first. A move counts as having kept its id when one\n"
    "\"moved\" report matches it and the map still holds that object id; a move reported as a\n"
    "removal and an addition is a missed move, and the two reports are false positives.\n"
    "Look-alikes cannot be told apart but by their place: a cup removed and the same cup\n"
    "(mesh) added elsewhere is as well a move, and of two identical mugs, which one moved and\n"
    "which one arrived is not to be seen. Their changes are read with the places they emptied\n"
    "and filled paired into moves as the reports pair them, never into fewer moves than the\n"
    "ground truth has; the scores say how many groups were read so.\n";

constexpr int kOk = 0, kError = 1, kUsage = 2;

// The objects the map claims, from a directory or (gRPC builds) a server.
bool LoadMapped(const std::string& source, std::vector<MappedObject>* mapped, std::string* why) {
  std::error_code error;
  if (std::filesystem::is_directory(source, error)) return ReadMapDirectory(source, mapped, why);
#ifdef OBJMAP_CLI_WITH_SERVER
  if (source.find(':') != std::string::npos) {
    MapClient client(source);
    v1::QueryObjectsRequest request;
    request.set_include_model(true);
    v1::QueryObjectsResponse response;
    const grpc::Status status = client.QueryObjects(request, &response);
    if (!status.ok()) {
      *why = source + ": " + DescribeStatus(status);
      return false;
    }
    for (const v1::Object& object : response.objects()) {
      MappedObject& m = mapped->emplace_back();
      m.id = object.id();
      m.class_id = object.class_id();
      m.centroid_W = Vec3FromProto(object.centroid());
      m.min_W = Vec3FromProto(object.bounds().min());
      m.max_W = Vec3FromProto(object.bounds().max());
      std::vector<std::array<std::uint8_t, 3>> colors;
      if (!DecodeObjectModel(object, &m.model_W, &colors, why)) return false;
    }
    return true;
  }
#endif
  *why = source + ": not a folder" +
#ifdef OBJMAP_CLI_WITH_SERVER
         std::string(" nor a server address (host:port)");
#else
         std::string(" (this build has no server client)");
#endif
  return false;
}

// The OctoMap's .bt bytes: --octomap, else <map-dir>/map.bt, else the server's. Empty with no
// error when a map folder has none.
bool LoadOctomapBytes(const std::string& source, const std::string& octomap_path,
                      std::string* bytes, std::string* why) {
  std::error_code error;
  std::string path = octomap_path;
  if (path.empty() && std::filesystem::is_directory(source, error)) {
    path = (std::filesystem::path(source) / "map.bt").string();
    if (!std::filesystem::exists(path, error)) return true;
  }
  if (!path.empty()) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      *why = path + ": cannot be opened";
      return false;
    }
    std::ostringstream content;
    content << in.rdbuf();
    *bytes = content.str();
    return true;
  }
#ifdef OBJMAP_CLI_WITH_SERVER
  MapClient client(source);
  v1::GetOctomapRequest request;
  v1::GetOctomapResponse response;
  const grpc::Status status = client.GetOctomap(request, &response);
  if (!status.ok()) {
    *why = source + ": " + DescribeStatus(status);
    return false;
  }
  *bytes = response.bt();
#endif
  return true;
}

std::string Format(const char* format, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

void PrintTable(const std::map<int, ClassCounts>& per_class, const ClassCounts& totals) {
  std::printf("%-16s %5s %6s %4s %4s %4s %4s %6s %6s %9s %7s\n", "class", "real", "mapped", "TP",
              "FP", "FN", "dup", "merge", "label", "precision", "recall");
  auto row = [](const std::string& name, const ClassCounts& c) {
    std::printf("%-16s %5d %6d %4d %4d %4d %4d %6d %6d %9.3f %7.3f\n", name.c_str(), c.real,
                c.mapped, c.true_positives, c.false_positives, c.misses, c.duplicates, c.merges,
                c.wrong_labels, c.Precision(), c.Recall());
  };
  for (const auto& [class_id, counts] : per_class)
    row(std::string(CocoClassName(class_id)), counts);
  row("all", totals);
}

nlohmann::ordered_json CountsJson(const ClassCounts& c) {
  return {{"real", c.real},         {"mapped", c.mapped},
          {"tp", c.true_positives}, {"fp", c.false_positives},
          {"fn", c.misses},         {"duplicates", c.duplicates},
          {"merges", c.merges},     {"wrong_labels", c.wrong_labels},
          {"unseen", c.unseen},     {"precision", c.Precision()},
          {"recall", c.Recall()}};
}

nlohmann::ordered_json ScoresJson(const std::map<int, ClassCounts>& per_class,
                                  const ClassCounts& totals) {
  nlohmann::ordered_json classes = nlohmann::ordered_json::object();
  for (const auto& [class_id, counts] : per_class) {
    classes[std::string(CocoClassName(class_id))] = CountsJson(counts);
  }
  return {{"classes", classes}, {"all", CountsJson(totals)}};
}

nlohmann::ordered_json OccupancyJson(const OccupancyEvaluation& o) {
  return {{"voxel_size_m", o.voxel_size_m},
          {"occupied", o.occupied},
          {"occupied_on_surface", o.occupied_on_surface},
          {"occupied_near_surface", o.occupied_near_surface},
          {"occupied_precision", o.OccupiedPrecision()},
          {"structure_surface", o.structure_surface},
          {"structure_occupied", o.structure_occupied},
          {"structure_free", o.structure_free},
          {"structure_completeness", o.StructureCompleteness()},
          {"structure_free_share", o.StructureFreeShare()},
          {"object_surface", o.object_surface},
          {"object_free", o.object_free},
          {"object_free_share", o.ObjectFreeShare()}};
}

void PrintOccupancy(const OccupancyEvaluation& o) {
  std::printf(
      "OctoMap against the seen surface (%.0f mm voxels):\n"
      "  occupied voxels on a seen surface (within 1 voxel): %zu of %zu (%.1f %%; within 2: "
      "%.1f %%)\n"
      "  seen structure surface occupied (within 1 voxel):   %zu of %zu (%.1f %%)\n"
      "  seen structure surface mapped free:                 %zu (%.2f %%)\n"
      "  seen object surface mapped free:                    %zu of %zu (%.2f %%)\n",
      1000.0 * o.voxel_size_m, o.occupied_on_surface, o.occupied, 100.0 * o.OccupiedPrecision(),
      100.0 * (o.occupied == 0 ? 0.0 : static_cast<double>(o.occupied_near_surface) / o.occupied),
      o.structure_occupied, o.structure_surface, 100.0 * o.StructureCompleteness(),
      o.structure_free, 100.0 * o.StructureFreeShare(), o.object_free, o.object_surface,
      100.0 * o.ObjectFreeShare());
}

// The OctoMap scored against the ground truth's seen surface; nullopt (and no error) when either
// is missing.
bool ScoreOccupancy(const std::string& source, const std::string& octomap_path,
                    const std::string& gt_path, std::optional<OccupancyEvaluation>* result,
                    std::string* why) {
  SeenSurface surface;
  bool present = false;
  if (!ReadSeenSurface(gt_path, &surface, &present, why)) return false;
  if (!present) return true;
  std::string bytes;
  if (!LoadOctomapBytes(source, octomap_path, &bytes, why)) return false;
  if (bytes.empty()) return true;
  OccupancyConfig config;
  config.resolution_m = surface.voxel_size_m;
  OccupancyMap map(config);
  if (!map.ReadBinary(bytes, why)) {
    *why = (octomap_path.empty() ? source : octomap_path) + ": " + *why;
    return false;
  }
  *result = EvaluateOccupancy(map, surface);
  return true;
}

// Prints the scores as a table, or puts them into `*json` when it is not null.
int EvaluateWithGroundTruth(const std::vector<MappedObject>& mapped, const std::string& source,
                            const std::string& octomap_path, const std::string& gt_path,
                            nlohmann::ordered_json* json) {
  std::vector<GroundTruthObject> real;
  std::string why;
  std::optional<OccupancyEvaluation> occupancy;
  if (!ReadGroundTruth(gt_path, &real, &why) ||
      !ScoreOccupancy(source, octomap_path, gt_path, &occupancy, &why)) {
    std::cerr << "objmap eval: " << why << "\n";
    return kError;
  }
  const ObjectEvaluation evaluation = EvaluateObjects(real, mapped, EvaluationConfig{});
  if (json) {
    nlohmann::ordered_json document = ScoresJson(evaluation.per_class, evaluation.totals);
    nlohmann::ordered_json matches = nlohmann::ordered_json::array();
    for (const ObjectMatch& match : evaluation.matches) {
      matches.push_back({{"real_id", match.real_id},
                         {"mapped_id", match.mapped_id},
                         {"model_to_surface_m", match.model_to_surface_m},
                         {"surface_to_model_m", match.surface_to_model_m}});
    }
    document["matches"] = matches;
    document["mean_model_to_surface_m"] = evaluation.mean_model_to_surface_m;
    document["unknown_objects"] = {{"mapped", evaluation.unknown.mapped},
                                   {"on_real", evaluation.unknown.on_real},
                                   {"on_missed", evaluation.unknown.on_missed},
                                   {"missed_marked", evaluation.unknown.missed_marked}};
    if (occupancy) document["occupancy"] = OccupancyJson(*occupancy);
    *json = std::move(document);
    return kOk;
  }
  PrintTable(evaluation.per_class, evaluation.totals);
  if (evaluation.totals.unseen > 0) {
    std::cout << evaluation.totals.unseen
              << " object(s) of the ground truth were never in view and are not counted\n";
  }
  std::cout << "model accuracy (mean distance of model points to the real surface): "
            << (evaluation.mean_model_to_surface_m < 0.0
                    ? std::string("n/a (no models or no surface samples)")
                    : Format("%.2f cm", 100.0 * evaluation.mean_model_to_surface_m))
            << " over " << evaluation.matches.size() << " matched objects\n";
  if (evaluation.unknown.mapped > 0) {
    std::cout << "unknown objects (segmented, never named; not counted above): "
              << evaluation.unknown.mapped << ", " << evaluation.unknown.on_real
              << " on a real object, " << evaluation.unknown.on_missed
              << " on one the named objects missed; " << evaluation.unknown.missed_marked
              << " missed object(s) marked by one\n";
  }
  if (occupancy) PrintOccupancy(*occupancy);
  return kOk;
}

int EvaluateWithCounts(const std::vector<MappedObject>& mapped, const std::string& counts_path,
                       nlohmann::ordered_json* json) {
  std::map<int, CountRange> expected;
  std::string why;
  if (!ReadExpectedCounts(counts_path, &expected, &why)) {
    std::cerr << "objmap eval: " << why << "\n";
    return kError;
  }
  std::map<int, int> found;
  for (const MappedObject& object : mapped) {
    if (object.class_id != kUnknownClassId) ++found[object.class_id];  // no count to match
  }
  const std::map<int, ClassCounts> per_class = ScoreCounts(expected, found);
  ClassCounts totals;
  for (const auto& [class_id, counts] : per_class) totals.Add(counts);
  if (json) {
    *json = ScoresJson(per_class, totals);
  } else {
    PrintTable(per_class, totals);
    std::cout << "(scored by counts: `real` is the expected count nearest to the mapped one)\n";
  }
  return kOk;
}

// The files of a change evaluation, as the command line names them.
struct ChangeInputs {
  std::string map_dir;
  std::string changes_path;
  std::string gt_before_path;  ///< may be empty
  std::string gt_after_path;   ///< may be empty
  std::int64_t since_session = 0;
  bool lookalikes_as_written = false;
};

// Reads a ground-truth file when one is named; none leaves `objects` empty.
bool ReadOptionalGroundTruth(const std::string& path, std::vector<GroundTruthObject>* objects,
                             std::string* why) {
  return path.empty() || ReadGroundTruth(path, objects, why);
}

nlohmann::ordered_json ChangeCountsJson(const ChangeCounts& c) {
  return {{"real", c.real},
          {"reported", c.reported},
          {"tp", c.true_positives},
          {"fp", c.false_positives},
          {"fn", c.misses},
          {"unseen", c.unseen},
          {"unknown_class", c.unknown_class},
          {"precision", c.Precision()},
          {"recall", c.Recall()}};
}

nlohmann::ordered_json ChangesJson(const ChangeEvaluation& e, std::int64_t since_session,
                                   bool ids_checked) {
  nlohmann::ordered_json document;
  document["since_session"] =
      since_session > 0 ? nlohmann::ordered_json(since_session) : nlohmann::ordered_json();
  for (ChangeKind kind : kChangeKinds) {
    document[std::string(ChangeKindName(kind))] = ChangeCountsJson(e.Of(kind));
  }
  document["all"] = ChangeCountsJson(e.totals);
  document["moved_kept_id"] = e.moved_kept_id;
  document["moved_total"] = e.moved_total;
  document["moved_as_removed_and_added"] = e.moved_as_removed_and_added;
  document["lookalike_groups_reread"] = e.lookalike_groups_reread;
  document["ids_checked"] = ids_checked;
  nlohmann::ordered_json matches = nlohmann::ordered_json::array();
  for (const ChangeMatch& match : e.matches) {
    nlohmann::ordered_json entry = {{"kind", std::string(ChangeKindName(match.kind))},
                                    {"real_id", match.real_id},
                                    {"object_id", match.object_id}};
    if (match.kind == ChangeKind::kMoved) entry["kept_id"] = match.kept_id;
    matches.push_back(entry);
  }
  document["matches"] = matches;
  return document;
}

void PrintChanges(const ChangeEvaluation& e, std::int64_t since_session, bool ids_checked) {
  std::printf("change detection (map reports of %s):\n",
              since_session > 0 ? ("sessions >= " + std::to_string(since_session)).c_str()
                                : "every session");
  std::printf("%-8s %5s %8s %4s %4s %4s %9s %7s\n", "kind", "real", "reported", "TP", "FP", "FN",
              "precision", "recall");
  auto row = [](const std::string& name, const ChangeCounts& c) {
    std::printf("%-8s %5d %8d %4d %4d %4d %9.3f %7.3f\n", name.c_str(), c.real, c.reported,
                c.true_positives, c.false_positives, c.misses, c.Precision(), c.Recall());
  };
  for (ChangeKind kind : kChangeKinds) row(std::string(ChangeKindName(kind)), e.Of(kind));
  row("all", e.totals);
  std::printf("moved objects that kept their id: %d of %d%s\n", e.moved_kept_id, e.moved_total,
              ids_checked ? "" : " (ids not checked: the map folder has no objects.json)");
  if (e.moved_as_removed_and_added > 0) {
    std::printf("moves reported as a removal and an addition (missed moves): %d\n",
                e.moved_as_removed_and_added);
  }
  if (e.lookalike_groups_reread > 0) {
    std::printf(
        "groups of look-alike objects whose changes were read as the reports pair them: "
        "%d\n",
        e.lookalike_groups_reread);
  }
  if (e.totals.unseen > 0) {
    std::printf("%d real change(s) of objects the second session never showed are not counted\n",
                e.totals.unseen);
  }
  if (e.totals.unknown_class > 0) {
    std::printf("%d report(s) of objects of class unknown are not counted\n",
                e.totals.unknown_class);
  }
}

// The objects the map folder claims now, for the check of kept ids: `loaded` when the caller
// loaded them already, else objects.json when the folder has one; null when it has none.
bool PresentObjects(const std::string& map_dir, const std::vector<MappedObject>* loaded,
                    std::vector<MappedObject>* read, const std::vector<MappedObject>** present,
                    std::string* why) {
  *present = loaded;
  std::error_code error;
  if (loaded != nullptr ||
      !std::filesystem::exists(std::filesystem::path(map_dir) / "objects.json", error)) {
    return true;
  }
  if (!ReadMapDirectory(map_dir, read, why)) return false;
  *present = read;
  return true;
}

// --since-session needs every report's session: one without would be left out unseen.
bool SessionsKnown(const std::vector<ReportedChange>& reported, const std::string& path,
                   std::string* why) {
  for (std::size_t i = 0; i < reported.size(); ++i) {
    if (reported[i].session_id < 0) {
      *why = path + ": changes[" + std::to_string(i) +
             "]: \"session_id\" is missing, which --since-session needs";
      return false;
    }
  }
  return true;
}

int EvaluateChangeDetection(const ChangeInputs& inputs, const std::vector<MappedObject>* loaded,
                            nlohmann::ordered_json* json) {
  std::string why;
  std::error_code error;
  if (!std::filesystem::is_directory(inputs.map_dir, error)) {
    std::cerr << "objmap eval: " << inputs.map_dir
              << ": not a folder (--changes scores a folder written by `objmap map --map`)\n";
    return kError;
  }
  ChangeEvaluationConfig config;
  config.min_session_id = inputs.since_session;
  config.lookalikes_interchangeable = !inputs.lookalikes_as_written;
  std::vector<ReportedChange> reported;
  std::vector<GroundTruthChange> real;
  std::vector<GroundTruthObject> before, after;
  std::vector<MappedObject> read;
  const std::vector<MappedObject>* present = nullptr;
  const std::string reported_path =
      (std::filesystem::path(inputs.map_dir) / "changes.json").string();
  if (!config.IsValid(&why) || !ReadReportedChanges(reported_path, &reported, &why) ||
      (inputs.since_session > 0 && !SessionsKnown(reported, reported_path, &why)) ||
      !ReadGroundTruthChanges(inputs.changes_path, &real, &why) ||
      !ReadOptionalGroundTruth(inputs.gt_before_path, &before, &why) ||
      !ReadOptionalGroundTruth(inputs.gt_after_path, &after, &why) ||
      !PresentObjects(inputs.map_dir, loaded, &read, &present, &why)) {
    std::cerr << "objmap eval: " << why << "\n";
    return kError;
  }
  const std::vector<int> not_found = AttachGroundTruthSizes(before, after, &real);
  if (!not_found.empty()) {
    // Likely the wrong file; the score is still meaningful, with the distance floor for those.
    std::cerr << "objmap eval: warning: " << not_found.size() << " object(s) of "
              << inputs.changes_path << " are missing from the ground truth given (first id "
              << not_found.front() << "); their match distance is the floor\n";
  }
  const ChangeEvaluation evaluation = EvaluateChanges(real, reported, present, config);
  if (json) {
    *json = ChangesJson(evaluation, inputs.since_session, present != nullptr);
  } else {
    PrintChanges(evaluation, inputs.since_session, present != nullptr);
  }
  return kOk;
}

}  // namespace

int RunEvalCommand(int argc, char** argv) {
  Arguments args(
      argc, argv,
      {"--gt", "--inventory", "--octomap", "--changes", "--gt-before", "--since-session"},
      {"--json", "--help", "--lookalikes-as-written"});
  if (args.Has("--help")) {
    std::cout << kEvalUsage;
    return kOk;
  }
  const bool changes = args.Has("--changes");
  const bool objects = args.Has("--gt") || args.Has("--inventory");
  const std::int64_t since_session = args.GetInteger("--since-session", 0, 1);
  if (!args.error().empty() || args.positional().size() != 1 ||
      (args.Has("--gt") && args.Has("--inventory")) || (!objects && !changes) ||
      (!changes && (args.Has("--gt-before") || args.Has("--since-session") ||
                    args.Has("--lookalikes-as-written")))) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << kEvalUsage;
    return kUsage;
  }
  const std::string& source = args.positional()[0];
  const bool json = args.Has("--json");
  nlohmann::ordered_json object_scores, change_scores;
  std::vector<MappedObject> mapped;
  if (objects) {
    std::string why;
    if (!LoadMapped(source, &mapped, &why)) {
      std::cerr << "objmap eval: " << why << "\n";
      return kError;
    }
    const int code = args.Has("--gt") ? EvaluateWithGroundTruth(
                                            mapped, source, args.Get("--octomap", ""),
                                            args.Get("--gt", ""), json ? &object_scores : nullptr)
                                      : EvaluateWithCounts(mapped, args.Get("--inventory", ""),
                                                           json ? &object_scores : nullptr);
    if (code != kOk) return code;
  }
  if (changes) {
    if (objects && !json) std::cout << "\n";
    const ChangeInputs inputs{source,
                              args.Get("--changes", ""),
                              args.Get("--gt-before", ""),
                              args.Get("--gt", ""),
                              since_session,
                              args.Has("--lookalikes-as-written")};
    const int code = EvaluateChangeDetection(inputs, objects ? &mapped : nullptr,
                                             json ? &change_scores : nullptr);
    if (code != kOk) return code;
  }
  if (json) {
    if (objects && changes) object_scores["changes"] = std::move(change_scores);
    std::cout << (objects ? object_scores : change_scores).dump(2) << "\n";
  }
  return kOk;
}

}  // namespace objmap::cli
