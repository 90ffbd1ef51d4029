// `objmap sessions`: the runs of keyframes a server's map holds, and `--start NAME` to open a new
// one (a robot's next run into the same map).
#include <cstdio>
#include <ctime>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kSessionsUsage[] =
    "objmap sessions: lists the sessions (runs of keyframes) of a running server's map.\n"
    "usage: objmap sessions [options]\n"
    "  --start NAME              end the current session and start a new one named NAME (\"\":\n"
    "                            \"session N\"); with estimated poses the server then places the\n"
    "                            next keyframe in the saved map by relocalisation\n"
    "  --json                    print JSON instead of a table\n";

constexpr char kCommand[] = "sessions";

// Local time as "2026-12-06 07:30:46", or "-" when not known.
std::string WallTime(bool known, double seconds) {
  if (!known) return "-";
  const std::time_t time = static_cast<std::time_t>(seconds);
  std::tm local{};
  localtime_r(&time, &local);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%S", &local);
  return text;
}

nlohmann::json SessionJson(const v1::Session& session) {
  nlohmann::json json = {{"id", session.id()},
                         {"name", session.name()},
                         {"pose_source", session.pose_source()},
                         {"keyframes", session.keyframes()},
                         {"revisits", session.revisits()},
                         {"current", session.current()}};
  json["started_s"] = session.has_started() ? nlohmann::json(session.started_s()) : nullptr;
  json["ended_s"] = session.has_ended() ? nlohmann::json(session.ended_s()) : nullptr;
  if (session.keyframes() > 0) {
    json["first_keyframe_id"] = session.first_keyframe_id();
    json["last_keyframe_id"] = session.last_keyframe_id();
    json["first_stamp"] = session.first_stamp();
    json["last_stamp"] = session.last_stamp();
  }
  return json;
}

void PrintTable(const v1::ListSessionsResponse& response) {
  std::printf("%4s  %-24s %-9s %-19s  %-19s  %9s  %8s  %s\n", "id", "name", "poses", "started",
              "ended", "keyframes", "revisits", "ids");
  for (const v1::Session& session : response.sessions()) {
    const std::string ids = session.keyframes() > 0
                                ? std::to_string(session.first_keyframe_id()) + ".." +
                                      std::to_string(session.last_keyframe_id())
                                : "-";
    std::printf(
        "%4lld  %-24s %-9s %-19s  %-19s  %9lld  %8lld  %s%s\n",
        static_cast<long long>(session.id()), session.name().c_str(),
        session.pose_source().empty() ? "-" : session.pose_source().c_str(),
        WallTime(session.has_started(), session.started_s()).c_str(),
        session.current() ? "(current)" : WallTime(session.has_ended(), session.ended_s()).c_str(),
        static_cast<long long>(session.keyframes()), static_cast<long long>(session.revisits()),
        ids.c_str(), session.current() ? "  *" : "");
  }
}

}  // namespace

int RunSessionsCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({"--start"}), {"--json", "--help"});
  const std::string usage = std::string(kSessionsUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  if (args.Has("--start")) {
    v1::StartSessionRequest request;
    request.set_name(args.Get("--start", ""));
    v1::Session started;
    const grpc::Status status = client->StartSession(request, &started);
    if (!status.ok()) return FailWithStatus(kCommand, status);
    if (args.Has("--json")) {
      std::cout << SessionJson(started).dump(2) << "\n";
    } else {
      std::cout << "started session " << started.id() << " \"" << started.name() << "\"\n";
    }
    return kExitOk;
  }
  v1::ListSessionsResponse response;
  const grpc::Status status = client->ListSessions(v1::ListSessionsRequest(), &response);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  if (args.Has("--json")) {
    nlohmann::json json = {{"current_session_id", response.current_session_id()},
                           {"sessions", nlohmann::json::array()}};
    for (const v1::Session& session : response.sessions()) {
      json["sessions"].push_back(SessionJson(session));
    }
    std::cout << json.dump(2) << "\n";
  } else {
    PrintTable(response);
  }
  return kExitOk;
}

}  // namespace objmap::cli
