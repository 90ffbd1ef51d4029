// `objmap status`: the state of a running server.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kStatusUsage[] =
    "objmap status: prints a running server's map version, counts, queue and database.\n"
    "usage: objmap status [options]\n";

std::string Regeneration(const v1::StatusResponse& status) {
  char text[128];
  if (status.regenerating()) return "running";
  if (status.last_regeneration_version() == 0) return "idle (none yet)";
  std::snprintf(text, sizeof(text), "idle (last took %.1f ms, for version %llu)",
                status.last_regeneration_ms(),
                static_cast<unsigned long long>(status.last_regeneration_version()));
  return text;
}

std::string Checkpoint(const v1::StatusResponse& status) {
  if (status.checkpoint_version() == 0) return "none";
  std::string text = "OctoMap of version " + std::to_string(status.checkpoint_version());
  // Zero when this run has not saved one yet (it was loaded at start).
  if (status.last_checkpoint_ms() > 0.0) {
    text += " (saved in " + std::to_string(std::lround(status.last_checkpoint_ms())) + " ms)";
  }
  return text;
}

std::string Startup(const v1::StatusResponse& status) {
  char text[128];
  std::snprintf(text, sizeof(text), "%.1f s, %d keyframes integrated into the OctoMap",
                status.startup_ms() / 1000.0, status.startup_keyframes_integrated());
  return text;
}

std::string OctomapMemory(const v1::StatusResponse& status) {
  char text[96];
  std::snprintf(text, sizeof(text), "%.1f MiB in memory, %s",
                static_cast<double>(status.occupancy_bytes()) / (1024.0 * 1024.0),
                status.occupancy_copies() == 2 ? "kept twice (queries never wait for writes)"
                                               : "one copy");
  return text;
}

std::string Duration(double seconds) {
  const long long total = static_cast<long long>(seconds);
  char text[64];
  std::snprintf(text, sizeof(text), "%lldh %02lldm %02llds", total / 3600, total / 60 % 60,
                total % 60);
  return text;
}

}  // namespace

int RunStatusCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({}), {"--help"});
  const std::string usage = std::string(kStatusUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  v1::StatusResponse status;
  const grpc::Status rpc = client->Status(v1::StatusRequest(), &status);
  if (!rpc.ok()) return FailWithStatus("status", rpc);
  char database_mib[32];
  std::snprintf(database_mib, sizeof(database_mib), "%.1f MiB",
                static_cast<double>(status.database_bytes()) / (1024.0 * 1024.0));
  std::cout << "server:        " << client->address() << "\n"
            << "map version:   " << status.map_version() << "\n"
            << "keyframes:     " << status.keyframes() << "\n"
            << "session:       " << status.session_id() << " \"" << status.session_name()
            << "\"\n"
            << "objects:       " << status.objects() << " (" << status.confirmed_objects()
            << " in the inventory)\n"
            << "ingest queue:  " << status.ingest_queue() << "\n"
            << "regeneration:  " << Regeneration(status) << "\n"
            << "database:      " << status.database() << " (" << database_mib << ")\n"
            << "octomap:       " << OctomapMemory(status) << "\n"
            << "checkpoint:    " << Checkpoint(status) << "\n"
            << "startup:       " << Startup(status) << "\n"
            << "uptime:        " << Duration(status.uptime_s()) << "\n";
  return kExitOk;
}

}  // namespace objmap::cli
