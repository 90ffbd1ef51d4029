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

nlohmann::json PlaceJson(const ObjectPlace& place) {
  return {{"centroid", Vector(place.centroid_W)},  {"bbox_min", Vector(place.min_W)},
          {"bbox_max", Vector(place.max_W)},       {"first_seen_keyframe", place.first_seen},
          {"last_seen_keyframe", place.last_seen}, {"seen_empty_keyframe", place.seen_empty_at}};
}

// The objects.json document of `mapper`, whose changes and confirmed objects are given (both
// project every object into every keyframe: computed once per write).
std::string ObjectsJsonOf(const Mapper& mapper, const ObjectChanges& changes,
                          const std::vector<const MapObject*>& confirmed_objects) {
  std::set<ObjectId> confirmed;
  for (const MapObject* object : confirmed_objects) confirmed.insert(object->id);
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& [id, object] : mapper.objects().objects()) {
    if (changes.gone.count(id) > 0) continue;
    const bool is_confirmed = confirmed.count(id) > 0;
    const bool counted = is_confirmed && (object.Label() != kUnknownClassId ||
                                          mapper.config().inventory.count_unknown);
    nlohmann::json json = ObjectJson(object, is_confirmed, counted, mapper.Evidence(object));
    const ObjectId published = changes.PublishedId(id);
    json["id"] = published;
    json["state"] = "present";
    const auto history = changes.histories.find(published);
    if (history != changes.histories.end()) {
      json["state"] = ObjectStateName(history->second.state);
      nlohmann::json before = nlohmann::json::array();
      for (std::size_t i = 0; i + 1 < history->second.places.size(); ++i) {
        before.push_back(PlaceJson(history->second.places[i]));
      }
      json["previous_places"] = before;
      if (history->second.added_at != 0) json["added_keyframe"] = history->second.added_at;
    }
    objects.push_back(std::move(json));
  }
  nlohmann::json removed = nlohmann::json::array();
  for (const auto& [id, history] : changes.histories) {
    if (history.state != ObjectState::kRemoved) continue;
    nlohmann::json places = nlohmann::json::array();
    for (const ObjectPlace& place : history.places) places.push_back(PlaceJson(place));
    removed.push_back({{"id", id},
                       {"class", std::string(ObjectClassName(history.class_id))},
                       {"places", places}});
  }
  nlohmann::json inventory = nlohmann::json::array();
  for (const InventoryEntry& entry :
       InventoryOf(confirmed_objects, mapper.config().inventory.count_unknown, &changes)) {
    inventory.push_back({{"class", std::string(ObjectClassName(entry.class_id))},
                         {"count", entry.count},
                         {"mean_confidence", entry.mean_confidence},
                         {"objects", entry.objects}});
  }
  return nlohmann::json{{"keyframes", mapper.num_keyframes()},
                        {"inventory", inventory},
                        {"objects", objects},
                        {"removed", removed}}
      .dump(2);
}

std::string ChangesJsonOf(const ObjectChanges& changes, const KeyframeWhenLookup& when) {
  nlohmann::json list = nlohmann::json::array();
  for (const ObjectChange& change : ChangeList(changes)) {
    nlohmann::json json = {{"kind", ChangeKindName(change.kind)},
                           {"object_id", change.id},
                           {"class", std::string(ObjectClassName(change.class_id))},
                           {"keyframe_id", change.keyframe_id},
                           {"position", Vector(change.centroid_W)},
                           {"min", Vector(change.min_W)},
                           {"max", Vector(change.max_W)}};
    if (change.kind == ObjectChange::Kind::kMoved) json["from"] = Vector(change.from_W);
    if (when) {
      const KeyframeWhen at = when(change.keyframe_id);
      json["session_id"] = at.session_id;
      json["stamp"] = at.stamp_s;
    }
    list.push_back(std::move(json));
  }
  return nlohmann::json{{"format", "objmap-map-changes-1"}, {"changes", list}}.dump(2);
}

// Writes `text` and a newline to `path`; false with the path named when it cannot.
bool WriteTextFile(const std::string& path, const std::string& text, std::string* why) {
  std::ofstream file(path);
  file << text << "\n";
  if (!file) {
    *why = path + ": write failed";
    return false;
  }
  return true;
}

}  // namespace

std::string ObjectsJson(const Mapper& mapper) {
  const ObjectChanges changes = mapper.Changes();
  return ObjectsJsonOf(mapper, changes, mapper.ConfirmedObjects(changes));
}

std::string ChangesJson(const Mapper& mapper, const KeyframeWhenLookup& when) {
  return ChangesJsonOf(mapper.Changes(), when);
}

bool WriteMapOutputs(const Mapper& mapper, const std::string& out_dir, std::string* why,
                     const KeyframeWhenLookup& when) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(fs::path(out_dir) / "objects", error);
  if (error) {
    *why = out_dir + ": " + error.message();
    return false;
  }
  if (!mapper.occupancy().WriteBinary(out_dir + "/map.bt", why)) return false;
  const ObjectChanges changes = mapper.Changes();
  const std::vector<const MapObject*> confirmed = mapper.ConfirmedObjects(changes);
  if (!WriteTextFile(out_dir + "/objects.json", ObjectsJsonOf(mapper, changes, confirmed), why) ||
      !WriteTextFile(out_dir + "/changes.json", ChangesJsonOf(changes, when), why)) {
    return false;
  }
  // A folder written again (a run added to a map folder) keeps no model of an object that has
  // since been merged, relabelled or dropped from the inventory.
  for (const fs::directory_entry& entry : fs::directory_iterator(fs::path(out_dir) / "objects")) {
    if (entry.path().extension() == ".ply") fs::remove(entry.path(), error);
  }
  for (const MapObject* object : confirmed) {
    const ColoredPoints model = mapper.objects().ModelPoints(*object);
    const std::string path = out_dir + "/objects/" +
                             ObjectModelFileName(changes.PublishedId(object->id), object->Label());
    if (!WritePly(path, model.points, model.colors, why)) return false;
  }
  return true;
}

}  // namespace objmap
