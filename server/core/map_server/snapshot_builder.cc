#include "map_server/snapshot_builder.h"

#include <algorithm>
#include <set>

namespace objmap {

ObjectSeen SnapshotBuilder::Seen(KeyframeId id) const {
  const auto it = keyframes_.find(id);
  return it != keyframes_.end() ? it->second : ObjectSeen{id, 0, 0.0};
}

std::shared_ptr<const ObjectView> SnapshotBuilder::MakeView(
    const ObjectMap& objects, const MapObject& object, bool confirmed, bool same_model,
    KeyframeId last_absent, std::uint64_t version,
    const std::shared_ptr<const ObjectView>& previous) {
  auto view = std::make_shared<ObjectView>();
  view->id = object.id;
  view->class_id = object.Label();
  view->confidence = object.Confidence();
  view->centroid_W = object.centroid_W;
  view->min_W = object.min_W;
  view->max_W = object.max_W;
  view->observations = static_cast<int>(object.observations.size());
  view->keyframes = object.Keyframes();
  for (int c = 0; c < kNumCocoClasses; ++c) {
    if (object.accumulated_scores[c] > 0.f)
      view->scores.emplace_back(c, object.accumulated_scores[c]);
  }
  std::sort(view->scores.begin(), view->scores.end(),
            [](const auto& a, const auto& b) { return a.second > b.second; });
  for (const ObjectObservation& observation : object.observations) {
    ObjectSighting sighting;
    sighting.keyframe_id = observation.keyframe_id;
    sighting.box = observation.box;
    for (const auto& [class_id, score] : observation.class_scores) {
      if (sighting.class_id < 0 || score > sighting.score) {
        sighting.class_id = class_id;
        sighting.score = score;
      }
    }
    view->sightings.push_back(sighting);
  }
  std::stable_sort(view->sightings.begin(), view->sightings.end(),
                   [](const ObjectSighting& a, const ObjectSighting& b) {
                     return a.keyframe_id < b.keyframe_id;
                   });
  if (!view->sightings.empty()) {
    view->first_seen = Seen(view->sightings.front().keyframe_id);
    view->last_seen = Seen(view->sightings.back().keyframe_id);
  }
  if (last_absent != 0) view->last_seen_absent = Seen(last_absent);
  view->confirmed = confirmed;
  view->changed_version = version;
  // The model is the expensive part: shared with the previous view when the object's published
  // model did not change (only its inventory status did).
  view->model_W = same_model && previous
                      ? previous->model_W
                      : std::make_shared<const ColoredPoints>(objects.ModelPoints(object));
  return view;
}

void SnapshotBuilder::AddKeyframe(KeyframeId id, SessionId session_id, double stamp_s) {
  keyframes_[id] = ObjectSeen{id, session_id, stamp_s};
}

void SnapshotBuilder::Touch(int class_id, std::uint64_t version) {
  if (class_id == kUnknownClassId && !count_unknown_) return;
  if (class_id >= 0 && class_id < kNumObjectClasses) class_changed_version_[class_id] = version;
}

std::shared_ptr<const MapSnapshot> SnapshotBuilder::Build(const Mapper& mapper,
                                                          std::uint64_t version, Diff* diff) {
  count_unknown_ = mapper.config().inventory.count_unknown;
  // Computed once: confirmation projects every object into every keyframe.
  const std::vector<const MapObject*> confirmed_objects = mapper.ConfirmedObjects();
  std::set<ObjectId> confirmed;
  for (const MapObject* object : confirmed_objects) confirmed.insert(object->id);

  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->version = version;
  snapshot->num_keyframes = mapper.num_keyframes();
  Diff local;
  for (const auto& [id, object] : mapper.objects().objects()) {
    const bool is_confirmed = confirmed.count(id) > 0;
    auto previous_it = views_.find(id);
    std::shared_ptr<const ObjectView> previous =
        previous_it == views_.end() ? nullptr : previous_it->second;
    // A neighbour of its class changing changes the published model too (ModelKey).
    auto model_key = mapper.objects().ModelKey(object);
    auto key_it = model_keys_.find(id);
    const bool same_model = key_it != model_keys_.end() && key_it->second == model_key;
    // Seen absent by a newer keyframe is a change too (the object may have been taken away).
    const KeyframeId last_absent = mapper.Evidence(object).last_absent;
    const bool unchanged = previous && same_model && previous->confirmed == is_confirmed &&
                           previous->observations == static_cast<int>(object.observations.size()) &&
                           previous->last_seen_absent.keyframe_id == last_absent;
    if (unchanged) {
      snapshot->objects.emplace(id, previous);
      continue;
    }
    auto view = MakeView(mapper.objects(), object, is_confirmed, same_model, last_absent, version,
                         previous);
    (previous ? local.updated : local.added).push_back(id);
    if (previous) Touch(previous->class_id, version);
    Touch(view->class_id, version);
    model_keys_[id] = std::move(model_key);
    snapshot->objects.emplace(id, view);
  }
  for (const auto& [id, view] : views_) {
    if (snapshot->objects.count(id) > 0) continue;
    local.removed.push_back(id);
    Touch(view->class_id, version);
    model_keys_.erase(id);
  }
  views_ = snapshot->objects;

  snapshot->inventory = InventoryOf(confirmed_objects, mapper.config().inventory.count_unknown);
  snapshot->class_changed_version.assign(class_changed_version_.begin(),
                                         class_changed_version_.end());
  if (diff != nullptr) *diff = std::move(local);
  return snapshot;
}

}  // namespace objmap
