// `objmap eval`: a map scored against ground truth (object poses) or expected counts per class.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "arguments.h"
#include "commands.h"
#include "evaluation/evaluation.h"
#include "evaluation/evaluation_io.h"
#include "types/coco_classes.h"
#ifdef OBJMAP_CLI_WITH_SERVER
#include "objmap/conversions.h"
#include "server_common.h"
#endif

namespace objmap::cli {
namespace {

constexpr char kEvalUsage[] =
    "usage: objmap eval <map-dir | ADDR> (--gt ground_truth.json | --inventory counts.json)\n"
    "  <map-dir>                 folder written by `objmap map --out` or `objmap export\n"
    "                            --objects` (objects.json and the .ply models)\n"
    "  ADDR                      host:port of a running objmap_server (its inventory objects)\n"
    "  --gt FILE                 real objects with poses, sizes and surface samples\n"
    "  --inventory FILE          expected count per class: {\"chair\": 4, \"tv\": [1, 2]}\n"
    "  --json                    print the scores as JSON\n"
    "Objects are matched per class (see docs/evaluation.md); the table has per class the real\n"
    "and mapped objects, true and false positives, misses, duplicates, merges, wrong labels,\n"
    "precision and recall.\n";

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
  return {{"real", c.real},
          {"mapped", c.mapped},
          {"tp", c.true_positives},
          {"fp", c.false_positives},
          {"fn", c.misses},
          {"duplicates", c.duplicates},
          {"merges", c.merges},
          {"wrong_labels", c.wrong_labels},
          {"precision", c.Precision()},
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

int EvaluateWithGroundTruth(const std::vector<MappedObject>& mapped, const std::string& gt_path,
                            bool json) {
  std::vector<GroundTruthObject> real;
  std::string why;
  if (!ReadGroundTruth(gt_path, &real, &why)) {
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
    std::cout << document.dump(2) << "\n";
    return kOk;
  }
  PrintTable(evaluation.per_class, evaluation.totals);
  std::cout << "model accuracy (mean distance of model points to the real surface): "
            << (evaluation.mean_model_to_surface_m < 0.0
                    ? std::string("n/a (no models or no surface samples)")
                    : Format("%.2f cm", 100.0 * evaluation.mean_model_to_surface_m))
            << " over " << evaluation.matches.size() << " matched objects\n";
  return kOk;
}

int EvaluateWithCounts(const std::vector<MappedObject>& mapped, const std::string& counts_path,
                       bool json) {
  std::map<int, CountRange> expected;
  std::string why;
  if (!ReadExpectedCounts(counts_path, &expected, &why)) {
    std::cerr << "objmap eval: " << why << "\n";
    return kError;
  }
  std::map<int, int> found;
  for (const MappedObject& object : mapped) ++found[object.class_id];
  const std::map<int, ClassCounts> per_class = ScoreCounts(expected, found);
  ClassCounts totals;
  for (const auto& [class_id, counts] : per_class) totals.Add(counts);
  if (json) {
    std::cout << ScoresJson(per_class, totals).dump(2) << "\n";
  } else {
    PrintTable(per_class, totals);
    std::cout << "(scored by counts: `real` is the expected count nearest to the mapped one)\n";
  }
  return kOk;
}

}  // namespace

int RunEvalCommand(int argc, char** argv) {
  Arguments args(argc, argv, {"--gt", "--inventory"}, {"--json", "--help"});
  if (args.Has("--help")) {
    std::cout << kEvalUsage;
    return kOk;
  }
  if (!args.error().empty() || args.positional().size() != 1 ||
      args.Has("--gt") == args.Has("--inventory")) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << kEvalUsage;
    return kUsage;
  }
  std::vector<MappedObject> mapped;
  std::string why;
  if (!LoadMapped(args.positional()[0], &mapped, &why)) {
    std::cerr << "objmap eval: " << why << "\n";
    return kError;
  }
  const bool json = args.Has("--json");
  return args.Has("--gt") ? EvaluateWithGroundTruth(mapped, args.Get("--gt", ""), json)
                          : EvaluateWithCounts(mapped, args.Get("--inventory", ""), json);
}

}  // namespace objmap::cli
