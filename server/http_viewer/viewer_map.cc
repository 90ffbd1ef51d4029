#include "http_viewer/viewer_map.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "occupancy/occupancy_map.h"
#include "pointcloud_io/pointcloud_io.h"
#include "render/map_picture.h"
#include "types/coco_classes.h"

namespace objmap::http_viewer {

namespace fs = std::filesystem;
using nlohmann::json;

LiveViewerMap::LiveViewerMap(const MapServer& server, std::string description)
    : server_(server), description_(std::move(description)) {}

std::string LiveViewerMap::Description() const { return description_; }

std::shared_ptr<const MapSnapshot> LiveViewerMap::Snapshot() const { return server_.Snapshot(); }

ServiceStatus LiveViewerMap::StructureCenters(std::size_t max_count,
                                              std::vector<Eigen::Vector3d>* centers,
                                              double* voxel_size_m,
                                              std::uint64_t* version) const {
  *voxel_size_m = server_.occupancy_resolution_m();
  return server_.OccupiedCenters(max_count, centers, version);
}

ServiceStatus LiveViewerMap::KeyframeColor(KeyframeId id, ColorImage* color) const {
  ServiceStatus status = server_.KeyframeColor(id, color);
  if (status.ok() && color->empty()) {
    return ServiceStatus::NotFound("keyframe " + std::to_string(id) + " came without a colour image");
  }
  return status;
}

ServiceStatus LiveViewerMap::IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                    bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                    std::vector<ObjectId>* objects_inside,
                                    std::uint64_t* version) const {
  return server_.IsFree(min_W, max_W, unknown_is_free, free, counts, objects_inside, version);
}

std::vector<MapChange> LiveViewerMap::ChangesSince(std::uint64_t since_version,
                                                   std::chrono::milliseconds timeout) const {
  return server_.ChangesSince(since_version, timeout);
}

std::optional<Eigen::Vector3d> LiveViewerMap::Up() const {
  // The first few hundred cameras tell the up direction as well as all of them.
  constexpr std::size_t kCameras = 300;
  std::vector<KeyframeSummary> keyframes;
  std::uint64_t version = 0;
  if (!server_.ListKeyframes(0, kCameras, &keyframes, &version).ok()) return std::nullopt;
  std::vector<Eigen::Isometry3d> poses;
  for (const KeyframeSummary& keyframe : keyframes) poses.push_back(keyframe.T_W_C);
  return UpFromCameras(poses);
}

struct FolderViewerMap::Impl {
  std::string dir;
  std::unique_ptr<OccupancyMap> occupancy;
  std::shared_ptr<const MapSnapshot> snapshot;
  std::optional<Eigen::Vector3d> up;
  double max_query_volume_m3 = MapServerConfig().max_query_volume_m3;
};

namespace {

Eigen::Vector3f ReadVector(const json& entry, const char* key) {
  const std::vector<float> values = entry.at(key).get<std::vector<float>>();
  if (values.size() != 3) throw std::invalid_argument(std::string(key) + " needs 3 numbers");
  return Eigen::Vector3f(values[0], values[1], values[2]);
}

// Class scores {"cup": 0.4, ...}, best first.
std::vector<std::pair<int, float>> ReadScores(const json& scores) {
  std::vector<std::pair<int, float>> out;
  for (const auto& [name, score] : scores.items()) {
    const int class_id = ObjectClassId(name);
    if (class_id >= 0) out.emplace_back(class_id, score.get<float>());
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  return out;
}

// One object of objects.json (as `objmap map` writes it) with its PLY model.
std::shared_ptr<const ObjectView> ReadObject(const fs::path& dir, const json& entry,
                                             std::string* why) {
  auto view = std::make_shared<ObjectView>();
  view->id = entry.at("id").get<ObjectId>();
  view->class_id = ObjectClassId(entry.at("class").get<std::string>());
  view->confidence = entry.value("confidence", 0.f);
  view->centroid_W = ReadVector(entry, "centroid");
  view->min_W = ReadVector(entry, "bbox_min");
  view->max_W = ReadVector(entry, "bbox_max");
  view->confirmed = entry.value("in_inventory", entry.value("confirmed", false));
  if (entry.contains("scores")) view->scores = ReadScores(entry["scores"]);
  for (const json& observation : entry.value("observations", json::array())) {
    ObjectSighting sighting;
    sighting.keyframe_id = observation.at("keyframe").get<KeyframeId>();
    const std::vector<float> box = observation.at("box").get<std::vector<float>>();
    if (box.size() != 4) throw std::invalid_argument("an observation box needs 4 numbers");
    sighting.box = {box[0], box[1], box[2], box[3]};
    const auto scores = ReadScores(observation.value("scores", json::object()));
    if (!scores.empty()) std::tie(sighting.class_id, sighting.score) = scores.front();
    view->sightings.push_back(sighting);
    view->keyframes.push_back(sighting.keyframe_id);
  }
  std::sort(view->keyframes.begin(), view->keyframes.end());
  view->keyframes.erase(std::unique(view->keyframes.begin(), view->keyframes.end()),
                        view->keyframes.end());
  view->observations = static_cast<int>(view->sightings.size());
  const fs::path ply =
      entry.contains("ply")
          ? dir / entry["ply"].get<std::string>()
          : dir / "objects" / ObjectModelFileName(view->id, view->class_id);
  auto model = std::make_shared<ColoredPoints>();
  // objmap map writes the models of confirmed objects only; the others are listed without one.
  std::error_code error;
  const bool has_model = view->confirmed || fs::exists(ply, error);
  if (has_model && !ReadPly(ply.string(), &model->points, &model->colors, why)) return nullptr;
  view->model_W = std::move(model);
  return view;
}

bool ReadObjects(const fs::path& dir, MapSnapshot* snapshot, std::string* why) {
  const fs::path path = dir / "objects.json";
  std::ifstream file(path);
  if (!file) {
    *why = path.string() + ": cannot open";
    return false;
  }
  try {
    const json document = json::parse(file);
    snapshot->num_keyframes = document.value("keyframes", std::size_t{0});
    for (const json& entry : document.at("objects")) {
      std::shared_ptr<const ObjectView> view = ReadObject(dir, entry, why);
      if (!view) return false;
      snapshot->objects[view->id] = std::move(view);
    }
    for (const json& entry : document.value("inventory", json::array())) {
      InventoryEntry inventory;
      inventory.class_id = ObjectClassId(entry.at("class").get<std::string>());
      inventory.count = entry.at("count").get<int>();
      inventory.mean_confidence = entry.value("mean_confidence", 0.f);
      inventory.objects = entry.at("objects").get<std::vector<ObjectId>>();
      snapshot->inventory.push_back(std::move(inventory));
    }
  } catch (const std::exception& error) {
    *why = path.string() + ": " + error.what();
    return false;
  }
  return true;
}

// Camera poses of keyframes.txt ("id tx ty tz qx qy qz qw", '#' comments); lines that are not
// such a pose are skipped: the file only orients the view.
std::vector<Eigen::Isometry3d> ReadCameraPoses(const fs::path& path) {
  std::vector<Eigen::Isometry3d> poses;
  std::ifstream file(path);
  std::string line;
  while (std::getline(file, line)) {
    line = line.substr(0, line.find('#'));
    std::istringstream fields(line);
    double id, tx, ty, tz, qx, qy, qz, qw;
    if (!(fields >> id >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) continue;
    const Eigen::Quaterniond q(qw, qx, qy, qz);
    if (!std::isfinite(q.norm()) || q.norm() < 1e-6) continue;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(tx, ty, tz);
    poses.push_back(T);
  }
  return poses;
}

}  // namespace

FolderViewerMap::FolderViewerMap() : impl_(std::make_unique<Impl>()) {}
FolderViewerMap::~FolderViewerMap() = default;

std::unique_ptr<FolderViewerMap> FolderViewerMap::Open(const std::string& dir, std::string* why) {
  std::unique_ptr<FolderViewerMap> map(new FolderViewerMap());
  map->impl_->dir = dir;
  map->impl_->occupancy = ReadOctomapFile((fs::path(dir) / "map.bt").string(), OccupancyConfig(), why);
  if (!map->impl_->occupancy) return nullptr;
  auto snapshot = std::make_shared<MapSnapshot>();
  // A folder is one state of the map: version 1 (0 is "before anything", what a client that
  // has seen nothing asks changes after).
  snapshot->version = 1;
  if (!ReadObjects(dir, snapshot.get(), why)) return nullptr;
  map->impl_->snapshot = std::move(snapshot);
  map->impl_->up = UpFromCameras(ReadCameraPoses(fs::path(dir) / "keyframes.txt"));
  return map;
}

std::string FolderViewerMap::Description() const { return "map folder " + impl_->dir; }

std::shared_ptr<const MapSnapshot> FolderViewerMap::Snapshot() const { return impl_->snapshot; }

ServiceStatus FolderViewerMap::StructureCenters(std::size_t max_count,
                                                std::vector<Eigen::Vector3d>* centers,
                                                double* voxel_size_m,
                                                std::uint64_t* version) const {
  if (max_count == 0) return ServiceStatus::Invalid("max_count must be positive");
  *centers = impl_->occupancy->OccupiedVoxelCenters();
  ThinEvenly(max_count, centers);
  *voxel_size_m = impl_->occupancy->config().resolution_m;
  *version = impl_->snapshot->version;
  return ServiceStatus::Ok();
}

ServiceStatus FolderViewerMap::KeyframeColor(KeyframeId id, ColorImage* color) const {
  const fs::path path = fs::path(impl_->dir) / "keyframes" / (std::to_string(id) + ".jpg");
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    return ServiceStatus::NotFound("keyframe " + std::to_string(id) + " has no image in " +
                                   impl_->dir + "/keyframes (objmap map writes <id>.jpg there)");
  }
  const cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (bgr.empty()) return {StatusCode::kInternal, path.string() + ": not a readable JPEG"};
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  color->width = rgb.cols;
  color->height = rgb.rows;
  color->rgb.assign(rgb.data, rgb.data + rgb.total() * 3);
  return ServiceStatus::Ok();
}

ServiceStatus FolderViewerMap::IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                      bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                      std::vector<ObjectId>* objects_inside,
                                      std::uint64_t* version) const {
  const ServiceStatus box = CheckQueryBox(min_W, max_W, "region", impl_->max_query_volume_m3);
  if (!box.ok()) return box;
  *counts = impl_->occupancy->QueryRegion(min_W, max_W, 0.0, 0);
  std::vector<ObjectId> inside = ObjectsInBox(*impl_->snapshot, min_W, max_W);
  *free = BoxIsFree(*counts, inside, unknown_is_free);
  if (objects_inside != nullptr) *objects_inside = std::move(inside);
  *version = impl_->snapshot->version;
  return ServiceStatus::Ok();
}

std::vector<MapChange> FolderViewerMap::ChangesSince(std::uint64_t since_version,
                                                     std::chrono::milliseconds timeout) const {
  if (since_version < impl_->snapshot->version) {
    // A client that has seen nothing yet: everything is new.
    MapChange change;
    change.version = impl_->snapshot->version;
    for (const auto& [id, view] : impl_->snapshot->objects) change.added.push_back(id);
    return {change};
  }
  std::this_thread::sleep_for(timeout);
  return {};
}

std::optional<Eigen::Vector3d> FolderViewerMap::Up() const { return impl_->up; }

}  // namespace objmap::http_viewer
