// `objmap inventory`: how many objects of each class the map holds.
#include <iomanip>
#include <iostream>

#include "commands.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kInventoryUsage[] =
    "objmap inventory: prints a running server's objects per class.\n"
    "usage: objmap inventory [options]\n"
    "  --since VERSION           only classes with an object added, changed or removed after\n"
    "                            this map version (a class whose last object went shows count 0)\n"
    "  --json                    print JSON instead of a table\n";

Json InventoryJson(const v1::InventoryResponse& response) {
  Json entries = Json::array();
  for (const v1::InventoryEntry& entry : response.entries()) {
    entries.push_back({{"class", entry.class_name()},
                       {"class_id", entry.class_id()},
                       {"count", entry.count()},
                       {"mean_confidence", Rounded(entry.mean_confidence())},
                       {"object_ids", std::vector<std::int64_t>(entry.object_ids().begin(),
                                                                entry.object_ids().end())}});
  }
  return {{"map_version", response.map_version()}, {"inventory", entries}};
}

void PrintTable(const v1::InventoryResponse& response) {
  std::cout << "map version " << response.map_version() << "\n";
  std::cout << std::left << std::setw(16) << "class" << std::right << std::setw(6) << "count"
            << std::setw(12) << "confidence"
            << "\n";
  for (const v1::InventoryEntry& entry : response.entries()) {
    std::cout << std::left << std::setw(16) << entry.class_name() << std::right << std::setw(6)
              << entry.count() << std::setw(12) << std::fixed << std::setprecision(3)
              << entry.mean_confidence() << "\n";
  }
}

}  // namespace

int RunInventoryCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({"--since"}), {"--json", "--help"});
  const std::string usage = std::string(kInventoryUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  v1::InventoryRequest request;
  const std::int64_t since = args.GetInteger("--since", 0, 0);
  if (args.Has("--since")) request.set_since_version(static_cast<std::uint64_t>(since));
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  v1::InventoryResponse response;
  const grpc::Status status = client->Inventory(request, &response);
  if (!status.ok()) return FailWithStatus("inventory", status);
  if (args.Has("--json")) {
    std::cout << InventoryJson(response).dump(2) << "\n";
  } else {
    PrintTable(response);
  }
  return kExitOk;
}

}  // namespace objmap::cli
