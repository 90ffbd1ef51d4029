#include "render/map_scene_io.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "occupancy/occupancy_map.h"
#include "pointcloud_io/pointcloud_io.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

bool ReadFile(const std::string& path, std::string* bytes, std::string* why) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    *why = path + ": cannot open";
    return false;
  }
  std::ostringstream content;
  content << file.rdbuf();
  *bytes = content.str();
  return true;
}

}  // namespace

bool ReadMapScene(const std::string& dir, PictureScene* scene, std::string* why) {
  namespace fs = std::filesystem;
  *scene = PictureScene();
  const std::unique_ptr<OccupancyMap> occupancy =
      ReadOctomapFile((fs::path(dir) / "map.bt").string(), OccupancyConfig(), why);
  if (!occupancy) return false;
  scene->structure_voxel_m = static_cast<float>(occupancy->config().resolution_m);
  const std::vector<Eigen::Vector3d> centres = occupancy->OccupiedVoxelCenters();
  scene->structure_W.reserve(centres.size());
  for (const Eigen::Vector3d& centre : centres) scene->structure_W.push_back(centre.cast<float>());

  const std::string json_path = (fs::path(dir) / "objects.json").string();
  if (!fs::exists(json_path)) return true;
  std::string bytes;
  if (!ReadFile(json_path, &bytes, why)) return false;
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(bytes);
  } catch (const nlohmann::json::exception& error) {
    *why = json_path + ": " + error.what();
    return false;
  }
  if (!document.is_object() || !document.contains("objects") || !document["objects"].is_array()) {
    *why = json_path + ": no \"objects\" list";
    return false;
  }
  for (const nlohmann::json& entry : document["objects"]) {
    try {
      // objmap map marks inventory objects "in_inventory"; objmap export lists confirmed ones.
      const bool counted = entry.value("in_inventory", entry.value("confirmed", false));
      if (!counted) continue;
      PictureObject object;
      object.id = entry.at("id").get<ObjectId>();
      object.class_name = entry.at("class").get<std::string>();
      object.confidence = entry.value("confidence", 0.f);
      const int class_id = CocoClassId(object.class_name);
      const std::string ply =
          entry.contains("ply")
              ? (fs::path(dir) / entry["ply"].get<std::string>()).string()
              : (fs::path(dir) / "objects" / ObjectModelFileName(object.id, class_id)).string();
      std::vector<std::array<std::uint8_t, 3>> colours;
      if (!ReadPly(ply, &object.points_W, &colours, why)) return false;
      scene->objects.push_back(std::move(object));
    } catch (const nlohmann::json::exception& error) {
      *why = json_path + ": object " + entry.dump().substr(0, 80) + ": " + error.what();
      return false;
    }
  }
  return true;
}

}  // namespace objmap
