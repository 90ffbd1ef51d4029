// `objmap export`: the server's OctoMap as a .bt file and its objects as PLY models plus a JSON
// index, for tools that read files (octovis, MeshLab, CloudCompare).
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "commands.h"
#include "objmap/conversions.h"
#include "pointcloud_io/pointcloud_io.h"
#include "server_common.h"
#include "types/coco_classes.h"

namespace objmap::cli {
namespace {

constexpr char kExportUsage[] =
    "objmap export: writes a running server's OctoMap (.bt) and object models (.ply) to files.\n"
    "usage: objmap export [--octomap FILE.bt] [--objects DIR] [options]\n"
    "  --octomap FILE            write the OctoMap (standard .bt) to FILE\n"
    "  --objects DIR             write DIR/<id>_<class>.ply (binary PLY, xyz + rgb, map frame)\n"
    "                            per object and DIR/objects.json\n"
    "  --region X0 Y0 Z0 X1 Y1 Z1  only this box of the OctoMap, only objects centred in it\n"
    "  --all                     also objects that do not (yet) pass the inventory thresholds\n"
    "at least one of --octomap and --objects is needed\n";

constexpr char kCommand[] = "export";

// Exporting a big map moves tens of megabytes; a minute is a better default than 30 s.
constexpr double kExportTimeoutS = 120.0;

}  // namespace

int ExportOctomap(const std::string& command, MapClient* client, const std::vector<double>& region,
                  const std::string& path) {
  v1::GetOctomapRequest request;
  if (region.size() == 6) {
    *request.mutable_region() =
        BoxToProto({region[0], region[1], region[2]}, {region[3], region[4], region[5]});
  }
  v1::GetOctomapResponse response;
  const grpc::Status status = client->GetOctomap(request, &response);
  if (!status.ok()) return FailWithStatus(command, status);
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code error;
  if (!parent.empty()) std::filesystem::create_directories(parent, error);
  if (error) return Fail(command, parent.string() + ": " + error.message());
  std::ofstream file(path, std::ios::binary);
  file.write(response.bt().data(), static_cast<std::streamsize>(response.bt().size()));
  if (!file) return Fail(command, path + ": write failed");
  std::cout << "wrote " << path << " (" << response.leaf_count() << " leaves, map version "
            << response.map_version() << ")\n";
  return kExitOk;
}

namespace {

// "<id>_<class>.ply", the class made safe for file names as `objmap map` does.
std::string PlyName(const v1::Object& object) {
  std::string name = object.class_name();
  if (CocoClassId(name) >= 0) name = CocoClassFileName(CocoClassId(name));
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return std::to_string(object.id()) + "_" + name + ".ply";
}

bool WriteObject(const v1::Object& object, const std::filesystem::path& dir, Json* entry,
                 std::string* why) {
  std::vector<Eigen::Vector3f> points_W;
  std::vector<std::array<std::uint8_t, 3>> colors;
  if (!DecodeObjectModel(object, &points_W, &colors, why)) return false;
  const std::string name = PlyName(object);
  if (!WritePly((dir / name).string(), points_W, colors, why)) return false;
  *entry = ObjectJson(object);
  (*entry)["points"] = points_W.size();
  (*entry)["ply"] = name;
  return true;
}

}  // namespace

int ExportObjects(const std::string& command, MapClient* client, const std::vector<double>& region,
                  bool all, const std::string& dir) {
  v1::QueryObjectsRequest request;
  if (region.size() == 6) {
    *request.mutable_region() =
        BoxToProto({region[0], region[1], region[2]}, {region[3], region[4], region[5]});
  }
  request.set_include_model(true);
  request.set_include_unconfirmed(all);
  v1::QueryObjectsResponse response;
  const grpc::Status status = client->QueryObjects(request, &response);
  if (!status.ok()) return FailWithStatus(command, status);
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) return Fail(command, dir + ": " + error.message());
  Json objects = Json::array();
  std::string why;
  for (const v1::Object& object : response.objects()) {
    Json entry;
    if (!WriteObject(object, dir, &entry, &why)) return Fail(command, why);
    objects.push_back(std::move(entry));
  }
  const Json document = {{"map_version", response.map_version()}, {"objects", objects}};
  const std::string json_path = (std::filesystem::path(dir) / "objects.json").string();
  std::ofstream file(json_path);
  file << document.dump(2) << "\n";
  if (!file) return Fail(command, json_path + ": write failed");
  std::cout << "wrote " << response.objects_size() << " objects to " << dir
            << " (objects.json and one .ply each, map version " << response.map_version() << ")\n";
  return kExitOk;
}

int RunExportCommand(int argc, char** argv) {
  Arguments args(argc, argv, WithServerFlags({"--octomap", "--objects"}), {"--all", "--help"},
                 {{"--region", 6}});
  const std::string usage = std::string(kExportUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  const std::vector<double> region = args.GetNumbers("--region");
  std::unique_ptr<MapClient> client = MakeClient(args, kExportTimeoutS);
  if (!args.error().empty() || !args.positional().empty() ||
      (!args.Has("--octomap") && !args.Has("--objects"))) {
    return UsageError(args, usage);
  }
  if (args.Has("--octomap")) {
    const int code = ExportOctomap(kCommand, client.get(), region, args.Get("--octomap", ""));
    if (code != kExitOk) return code;
  }
  if (args.Has("--objects")) {
    return ExportObjects(kCommand, client.get(), region, args.Has("--all"),
                         args.Get("--objects", ""));
  }
  return kExitOk;
}

}  // namespace objmap::cli
