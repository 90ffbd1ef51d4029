// `objmap render`: a picture of a map folder (PNG): the structure in grey, the inventory objects
// in their class colours with labels, a legend and a scale bar.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>

#include "arguments.h"
#include "commands.h"
#include "poses_file.h"
#include "render/map_picture.h"
#include "render/map_scene_io.h"
#ifdef OBJMAP_CLI_WITH_SERVER
#include <unistd.h>

#include "objmap/conversions.h"
#include "server_common.h"
#endif

namespace objmap::cli {
namespace {

constexpr char kRenderUsage[] =
    "objmap render: a picture of a map, headless (PNG).\n"
    "usage: objmap render <map-dir> --out FILE.png [options]\n"
#ifdef OBJMAP_CLI_WITH_SERVER
    "       objmap render --server ADDR --out FILE.png [options]\n"
#endif
    "  <map-dir>               written by `objmap map --out` or `objmap export`: map.bt,\n"
    "                          objects.json, objects/*.ply (keyframes.txt, when there, gives\n"
    "                          the up direction)\n"
#ifdef OBJMAP_CLI_WITH_SERVER
    "  --server ADDR           a running objmap_server instead: its OctoMap, confirmed\n"
    "                          objects and keyframe poses (the server options below)\n"
#endif
    "  --view V                top | perspective (default; camera with --camera) | camera\n"
    "  --camera TX TY TZ QX QY QZ QW\n"
    "                          the camera pose T_W_C of --view camera (x right, y down,\n"
    "                          z forward)\n"
    "  --size W H              picture size in pixels (default 1280 960)\n"
    "  --fov DEG               vertical field of view of perspective and camera views\n"
    "                          (default 50)\n"
    "  --class C               colour, label and frame only the objects of class C\n"
    "  --region X0 Y0 Z0 X1 Y1 Z1\n"
    "                          draw and frame only this box (metres, world frame)\n"
    "  --up auto|x|-x|y|-y|z|-z\n"
    "                          the world's up: auto takes it from the keyframe poses in\n"
    "                          keyframes.txt (cameras are held upright), else +z\n"
    "  --no-labels, --no-legend, --no-scale-bar\n"
    "Prints the legend (classes and counts) and the scale bar.\n";

constexpr int kOk = 0, kError = 1, kUsage = 2;

#ifdef OBJMAP_CLI_WITH_SERVER
// Reads the server's map into a folder as `objmap export` writes it, and its keyframe poses.
int FetchFromServer(Arguments& args, const std::vector<double>& region, const std::string& dir,
                    std::vector<Eigen::Isometry3d>* keyframe_poses) {
  constexpr char kCommand[] = "render";
  std::unique_ptr<MapClient> client = MakeClient(args, 120.0);
  int code = ExportOctomap(kCommand, client.get(), region, dir + "/map.bt");
  if (code == kOk) code = ExportObjects(kCommand, client.get(), region, false, dir);
  if (code != kOk) return code;
  v1::ListKeyframesResponse response;
  const grpc::Status status = client->ListKeyframes(v1::ListKeyframesRequest(), &response);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  std::string why;
  for (const v1::KeyframeInfo& keyframe : response.keyframes()) {
    Eigen::Isometry3d T_W_C;
    if (PoseFromProto(keyframe.t_w_c(), &T_W_C, &why)) keyframe_poses->push_back(T_W_C);
  }
  return kOk;
}
#endif

bool ParseUp(const std::string& text, Eigen::Vector3d* up) {
  const std::string axis = text.size() == 2 && text[0] == '-' ? text.substr(1) : text;
  const double sign = axis.size() < text.size() ? -1.0 : 1.0;
  if (axis == "x") *up = sign * Eigen::Vector3d::UnitX();
  else if (axis == "y") *up = sign * Eigen::Vector3d::UnitY();
  else if (axis == "z") *up = sign * Eigen::Vector3d::UnitZ();
  else return false;
  return true;
}

}  // namespace

int RunRenderCommand(int argc, char** argv) {
  std::set<std::string> flags = {"--out", "--view", "--class", "--up", "--fov"};
  std::string usage = kRenderUsage;
#ifdef OBJMAP_CLI_WITH_SERVER
  flags = WithServerFlags(flags);
  usage += kServerOptionsUsage;
#endif
  Arguments args(argc, argv, flags, {"--help", "--no-labels", "--no-legend", "--no-scale-bar"},
                 {{"--camera", 7}, {"--size", 2}, {"--region", 6}});
  if (args.Has("--help")) {
    std::cout << usage;
    return kOk;
  }
  const bool from_server = args.Has("--server");
  PictureConfig config;
  // A camera pose alone asks for the camera view.
  const std::string default_view = args.Has("--camera") ? "camera" : "perspective";
  if (!ParsePictureView(args.Get("--view", default_view), &config.view)) {
    args.SetError("--view must be top, perspective or camera, not " + args.Get("--view", ""));
  }
  const std::vector<double> size = args.GetNumbers("--size");
  if (size.size() == 2) {
    if (!(size[0] >= 1 && size[0] <= 1e5 && size[1] >= 1 && size[1] <= 1e5)) {
      args.SetError("--size: the picture must be 64 to 8192 pixels wide and high");
    } else {
      config.width = static_cast<int>(size[0]);
      config.height = static_cast<int>(size[1]);
      if (config.width != size[0] || config.height != size[1]) args.SetError("--size takes whole pixels");
    }
  }
  config.fov_deg = args.GetNumber("--fov", config.fov_deg);
  const std::vector<double> camera = args.GetNumbers("--camera");
  if (config.view == PictureView::kCamera && camera.size() != 7) {
    args.SetError("--view camera needs --camera TX TY TZ QX QY QZ QW");
  }
  if (config.view != PictureView::kCamera && !camera.empty()) {
    args.SetError("--camera gives the pose of --view camera, not of --view " +
                  args.Get("--view", ""));
  }
  if (camera.size() == 7) {
    const Eigen::Quaterniond q(camera[6], camera[3], camera[4], camera[5]);
    if (std::abs(q.norm() - 1.0) > 0.01) {
      args.SetError("--camera: the quaternion must have unit length");
    } else {
      config.T_W_C.linear() = q.normalized().toRotationMatrix();
      config.T_W_C.translation() = Eigen::Vector3d(camera[0], camera[1], camera[2]);
    }
  }
  const std::vector<double> region = args.GetNumbers("--region");
  if (region.size() == 6) {
    const Eigen::Vector3f low(static_cast<float>(region[0]), static_cast<float>(region[1]),
                              static_cast<float>(region[2]));
    const Eigen::Vector3f high(static_cast<float>(region[3]), static_cast<float>(region[4]),
                               static_cast<float>(region[5]));
    if (!(low.array() < high.array()).all()) args.SetError("--region: X0 Y0 Z0 must be below X1 Y1 Z1");
    config.region = Eigen::AlignedBox3f(low, high);
  }
  config.only_class = args.Get("--class", "");
  config.labels = !args.Has("--no-labels");
  config.legend = !args.Has("--no-legend");
  config.scale_bar = !args.Has("--no-scale-bar");
  const std::string up_text = args.Get("--up", "auto");
  if (up_text != "auto" && !ParseUp(up_text, &config.up_W)) {
    args.SetError("--up must be auto, x, -x, y, -y, z or -z, not " + up_text);
  }
  std::string why;
  if (args.error().empty() && !config.IsValid(&why)) args.SetError(why);
  if (!args.error().empty() || args.positional().size() != (from_server ? 0u : 1u) ||
      !args.Has("--out")) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << usage;
    return kUsage;
  }
  const auto start = std::chrono::steady_clock::now();
  std::string dir = from_server ? "" : args.positional()[0];
  std::vector<Eigen::Isometry3d> keyframe_poses;
#ifdef OBJMAP_CLI_WITH_SERVER
  // The server's map goes through a folder of its own, removed whatever happens.
  struct RemovedAtExit {
    std::string path;
    ~RemovedAtExit() {
      std::error_code ignored;
      if (!path.empty()) std::filesystem::remove_all(path, ignored);
    }
  } fetched;
  if (from_server) {
    fetched.path = (std::filesystem::temp_directory_path() /
                    ("objmap_render_" + std::to_string(::getpid())))
                       .string();
    dir = fetched.path;
    const int code = FetchFromServer(args, region, dir, &keyframe_poses);
    if (code != kOk) return code;
  }
#endif
  PictureScene scene;
  if (!ReadMapScene(dir, &scene, &why)) {
    std::cerr << "objmap render: " << why << "\n";
    return kError;
  }
  if (up_text == "auto" && from_server) {
    if (const auto up = UpFromCameras(keyframe_poses)) {
      config.up_W = *up;
    } else {
      std::cout << "up: +z (the server has no keyframe poses to tell it; --up to choose)\n";
    }
  } else if (up_text == "auto") {
    const std::string keyframes = (std::filesystem::path(dir) / "keyframes.txt").string();
    std::optional<Eigen::Vector3d> up;
    if (std::filesystem::exists(keyframes)) {
      std::vector<KeyframePoseLine> poses;
      if (!ReadPosesFile(keyframes, &poses, &why)) {
        std::cerr << "objmap render: " << why << "\n";
        return kError;
      }
      std::vector<Eigen::Isometry3d> T_W_C;
      for (const KeyframePoseLine& pose : poses) T_W_C.push_back(pose.T_W_C);
      up = UpFromCameras(T_W_C);
    }
    if (up) {
      config.up_W = *up;
    } else {
      std::cout << "up: +z (no keyframe poses in " << dir << " to tell it; --up to choose)\n";
    }
  }
  MapPicture picture;
  const std::string out = args.Get("--out", "");
  if (!RenderMapPicture(scene, config, &picture, &why) || !WritePicturePng(picture, out, &why)) {
    std::cerr << "objmap render: " << why << "\n";
    return kError;
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::cout << "legend:";
  for (const LegendEntry& entry : picture.legend) {
    std::cout << " " << entry.class_name << " " << entry.count << ";";
  }
  if (picture.legend.empty()) std::cout << " no objects";
  std::cout << "\n";
  char line[256];
  std::snprintf(line, sizeof line,
                "rendered %s (%s view, up %.2f %.2f %.2f): %zu structure voxels, %zu objects, "
                "scale bar %g m = %d px; wrote %s (%dx%d) in %.0f ms\n",
                from_server ? args.Get("--server", "").c_str() : dir.c_str(),
                PictureViewName(config.view), config.up_W.x(), config.up_W.y(),
                config.up_W.z(), scene.structure_W.size(), scene.objects.size(),
                picture.scale_bar_m, picture.scale_bar_px, out.c_str(), picture.width,
                picture.height, ms);
  std::cout << line;
  return kOk;
}

}  // namespace objmap::cli
