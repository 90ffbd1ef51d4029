// `objmap update-poses`: corrected keyframe poses (from a pose-graph back end) for the server.
#include <iostream>

#include "commands.h"
#include "objmap/conversions.h"
#include "poses_file.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kUpdatePosesUsage[] =
    "objmap update-poses: sends corrected keyframe poses (a loop closure) to a running server,\n"
    "which regenerates its map.\n"
    "usage: objmap update-poses <poses.txt> [options]\n"
    "  <poses.txt>               lines \"keyframe_id tx ty tz qx qy qz qw\" (T_W_C, TUM order);\n"
    "                            '#' starts a comment\n"
    "  --wait                    return once the map has been regenerated with the new poses\n"
    "                            (the deadline is then 600 s unless --timeout says otherwise)\n";

// Regenerating a large map takes minutes; --wait gets a deadline to match.
constexpr double kWaitTimeoutS = 600.0;

}  // namespace

int RunUpdatePosesCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({}), {"--wait", "--help"});
  const std::string usage = std::string(kUpdatePosesUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  const bool wait = args.Has("--wait");
  std::unique_ptr<MapClient> client = MakeClient(args, wait ? kWaitTimeoutS : 30.0);
  if (!args.error().empty() || args.positional().size() != 1) return UsageError(args, usage);

  std::vector<KeyframePoseLine> poses;
  std::string why;
  if (!ReadPosesFile(args.positional()[0], &poses, &why)) return Fail("update-poses", why);
  v1::UpdatePosesRequest request;
  request.set_wait(wait);
  for (const KeyframePoseLine& pose : poses) {
    v1::KeyframePose* out = request.add_poses();
    out->set_keyframe_id(pose.keyframe_id);
    *out->mutable_t_w_c() = PoseToProto(pose.T_W_C);
  }
  v1::UpdatePosesResponse response;
  const grpc::Status status = client->UpdatePoses(request, &response);
  if (!status.ok()) return FailWithStatus("update-poses", status);
  // Without --wait the server answers once the poses are stored, before it knows which moved.
  if (response.regenerated()) {
    std::cout << "map version " << response.map_version() << ": " << response.keyframes_moved()
              << " of " << poses.size() << " keyframes moved; ";
    if (response.reassociated()) {
      std::cout << "objects re-associated (" << response.objects_before() << " -> "
                << response.objects_after() << "), ";
    }
    std::cout << "regenerated in " << response.regeneration_ms() << " ms\n";
  } else {
    std::cout << "map version " << response.map_version() << ": " << poses.size()
              << " poses stored; regeneration queued (`objmap status` shows when it is done)\n";
  }
  return kExitOk;
}

}  // namespace objmap::cli
