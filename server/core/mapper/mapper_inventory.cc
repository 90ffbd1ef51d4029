// What the Mapper makes of its objects: their visibility in every keyframe, their evidence, the
// changes between sessions and the inventory of the confirmed ones.

#include <iterator>
#include <limits>
#include <map>
#include <vector>

#include "mapper/mapper_impl.h"

namespace objmap {

const std::map<KeyframeId, ObjectVisibility>& Mapper::Impl::VisibilityOf(
    const MapObject& object) const {
  ObjectVisibilityCache& cache = visibility_cache[object.id];
  if (cache.model_version != object.version) cache = ObjectVisibilityCache{object.version, 0, {}};
  if (!keyframes.empty() && keyframes.rbegin()->first > cache.evaluated_through) {
    const std::vector<Eigen::Vector3f> samples =
        VisibilitySamples(object, config.inventory.max_visibility_points);
    // What lies within 2 cm of the model's bounds is the object itself (depth noise at its edges).
    const Eigen::AlignedBox3f bounds_W(object.min_W - Eigen::Vector3f::Constant(0.02f),
                                       object.max_W + Eigen::Vector3f::Constant(0.02f));
    for (auto it = keyframes.upper_bound(cache.evaluated_through); it != keyframes.end(); ++it) {
      const KeyframeRecord& record = it->second;
      const ObjectVisibility seen = VisibilityIn(samples, bounds_W, record.T_W_C, record.intrinsics,
                                                 record.depth_mm, config.inventory, config.changes);
      if (seen.visible_fraction > 0.f) cache.seen[it->first] = seen;
    }
    cache.evaluated_through = keyframes.rbegin()->first;
  }
  return cache.seen;
}

ObjectEvidence Mapper::Evidence(const MapObject& object) const {
  return EvidenceOf(object, impl_->VisibilityOf(object), impl_->view_of_keyframe,
                    impl_->SessionLookup(), impl_->config.inventory);
}

bool Mapper::Impl::IsConfirmedThrough(const MapObject& object, KeyframeId through) const {
  const InventoryConfig& thresholds = config.inventory;
  // An unknown object has no class score to be confident of; its views stand for it.
  const bool unknown = object.Label() == kUnknownClassId;
  if (static_cast<int>(object.observations.size()) < thresholds.min_observations ||
      (!unknown && object.Confidence() < thresholds.min_confidence)) {
    return false;
  }
  const std::map<KeyframeId, ObjectVisibility>& all = VisibilityOf(object);
  std::map<KeyframeId, ObjectVisibility> until;
  const bool whole = all.empty() || all.rbegin()->first <= through;
  if (!whole) until.insert(all.begin(), all.upper_bound(through));
  const ObjectEvidence evidence =
      EvidenceOf(object, whole ? all : until, view_of_keyframe, SessionLookup(), thresholds);
  if (unknown && evidence.views_detecting < thresholds.unknown_min_views) return false;
  return evidence.evidence >= thresholds.min_evidence;
}

void Mapper::Impl::DropStaleVisibility() const {
  // Objects merged away or re-associated since: their cached visibility is of no use.
  for (auto it = visibility_cache.begin(); it != visibility_cache.end();) {
    it = objects.Find(it->first) == nullptr ? visibility_cache.erase(it) : std::next(it);
  }
}

ObjectChanges Mapper::Changes() const {
  impl_->DropStaleVisibility();
  ChangeInputs inputs;
  inputs.objects = &impl_->objects;
  inputs.view_of_keyframe = &impl_->view_of_keyframe;
  inputs.session_of = impl_->SessionLookup();
  inputs.visibility_of =
      [this](const MapObject& object) -> const std::map<KeyframeId, ObjectVisibility>& {
    return impl_->VisibilityOf(object);
  };
  inputs.confirmed_through = [this](const MapObject& object, KeyframeId through) {
    return impl_->IsConfirmedThrough(object, through);
  };
  return DetectChanges(inputs, impl_->config.changes);
}

std::vector<const MapObject*> Mapper::ConfirmedObjects() const {
  return ConfirmedObjects(Changes());
}

std::vector<const MapObject*> Mapper::ConfirmedObjects(const ObjectChanges& changes) const {
  impl_->DropStaleVisibility();
  std::vector<const MapObject*> confirmed;
  for (const auto& [id, object] : impl_->objects.objects()) {
    if (changes.gone.count(id) > 0) continue;
    if (impl_->IsConfirmedThrough(object, std::numeric_limits<KeyframeId>::max())) {
      confirmed.push_back(&object);
    }
  }
  return confirmed;
}

std::vector<InventoryEntry> InventoryOf(const std::vector<const MapObject*>& objects,
                                        bool count_unknown, const ObjectChanges* changes) {
  std::map<int, InventoryEntry> by_class;
  for (const MapObject* object : objects) {
    if (!count_unknown && object->Label() == kUnknownClassId) continue;
    InventoryEntry& entry = by_class[object->Label()];
    entry.class_id = object->Label();
    ++entry.count;
    entry.mean_confidence += object->Confidence();
    entry.objects.push_back(changes != nullptr ? changes->PublishedId(object->id) : object->id);
  }
  std::vector<InventoryEntry> inventory;
  for (auto& [class_id, entry] : by_class) {
    entry.mean_confidence /= static_cast<float>(entry.count);
    inventory.push_back(entry);
  }
  std::stable_sort(
      inventory.begin(), inventory.end(),
      [](const InventoryEntry& a, const InventoryEntry& b) { return a.count > b.count; });
  return inventory;
}

std::vector<InventoryEntry> Mapper::Inventory() const {
  const ObjectChanges changes = Changes();
  return InventoryOf(ConfirmedObjects(changes), impl_->config.inventory.count_unknown, &changes);
}

}  // namespace objmap
