#include "http_viewer/viewer_json.h"

#include <cstdio>

#include "render/map_picture.h"
#include "types/coco_classes.h"

namespace objmap::http_viewer {

using nlohmann::json;

namespace {

json VectorJson(const Eigen::Vector3f& v) { return json::array({v.x(), v.y(), v.z()}); }

std::string ClassName(int class_id) { return std::string(ObjectClassName(class_id)); }

json SeenJson(const ObjectSeen& seen) {
  return json{
      {"keyframe", seen.keyframe_id}, {"session", seen.session_id}, {"stamp", seen.stamp_s}};
}

const char* StateName(ObjectState state) { return ObjectStateName(state); }

// What the object list and the inventory table need: no scores, no model. `in_inventory`: the
// inventory counts it (a confirmed object of no named class is not counted by default).
json ObjectSummary(const ObjectView& view, bool in_inventory) {
  const std::string name = ClassName(view.class_id);
  json summary{{"id", view.id},
               {"class", name},
               {"class_id", view.class_id},
               {"colour", HexColour(name)},
               {"confidence", view.confidence},
               {"in_inventory", in_inventory},
               {"confirmed", view.confirmed},
               {"observations", view.observations},
               {"keyframes", view.keyframes.size()},
               {"points", view.model_W ? view.model_W->size() : 0},
               {"centroid", VectorJson(view.centroid_W)},
               {"min", VectorJson(view.min_W)},
               {"max", VectorJson(view.max_W)},
               {"changed_version", view.changed_version},
               {"state", StateName(view.state)},
               {"first_seen", SeenJson(view.first_seen)},
               {"last_seen", SeenJson(view.last_seen)}};
  json places = json::array();
  for (const ObjectPlaceView& place : view.previous_places) {
    places.push_back({{"centroid", VectorJson(place.centroid_W)},
                      {"min", VectorJson(place.min_W)},
                      {"max", VectorJson(place.max_W)},
                      {"last_seen", SeenJson(place.last_seen)},
                      {"seen_empty", SeenJson(place.seen_empty)}});
  }
  summary["previous_places"] = places;
  if (view.added.keyframe_id != 0) summary["added"] = SeenJson(view.added);
  if (view.removed.keyframe_id != 0) summary["removed"] = SeenJson(view.removed);
  return summary;
}

}  // namespace

std::string HexColour(const std::string& class_name) {
  const RgbColour colour = ClassColour(class_name);
  char text[8];
  std::snprintf(text, sizeof(text), "#%02x%02x%02x", colour[0], colour[1], colour[2]);
  return text;
}

// The ids the inventory counts.
std::set<ObjectId> InventoryObjects(const MapSnapshot& snapshot) {
  std::set<ObjectId> counted;
  for (const InventoryEntry& entry : snapshot.inventory) {
    counted.insert(entry.objects.begin(), entry.objects.end());
  }
  return counted;
}

json MapJson(const ViewerMap& map) {
  const std::shared_ptr<const MapSnapshot> snapshot = map.Snapshot();
  json inventory = json::array();
  for (const InventoryEntry& entry : snapshot->inventory) {
    const std::string name = ClassName(entry.class_id);
    inventory.push_back({{"class", name},
                         {"class_id", entry.class_id},
                         {"colour", HexColour(name)},
                         {"count", entry.count},
                         {"mean_confidence", entry.mean_confidence},
                         {"objects", entry.objects}});
  }
  const std::set<ObjectId> counted = InventoryObjects(*snapshot);
  json objects = json::array();
  // The sessions the map's objects were seen in, for the page's session selector.
  std::set<SessionId> sessions;
  for (const auto& [id, view] : snapshot->objects) {
    objects.push_back(ObjectSummary(*view, counted.count(id) > 0));
    sessions.insert({view->first_seen.session_id, view->last_seen.session_id});
  }
  json tombstones = json::array();
  for (const auto& [id, view] : snapshot->tombstones) {
    tombstones.push_back(ObjectSummary(*view, false));
  }
  json changes = json::array();
  for (const MapObjectChange& change : snapshot->changes) {
    json entry{{"kind", ChangeKindName(change.change.kind)},
               {"id", change.change.id},
               {"class", ClassName(change.change.class_id)},
               {"seen", SeenJson(change.seen)},
               {"version", change.version},
               {"position", VectorJson(change.change.centroid_W)}};
    if (change.change.kind == ObjectChange::Kind::kMoved) {
      entry["from"] = VectorJson(change.change.from_W);
    }
    changes.push_back(std::move(entry));
    sessions.insert(change.seen.session_id);
  }
  sessions.erase(0);
  const std::optional<Eigen::Vector3d> up = map.Up();
  return json{{"source", map.Description()},
              {"up", up ? json::array({up->x(), up->y(), up->z()}) : json(nullptr)},
              {"version", snapshot->version},
              {"keyframes", snapshot->num_keyframes},
              {"inventory", inventory},
              {"objects", objects},
              {"tombstones", tombstones},
              {"changes", changes},
              {"sessions", std::vector<SessionId>(sessions.begin(), sessions.end())}};
}

json ObjectDetailJson(const MapSnapshot& snapshot, const ObjectView& view) {
  json detail = ObjectSummary(view, InventoryObjects(snapshot).count(view.id) > 0);
  json scores = json::array();
  for (const auto& [class_id, score] : view.scores) {
    scores.push_back({{"class", ClassName(class_id)}, {"score", score}});
  }
  detail["scores"] = scores;
  json sightings = json::array();
  for (const ObjectSighting& sighting : view.sightings) {
    sightings.push_back(
        {{"keyframe", sighting.keyframe_id},
         {"box", {sighting.box.x_min, sighting.box.y_min, sighting.box.x_max, sighting.box.y_max}},
         {"class", ClassName(sighting.class_id)},
         {"score", sighting.score},
         {"image", "/api/objects/" + std::to_string(view.id) + "/sightings/" +
                       std::to_string(sighting.keyframe_id) + ".jpg"}});
  }
  detail["sightings"] = sightings;
  return detail;
}

// Little-endian float32 x y z per point, then r g b bytes per point (grey when uncoloured):
// what a Float32Array and a Uint8Array read without parsing.
json ChangeJson(const MapChange& change) {
  return json{{"version", change.version},      {"kind", MapChangeKindName(change.kind)},
              {"keyframe", change.keyframe_id}, {"added", change.added},
              {"updated", change.updated},      {"removed", change.removed}};
}

}  // namespace objmap::http_viewer
