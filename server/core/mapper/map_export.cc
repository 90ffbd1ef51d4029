#include "mapper/map_export.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "pointcloud_io/pointcloud_io.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

nlohmann::json Vector(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

// `confirmed`: it passed the inventory's thresholds; `in_inventory`: it is also counted there
// (unknown objects are confirmed but counted only with InventoryConfig::count_unknown).
nlohmann::json ObjectJson(const MapObject& object, bool confirmed, bool in_inventory,
                          const ObjectEvidence& evidence) {
  nlohmann::json scores = nlohmann::json::object();
  for (int c = 0; c < kNumCocoClasses; ++c) {
    if (object.accumulated_scores[c] > 0.f) {
      scores[std::string(CocoClassName(c))] = object.accumulated_scores[c];
    }
  }
  nlohmann::json observations = nlohmann::json::array();
  for (const ObjectObservation& observation : object.observations) {
    nlohmann::json classes = nlohmann::json::object();
    for (const auto& [class_id, score] : observation.class_scores) {
      classes[std::string(ObjectClassName(class_id))] = score;
    }
    observations.push_back({{"keyframe", observation.keyframe_id},
                            {"box",
                             {observation.box.x_min, observation.box.y_min, observation.box.x_max,
                              observation.box.y_max}},
                            {"scores", classes},
                            {"points", observation.segment_C.size()}});
  }
  return {{"id", object.id},
          {"class", std::string(ObjectClassName(object.Label()))},
          {"confidence", object.Confidence()},
          {"confirmed", confirmed},
          {"in_inventory", in_inventory},
          {"scores", scores},
          {"evidence", evidence.evidence},
          {"keyframes_seeing", evidence.keyframes_seeing},
          {"views_seeing", evidence.views_seeing},
          {"views_detecting", evidence.views_detecting},
          {"observations", observations},
          {"centroid", Vector(object.centroid_W)},
          {"bbox_min", Vector(object.min_W)},
          {"bbox_max", Vector(object.max_W)},
          {"model_points", object.model_W.size()}};
}

std::set<ObjectId> ConfirmedIds(const Mapper& mapper) {
  std::set<ObjectId> ids;
  for (const MapObject* object : mapper.ConfirmedObjects()) ids.insert(object->id);
  return ids;
}

}  // namespace

std::string ObjectsJson(const Mapper& mapper) {
  const std::set<ObjectId> confirmed = ConfirmedIds(mapper);
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& [id, object] : mapper.objects().objects()) {
    const bool is_confirmed = confirmed.count(id) > 0;
    const bool counted = is_confirmed && (object.Label() != kUnknownClassId ||
                                          mapper.config().inventory.count_unknown);
    objects.push_back(ObjectJson(object, is_confirmed, counted, mapper.Evidence(object)));
  }
  nlohmann::json inventory = nlohmann::json::array();
  for (const InventoryEntry& entry : mapper.Inventory()) {
    inventory.push_back({{"class", std::string(ObjectClassName(entry.class_id))},
                         {"count", entry.count},
                         {"mean_confidence", entry.mean_confidence},
                         {"objects", entry.objects}});
  }
  return nlohmann::json{
      {"keyframes", mapper.num_keyframes()}, {"inventory", inventory}, {"objects", objects}}
      .dump(2);
}

bool WriteMapOutputs(const Mapper& mapper, const std::string& out_dir, std::string* why) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(fs::path(out_dir) / "objects", error);
  if (error) {
    *why = out_dir + ": " + error.message();
    return false;
  }
  if (!mapper.occupancy().WriteBinary(out_dir + "/map.bt", why)) return false;
  const std::string json_path = out_dir + "/objects.json";
  std::ofstream json(json_path);
  json << ObjectsJson(mapper) << "\n";
  if (!json) {
    *why = json_path + ": write failed";
    return false;
  }
  // A folder written again (a run added to a map folder) keeps no model of an object that has
  // since been merged, relabelled or dropped from the inventory.
  for (const fs::directory_entry& entry : fs::directory_iterator(fs::path(out_dir) / "objects")) {
    if (entry.path().extension() == ".ply") fs::remove(entry.path(), error);
  }
  for (const MapObject* object : mapper.ConfirmedObjects()) {
    const ColoredPoints model = mapper.objects().ModelPoints(*object);
    const std::string path =
        out_dir + "/objects/" + ObjectModelFileName(object->id, object->Label());
    if (!WritePly(path, model.points, model.colors, why)) return false;
  }
  return true;
}

}  // namespace objmap
