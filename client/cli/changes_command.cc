// `objmap changes`: what changed in a running server's map: objects added (put where earlier
// views saw nothing), removed (their place seen empty since) and moved (one id, both places).
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kChangesUsage[] =
    "objmap changes: objects added, removed and moved in a running server's map.\n"
    "usage: objmap changes [options]\n"
    "  --since-version V         changes first listed after map version V\n"
    "  --since-session S         changes seen in session S or later\n"
    "  --since-stamp T           changes whose keyframe's camera stamp is >= T seconds\n"
    "  --json                    print JSON instead of a table\n";

constexpr char kCommand[] = "changes";

const char* KindName(v1::ObjectChange::Kind kind) {
  switch (kind) {
    case v1::ObjectChange::ADDED:
      return "added";
    case v1::ObjectChange::REMOVED:
      return "removed";
    case v1::ObjectChange::MOVED:
      return "moved";
    default:
      return "?";
  }
}

nlohmann::json Vec3Json(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json ChangeJson(const v1::ObjectChange& change) {
  nlohmann::json json = {{"kind", KindName(change.kind())},
                         {"object_id", change.object_id()},
                         {"class", change.class_name()},
                         {"keyframe_id", change.seen().keyframe_id()},
                         {"session_id", change.seen().session_id()},
                         {"stamp", change.seen().stamp()},
                         {"map_version", change.map_version()},
                         {"position", Vec3Json(change.position())},
                         {"min", Vec3Json(change.bounds().min())},
                         {"max", Vec3Json(change.bounds().max())}};
  if (change.kind() == v1::ObjectChange::MOVED) json["from"] = Vec3Json(change.from());
  return json;
}

void PrintTable(const v1::ListChangesResponse& response) {
  std::printf("%-8s %6s  %-14s %7s %8s  %-26s %s\n", "change", "id", "class", "session", "keyframe",
              "where (m)", "from (m)");
  for (const v1::ObjectChange& change : response.changes()) {
    char where[64], from[64] = "";
    std::snprintf(where, sizeof(where), "%.2f %.2f %.2f", change.position().x(),
                  change.position().y(), change.position().z());
    if (change.kind() == v1::ObjectChange::MOVED) {
      std::snprintf(from, sizeof(from), "%.2f %.2f %.2f", change.from().x(), change.from().y(),
                    change.from().z());
    }
    std::printf("%-8s %6lld  %-14s %7lld %8lld  %-26s %s\n", KindName(change.kind()),
                static_cast<long long>(change.object_id()), change.class_name().c_str(),
                static_cast<long long>(change.seen().session_id()),
                static_cast<long long>(change.seen().keyframe_id()), where, from);
  }
  std::printf("%d change(s), map version %llu\n", response.changes_size(),
              static_cast<unsigned long long>(response.map_version()));
}

}  // namespace

int RunChangesCommand(int argc, char** argv) {
  Arguments args(argc, argv,
                 WithServerFlags({"--since-version", "--since-session", "--since-stamp"}),
                 {"--json", "--help"});
  const std::string usage = std::string(kChangesUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  v1::ListChangesRequest request;
  if (args.Has("--since-version")) {
    const double version = args.GetNumber("--since-version", 0);
    if (version < 0) args.SetError("--since-version must be >= 0");
    request.set_since_version(static_cast<std::uint64_t>(version));
  }
  if (args.Has("--since-session")) {
    request.set_since_session(static_cast<std::int64_t>(args.GetNumber("--since-session", 0)));
  }
  if (args.Has("--since-stamp")) request.set_since_stamp(args.GetNumber("--since-stamp", 0));
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  v1::ListChangesResponse response;
  const grpc::Status status = client->ListChanges(request, &response);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  if (args.Has("--json")) {
    nlohmann::json json = {{"map_version", response.map_version()},
                           {"changes", nlohmann::json::array()}};
    for (const v1::ObjectChange& change : response.changes()) {
      json["changes"].push_back(ChangeJson(change));
    }
    std::cout << json.dump(2) << "\n";
  } else {
    PrintTable(response);
  }
  return kExitOk;
}

}  // namespace objmap::cli
