// `objmap free`: whether a box holds no occupied (and, by default, no unknown) space.
#include <iostream>

#include "commands.h"
#include "objmap/conversions.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kFreeUsage[] =
    "objmap free: asks a running server whether a box is free space (exit 0) or not (exit 3).\n"
    "usage: objmap free X0 Y0 Z0 X1 Y1 Z1 [options]\n"
    "  X0 Y0 Z0 X1 Y1 Z1         the box's min and max corners in the map frame, metres\n"
    "  --unknown-is-free         unknown space counts as free (default: it does not)\n"
    "exit code: 0 free, 3 not free, 1 server error, 2 bad arguments\n";

constexpr int kExitNotFree = 3;

}  // namespace

int RunFreeCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({}), {"--unknown-is-free", "--help"});
  const std::string usage = std::string(kFreeUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  static const char* kCorners[] = {"X0", "Y0", "Z0", "X1", "Y1", "Z1"};
  double corners[6];
  for (int k = 0; k < 6; ++k) corners[k] = args.PositionalNumber(k, kCorners[k]);
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || args.positional().size() != 6) return UsageError(args, usage);

  v1::IsFreeRequest request;
  *request.mutable_region() =
      BoxToProto({corners[0], corners[1], corners[2]}, {corners[3], corners[4], corners[5]});
  request.set_unknown_is_free(args.Has("--unknown-is-free"));
  v1::IsFreeResponse response;
  const grpc::Status status = client->IsFree(request, &response);
  if (!status.ok()) return FailWithStatus("free", status);
  if (response.free()) {
    std::cout << "free\n";
    return kExitOk;
  }
  std::cout << "not free (occupied " << response.occupied() << ", unknown " << response.unknown();
  if (response.object_ids_size() > 0) {
    std::cout << ", objects";
    for (std::int64_t id : response.object_ids()) std::cout << " " << id;
  }
  std::cout << ")\n";
  return kExitNotFree;
}

}  // namespace objmap::cli
