// `objmap objects`: the objects that match a class, a region, a confidence, sorted by id or by
// distance to a point.
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "objmap/conversions.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kObjectsUsage[] =
    "objmap objects: lists a running server's objects by class, region or distance.\n"
    "usage: objmap objects [options]\n"
    "  --class NAME              only this COCO class (\"cup\", \"dining table\")\n"
    "  --region X0 Y0 Z0 X1 Y1 Z1  only objects whose centroid lies in this box, metres\n"
    "  --near X Y Z              sort by centroid distance to this point (default: by id)\n"
    "  --min-confidence C        only objects at least this confident\n"
    "  --all                     also objects that do not (yet) pass the inventory thresholds\n"
    "  --limit N                 at most N objects (default: all)\n"
    "  --json                    print a JSON array instead of a table\n";

// Fills the request from the options; argument errors are left in `args`.
v1::QueryObjectsRequest RequestFrom(Arguments& args) {
  v1::QueryObjectsRequest request;
  request.set_class_name(args.Get("--class", ""));
  const std::vector<double> region = args.GetNumbers("--region");
  if (region.size() == 6) {
    *request.mutable_region() =
        BoxToProto({region[0], region[1], region[2]}, {region[3], region[4], region[5]});
  }
  const std::vector<double> near = args.GetNumbers("--near");
  if (near.size() == 3)
    *request.mutable_nearest_to() = Vec3ToProto(Eigen::Vector3d(near[0], near[1], near[2]));
  request.set_min_confidence(static_cast<float>(args.GetNumber("--min-confidence", 0.0)));
  request.set_max_results(static_cast<std::int32_t>(args.GetInteger("--limit", 0, 0)));
  request.set_include_unconfirmed(args.Has("--all"));
  return request;
}

void PrintTable(const v1::QueryObjectsResponse& response) {
  std::printf("%-8s %-16s %10s  %-30s %12s  %s\n", "id", "class", "confidence", "centroid (m)",
              "observations", "seen in sessions");
  for (const v1::Object& object : response.objects()) {
    const std::string sessions =
        !object.has_first_seen() ? "-"
        : object.first_seen().session_id() == object.last_seen().session_id()
            ? std::to_string(object.first_seen().session_id())
            : std::to_string(object.first_seen().session_id()) + ".." +
                  std::to_string(object.last_seen().session_id());
    std::printf("%-8lld %-16s %10.3f  %-30s %12d  %s\n", static_cast<long long>(object.id()),
                object.class_name().c_str(), object.confidence(),
                FormatPoint(object.centroid()).c_str(), object.observations(), sessions.c_str());
  }
}

}  // namespace

int RunObjectsCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({"--class", "--min-confidence", "--limit"}),
                 {"--all", "--json", "--help"}, {{"--region", 6}, {"--near", 3}});
  const std::string usage = std::string(kObjectsUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  const v1::QueryObjectsRequest request = RequestFrom(args);
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  v1::QueryObjectsResponse response;
  const grpc::Status status = client->QueryObjects(request, &response);
  if (!status.ok()) return FailWithStatus("objects", status);
  if (args.Has("--json")) {
    Json objects = Json::array();
    for (const v1::Object& object : response.objects()) objects.push_back(ObjectJson(object));
    std::cout << objects.dump(2) << "\n";
  } else {
    PrintTable(response);
  }
  return kExitOk;
}

}  // namespace objmap::cli
