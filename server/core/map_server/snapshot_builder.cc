#include "map_server/snapshot_builder.h"

#include <algorithm>
#include <iterator>
#include <set>

namespace objmap {

ObjectSeen SnapshotBuilder::Seen(KeyframeId id) const {
  const auto it = keyframes_.find(id);
  return it != keyframes_.end() ? it->second : ObjectSeen{id, 0, 0.0};
}

std::shared_ptr<ObjectView> SnapshotBuilder::MakeView(
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
    view->last_seen = LastSeen(object);
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

namespace {

bool SameSighting(const ObjectSeen& a, const ObjectSeen& b) {
  return a.keyframe_id == b.keyframe_id && a.session_id == b.session_id && a.stamp_s == b.stamp_s;
}

// Sessions come in order; within one, the camera's stamps do.
bool Later(const ObjectSeen& a, const ObjectSeen& b) {
  return a.session_id != b.session_id ? a.session_id > b.session_id : a.stamp_s > b.stamp_s;
}

}  // namespace

void SnapshotBuilder::AddRevisit(KeyframeId id, SessionId session_id, double stamp_s) {
  const ObjectSeen seen{id, session_id, stamp_s};
  const auto [it, inserted] = revisits_.emplace(id, seen);
  if (!inserted && Later(seen, it->second)) it->second = seen;
}

ObjectSeen SnapshotBuilder::LastSeen(const MapObject& object) const {
  ObjectSeen last;
  KeyframeId newest = 0;
  for (const ObjectObservation& observation : object.observations) {
    newest = std::max(newest, observation.keyframe_id);
  }
  if (newest != 0) last = Seen(newest);
  if (revisits_.empty()) return last;
  for (const ObjectObservation& observation : object.observations) {
    const auto revisit = revisits_.find(observation.keyframe_id);
    if (revisit != revisits_.end() && Later(revisit->second, last)) last = revisit->second;
  }
  return last;
}

void SnapshotBuilder::Touch(int class_id, std::uint64_t version) {
  if (class_id == kUnknownClassId && !count_unknown_) return;
  if (class_id >= 0 && class_id < kNumObjectClasses) class_changed_version_[class_id] = version;
}

ObjectPlaceView SnapshotBuilder::PlaceView(const ObjectPlace& place) const {
  ObjectPlaceView view;
  view.centroid_W = place.centroid_W;
  view.min_W = place.min_W;
  view.max_W = place.max_W;
  view.first_seen = Seen(place.first_seen);
  view.last_seen = Seen(place.last_seen);
  if (place.seen_empty_at != 0) view.seen_empty = Seen(place.seen_empty_at);
  return view;
}

void SnapshotBuilder::ApplyHistory(const ObjectHistory* history, ObjectId published_id,
                                   ObjectView* view) const {
  view->id = published_id;
  if (history == nullptr) return;
  view->state = history->state;
  for (std::size_t i = 0; i + 1 < history->places.size(); ++i) {
    view->previous_places.push_back(PlaceView(history->places[i]));
  }
  if (history->added_at != 0) view->added = Seen(history->added_at);
  if (history->state == ObjectState::kRemoved) {
    view->removed = Seen(history->places.back().seen_empty_at);
  }
}

std::vector<MapObjectChange> SnapshotBuilder::ListChanges(const ObjectChanges& changes,
                                                          std::uint64_t version, Diff* diff) {
  std::vector<MapObjectChange> listed;
  std::map<std::tuple<int, ObjectId, KeyframeId>, std::uint64_t> versions;
  for (const ObjectChange& change : ChangeList(changes)) {
    MapObjectChange& entry = listed.emplace_back();
    entry.change = change;
    entry.seen = Seen(change.keyframe_id);
    const auto key = std::make_tuple(static_cast<int>(change.kind), change.id, change.keyframe_id);
    const auto known = change_versions_.find(key);
    entry.version = known != change_versions_.end() ? known->second : version;
    if (change.kind == ObjectChange::Kind::kMoved)
      entry.from_last_seen = Seen(change.from_last_seen);
    versions[key] = entry.version;
    if (known == change_versions_.end()) diff->object_changes.push_back(entry);
  }
  change_versions_ = std::move(versions);
  return listed;
}

std::shared_ptr<const MapSnapshot> SnapshotBuilder::Build(const Mapper& mapper,
                                                          std::uint64_t version, Diff* diff) {
  count_unknown_ = mapper.config().inventory.count_unknown;
  // Computed once: changes and confirmation project every object into every keyframe.
  const ObjectChanges changes = mapper.Changes();
  const std::vector<const MapObject*> confirmed_objects = mapper.ConfirmedObjects(changes);
  std::set<ObjectId> confirmed;
  for (const MapObject* object : confirmed_objects) confirmed.insert(object->id);
  auto history_of = [&changes](ObjectId published) -> const ObjectHistory* {
    const auto it = changes.histories.find(published);
    return it != changes.histories.end() ? &it->second : nullptr;
  };

  auto snapshot = std::make_shared<MapSnapshot>();
  snapshot->version = version;
  snapshot->num_keyframes = mapper.num_keyframes();
  Diff local;
  std::map<ObjectId, ObjectId> sources;
  for (const auto& [internal_id, object] : mapper.objects().objects()) {
    const ObjectId id = changes.PublishedId(internal_id);
    const ObjectHistory* history = history_of(id);
    const bool gone = changes.gone.count(internal_id) > 0;
    // A removed object's tombstone is its last place; the old places of a moved one are only
    // places in its history.
    if (gone && (history == nullptr || history->state != ObjectState::kRemoved ||
                 history->places.back().object != internal_id)) {
      continue;
    }
    const bool is_confirmed = confirmed.count(internal_id) > 0;
    auto& views = gone ? tombstones_ : views_;
    auto previous_it = views.find(id);
    std::shared_ptr<const ObjectView> previous =
        previous_it == views.end() ? nullptr : previous_it->second;
    // A neighbour of its class changing changes the published model too (ModelKey).
    auto model_key = mapper.objects().ModelKey(object);
    auto key_it = model_keys_.find(internal_id);
    // The id names another object of the map since it was found moved: nothing to reuse.
    const auto source = view_sources_.find(id);
    const bool same_source = source != view_sources_.end() && source->second == internal_id;
    const bool same_model =
        same_source && key_it != model_keys_.end() && key_it->second == model_key;
    // Seen absent by a newer keyframe is a change too (the object may have been taken away).
    const KeyframeId last_absent = mapper.Evidence(object).last_absent;
    const std::size_t places = history != nullptr ? history->places.size() : 1;
    sources[id] = internal_id;
    const bool unchanged =
        previous && same_model && previous->confirmed == is_confirmed &&
        previous->observations == static_cast<int>(object.observations.size()) &&
        previous->last_seen_absent.keyframe_id == last_absent &&
        (revisits_.empty() || SameSighting(previous->last_seen, LastSeen(object))) &&
        previous->previous_places.size() + 1 == places &&
        previous->added.keyframe_id == (history != nullptr ? history->added_at : 0);
    auto& target = gone ? snapshot->tombstones : snapshot->objects;
    if (unchanged) {
      target.emplace(id, previous);
      continue;
    }
    auto view = MakeView(mapper.objects(), object, is_confirmed, same_model, last_absent, version,
                         same_source ? previous : nullptr);
    ApplyHistory(history, id, view.get());
    if (!gone) {
      (previous ? local.updated : local.added).push_back(id);
      local.changed_objects.push_back(internal_id);
    }
    if (previous) Touch(previous->class_id, version);
    Touch(view->class_id, version);
    model_keys_[internal_id] = std::move(model_key);
    target.emplace(id, std::move(view));
  }
  for (const auto& [id, view] : views_) {
    if (snapshot->objects.count(id) > 0) continue;
    local.removed.push_back(id);
    Touch(view->class_id, version);
  }
  for (auto it = model_keys_.begin(); it != model_keys_.end();) {
    it = mapper.objects().Find(it->first) == nullptr ? model_keys_.erase(it) : std::next(it);
  }
  views_ = snapshot->objects;
  view_sources_ = std::move(sources);
  tombstones_ = snapshot->tombstones;
  snapshot->changes = ListChanges(changes, version, &local);

  snapshot->inventory =
      InventoryOf(confirmed_objects, mapper.config().inventory.count_unknown, &changes);
  snapshot->class_changed_version.assign(class_changed_version_.begin(),
                                         class_changed_version_.end());
  if (diff != nullptr) *diff = std::move(local);
  return snapshot;
}

}  // namespace objmap
