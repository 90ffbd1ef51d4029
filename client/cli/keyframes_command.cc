// `objmap keyframes`: the stored keyframes with their current poses, in the poses-file format
// that `objmap update-poses` reads, so that poses can be exported, optimized and sent back.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>

#include "commands.h"
#include "objmap/conversions.h"
#include "poses_file.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kKeyframesUsage[] =
    "objmap keyframes: lists a running server's keyframes and their current poses.\n"
    "usage: objmap keyframes [options]\n"
    "  --first-id N              keyframes with id >= N (default: all)\n"
    "  --limit N                 at most N keyframes (default: all)\n"
    "  --out FILE                write to FILE instead of standard output\n"
    "Prints one line per keyframe, `id tx ty tz qx qy qz qw  # name stamp`: T_W_C (camera to\n"
    "world) in the format of `objmap update-poses`.\n";

constexpr char kCommand[] = "keyframes";

void WriteKeyframes(const v1::ListKeyframesResponse& response, std::ostream& out) {
  out << "# keyframe_id tx ty tz qx qy qz qw (T_W_C, camera to world), map version "
      << response.map_version() << "\n";
  char stamp[32];
  for (const v1::KeyframeInfo& keyframe : response.keyframes()) {
    const v1::Pose& pose = keyframe.t_w_c();
    std::snprintf(stamp, sizeof(stamp), "%.6f", keyframe.stamp());
    out << FormatPoseLine(
        keyframe.id(),
        Eigen::Vector3d(pose.translation().x(), pose.translation().y(), pose.translation().z()),
        Eigen::Quaterniond(pose.qw(), pose.qx(), pose.qy(), pose.qz()),
        keyframe.name() + " " + stamp);
  }
}

}  // namespace

int RunKeyframesCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({"--first-id", "--limit", "--out"}), {"--help"});
  const std::string usage = std::string(kKeyframesUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  v1::ListKeyframesRequest request;
  request.set_first_id(args.GetInteger("--first-id", 0, 0));
  request.set_max_results(static_cast<int>(
      std::min<std::int64_t>(args.GetInteger("--limit", 0, 0), std::numeric_limits<int>::max())));
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0);
  if (!args.error().empty() || !args.positional().empty()) return UsageError(args, usage);

  v1::ListKeyframesResponse response;
  const grpc::Status status = client->ListKeyframes(request, &response);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  if (!args.Has("--out")) {
    WriteKeyframes(response, std::cout);
    return kExitOk;
  }
  const std::string path = args.Get("--out", "");
  std::ofstream file(path);
  if (file) WriteKeyframes(response, file);
  if (!file) return Fail(kCommand, path + ": cannot be written");
  std::cerr << response.keyframes_size() << " keyframes written to " << path << "\n";
  return kExitOk;
}

}  // namespace objmap::cli
