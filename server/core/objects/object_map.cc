#include "objects/object_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace objmap {
namespace {

ColoredPoints Transform(const ColoredPoints& points_C, const Eigen::Isometry3d& T_W_C) {
  ColoredPoints points_W;
  points_W.colors = points_C.colors;
  points_W.points.reserve(points_C.points.size());
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  for (const Eigen::Vector3f& p : points_C.points) points_W.points.push_back(T * p);
  return points_W;
}

// The spread of the model along its least principal axis, 5th to 95th percentile: a few stray
// voxels (a border pixel, a slice of the surface under it) do not make a phone thick.
float ThicknessOf(const VoxelModel& model, const Eigen::Vector3f& centroid) {
  Eigen::Matrix3f covariance = Eigen::Matrix3f::Zero();
  model.ForEachPoint([&](const Eigen::Vector3f& p) {
    const Eigen::Vector3f d = p - centroid;
    covariance += d * d.transpose();
    return true;
  });
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(covariance);
  const Eigen::Vector3f axis = solver.eigenvectors().col(0);  // eigenvalues ascend
  std::vector<float> along;
  along.reserve(model.size());
  model.ForEachPoint([&](const Eigen::Vector3f& p) {
    along.push_back(axis.dot(p - centroid));
    return true;
  });
  const auto at = [&](float q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<float>(along.size() - 1));
    std::nth_element(along.begin(), along.begin() + k, along.end());
    return along[static_cast<std::size_t>(k)];
  };
  const float low = at(0.05f);
  return at(0.95f) - low;
}

// A class the shape allows takes the label from a ruled-out one when the detections gave it at
// least this share of the ruled-out class's score: named in a fair part of the views, not once
// in passing (a mouse's detections: phone 4.8, remote 4.1, mouse 1.8; a phone-shaped patch's:
// phone 3.0, remote 2.2, clock 0.3).
constexpr float kMinRelabelShare = 0.25f;

// The class with the highest positive accumulated score among those not `excluded` (the lowest
// id on a tie); kUnknownClassId when none has scored.
int BestScoredClass(const std::array<float, kNumCocoClasses>& scores,
                    const std::bitset<kNumCocoClasses>& excluded) {
  int best = kUnknownClassId;
  for (int c = 0; c < kNumCocoClasses; ++c) {
    if (excluded[c] || !(scores[c] > 0.f)) continue;
    if (best == kUnknownClassId || scores[c] > scores[best]) best = c;
  }
  return best;
}

}  // namespace

bool ObjectMapConfig::IsValid(std::string* why) const {
  if (!(model_voxel_size_m > 0.f)) {
    *why = "ObjectMapConfig.model_voxel_size_m must be positive";
    return false;
  }
  if (min_voxel_observations < 1) {
    *why = "ObjectMapConfig.min_voxel_observations must be >= 1";
    return false;
  }
  if (!(max_thin_thickness_m > 0.f)) {
    *why = "ObjectMapConfig.max_thin_thickness_m must be positive";
    return false;
  }
  for (int class_id : thin_classes) {
    if (class_id < 0 || class_id >= kNumCocoClasses) {
      *why = "ObjectMapConfig.thin_classes holds a class id outside 0..79";
      return false;
    }
  }
  return true;
}

bool IsUnclassified(const ObjectObservation& observation) {
  return observation.class_scores.size() == 1 &&
         observation.class_scores.front().first == kUnknownClassId;
}

int MapObject::Label() const {
  const int best = BestScoredClass(accumulated_scores, {});
  if (best == kUnknownClassId || !ruled_out_classes[best]) return best;
  // The detector hesitated between the ruled-out class and this one; a class it gave in
  // passing is no name, and the object is what no detection named.
  const int best_allowed = BestScoredClass(accumulated_scores, ruled_out_classes);
  if (best_allowed != kUnknownClassId &&
      accumulated_scores[best_allowed] >= kMinRelabelShare * accumulated_scores[best]) {
    return best_allowed;
  }
  return kUnknownClassId;
}

float MapObject::Confidence() const {
  const int label = Label();
  if (label == kUnknownClassId) return 0.f;
  const auto named = std::count_if(observations.begin(), observations.end(),
                                   [](const ObjectObservation& o) { return !IsUnclassified(o); });
  if (named == 0) return 0.f;
  const float confidence = accumulated_scores[label] / static_cast<float>(named);
  // Relabelled from a class the shape rules out: the score the detections gave to the ruled-out
  // classes goes to the others in proportion (a mouse named a phone in half its views is a
  // mouse in all of them). An object whose best class stands keeps the paper's confidence.
  if (label == BestScoredClass(accumulated_scores, {})) return confidence;
  float total = 0.f, allowed = 0.f;
  for (int c = 0; c < kNumCocoClasses; ++c) {
    total += accumulated_scores[c];
    if (!ruled_out_classes[c]) allowed += accumulated_scores[c];
  }
  if (!(allowed > 0.f) || !(allowed < total)) return confidence;
  return std::min(1.f, confidence * total / allowed);
}

std::vector<KeyframeId> MapObject::Keyframes() const {
  std::vector<KeyframeId> keyframes;
  for (const ObjectObservation& observation : observations) {
    keyframes.push_back(observation.keyframe_id);
  }
  std::sort(keyframes.begin(), keyframes.end());
  keyframes.erase(std::unique(keyframes.begin(), keyframes.end()), keyframes.end());
  return keyframes;
}

ObjectMap::ObjectMap(const ObjectMapConfig& config) : config_(config) {}

ObjectId ObjectMap::AddObject(ObjectObservation observation, const Eigen::Isometry3d& T_W_C) {
  const ObjectId id = next_id_++;
  MapObject& object = objects_[id];
  object.id = id;
  object.model_W = VoxelModel(config_.model_voxel_size_m);
  AddToModel(&object, observation, T_W_C);
  object.observations.push_back(std::move(observation));
  return id;
}

bool ObjectMap::AddObservation(ObjectId id, ObjectObservation observation,
                               const Eigen::Isometry3d& T_W_C) {
  auto it = objects_.find(id);
  if (it == objects_.end()) return false;
  AddToModel(&it->second, observation, T_W_C);
  it->second.observations.push_back(std::move(observation));
  return true;
}

void ObjectMap::AddToModel(MapObject* object, const ObjectObservation& observation,
                           const Eigen::Isometry3d& T_W_C) {
  for (const auto& [class_id, score] : observation.class_scores) {
    if (class_id >= 0 && class_id < kNumCocoClasses) object->accumulated_scores[class_id] += score;
  }
  InsertIntoModel(object, observation, T_W_C);
  UpdateBounds(object);
}

void ObjectMap::UpdateBounds(MapObject* object) {
  object->version = ++last_model_version_;
  if (object->model_W.empty()) {
    object->centroid_W = object->min_W = object->max_W = Eigen::Vector3f::Zero();
    object->ruled_out_classes.reset();
    return;
  }
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  object->model_W.ForEachPoint([&](const Eigen::Vector3f& p) {
    sum += p;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    return true;
  });
  object->centroid_W = sum / static_cast<float>(object->model_W.size());
  object->min_W = lo;
  object->max_W = hi;
  UpdateRuledOutClasses(object);
}

void ObjectMap::UpdateRuledOutClasses(MapObject* object) const {
  object->ruled_out_classes.reset();
  const bool thin_class_scored =
      std::any_of(config_.thin_classes.begin(), config_.thin_classes.end(),
                  [&](int class_id) { return object->accumulated_scores[class_id] > 0.f; });
  if (!thin_class_scored || object->model_W.empty()) return;
  if (ThicknessOf(object->model_W, object->centroid_W) <= config_.max_thin_thickness_m) return;
  for (int class_id : config_.thin_classes) object->ruled_out_classes.set(class_id);
}

bool ObjectMap::Merge(ObjectId kept, ObjectId absorbed) {
  if (kept == absorbed) return false;
  auto kept_it = objects_.find(kept);
  auto absorbed_it = objects_.find(absorbed);
  if (kept_it == objects_.end() || absorbed_it == objects_.end()) return false;
  MapObject& target = kept_it->second;
  MapObject& source = absorbed_it->second;
  for (int c = 0; c < kNumCocoClasses; ++c) {
    target.accumulated_scores[c] += source.accumulated_scores[c];
  }
  target.model_W.Insert(source.model_W);
  for (ObjectObservation& observation : source.observations) {
    target.observations.push_back(std::move(observation));
  }
  UpdateBounds(&target);
  objects_.erase(absorbed_it);
  return true;
}

bool ObjectMap::Remove(ObjectId id) { return objects_.erase(id) > 0; }

void ObjectMap::RebuildObject(MapObject* object, const KeyframePoseLookup& pose_of) {
  object->model_W.Clear();
  for (const ObjectObservation& observation : object->observations) {
    const std::optional<Eigen::Isometry3d> T_W_C = pose_of(observation.keyframe_id);
    if (T_W_C) InsertIntoModel(object, observation, *T_W_C);
  }
  UpdateBounds(object);
}

void ObjectMap::Rebuild(const KeyframePoseLookup& pose_of) {
  for (auto& [id, object] : objects_) RebuildObject(&object, pose_of);
}

std::size_t ObjectMap::RebuildObserving(const std::set<KeyframeId>& moved,
                                        const KeyframePoseLookup& pose_of) {
  std::size_t rebuilt = 0;
  for (auto& [id, object] : objects_) {
    const bool touched =
        std::any_of(object.observations.begin(), object.observations.end(),
                    [&](const ObjectObservation& o) { return moved.count(o.keyframe_id) > 0; });
    if (!touched) continue;
    RebuildObject(&object, pose_of);
    ++rebuilt;
  }
  return rebuilt;
}

void ObjectMap::Restore(std::map<ObjectId, std::vector<ObjectObservation>> observations,
                        ObjectId next_id, const KeyframePoseLookup& pose_of) {
  objects_.clear();
  next_id_ = next_id;
  for (auto& [id, list] : observations) {
    MapObject& object = objects_[id];
    object.id = id;
    object.model_W = VoxelModel(config_.model_voxel_size_m);
    object.observations = std::move(list);
    for (const ObjectObservation& observation : object.observations) {
      for (const auto& [class_id, score] : observation.class_scores) {
        if (class_id >= 0 && class_id < kNumCocoClasses) {
          object.accumulated_scores[class_id] += score;
        }
      }
    }
    RebuildObject(&object, pose_of);
    next_id_ = std::max(next_id_, id + 1);
  }
}

void ObjectMap::InsertIntoModel(MapObject* object, const ObjectObservation& observation,
                                const Eigen::Isometry3d& T_W_C) {
  if (observation.view >= 0) {
    object->model_W.Insert(Transform(observation.segment_C, T_W_C), observation.view);
  } else {
    object->model_W.Insert(Transform(observation.segment_C, T_W_C));
  }
}

void AssignViews(const std::map<KeyframeId, int>& view_of,
                 std::vector<ObjectObservation>* observations) {
  for (ObjectObservation& observation : *observations) {
    const auto it = view_of.find(observation.keyframe_id);
    observation.view = it == view_of.end() ? -1 : it->second;
  }
}

void ObjectMap::AssignViews(const std::map<KeyframeId, int>& view_of) {
  for (auto& [id, object] : objects_) objmap::AssignViews(view_of, &object.observations);
}

int MapObject::Views() const {
  std::set<std::int64_t> views;
  int own = 0;
  for (const ObjectObservation& observation : observations) {
    if (observation.view < 0) {
      ++own;
    } else {
      views.insert(observation.view);
    }
  }
  return own + static_cast<int>(views.size());
}

std::vector<const MapObject*> ObjectMap::Rivals(const MapObject& object) const {
  std::vector<const MapObject*> rivals;
  if (!config_.resolve_shared_voxels || object.model_W.empty()) return rivals;
  const float reach = config_.model_voxel_size_m;
  const int label = object.Label();
  for (const auto& [id, other] : objects_) {
    if (id == object.id || other.model_W.empty() || other.Label() != label) continue;
    if (((object.min_W.array() - reach) > other.max_W.array()).any() ||
        ((other.min_W.array() - reach) > object.max_W.array()).any()) {
      continue;
    }
    rivals.push_back(&other);
  }
  return rivals;
}

std::vector<std::pair<ObjectId, std::uint64_t>> ObjectMap::ModelKey(const MapObject& object) const {
  std::vector<std::pair<ObjectId, std::uint64_t>> key = {{object.id, object.version}};
  for (const MapObject* rival : Rivals(object)) key.emplace_back(rival->id, rival->version);
  return key;
}

namespace {

// The share of an object's views that reached a voxel, as if it also had this many views that
// did not: one view says little (a one-off detection reaches every voxel it has), so a voxel
// that 15 of 20 views reached stays with its object against one that a single view put there.
constexpr float kSharePriorViews = 2.f;

// Side of the cells that mark where a rival comes near, in voxels: the object's voxels in a
// marked cell or next to one get the exact search, so larger cells search more of them and
// smaller ones make more cells to mark.
constexpr float kRivalCellVoxels = 4.f;

float ViewShare(std::uint32_t observations, int views) {
  return static_cast<float>(observations) / (static_cast<float>(views) + kSharePriorViews);
}

// The cells, `cell_m` on a side, that hold a point of `model` within `region`, and the cells
// around them: a voxel whose cell is not among them has no voxel of `model` within two voxels
// (a cell is wider), so the search around it is skipped. One pass over the rival instead of a
// 27-voxel search around each of the object's voxels: a table and a fragment of it found
// apart share bounds but few voxels.
std::vector<std::uint64_t> CellsNear(const VoxelModel& model, const Eigen::AlignedBox3f& region,
                                     float cell_m) {
  std::vector<std::uint64_t> held;
  model.ForEachVoxel([&](const Eigen::Vector3f& p, std::uint32_t, const auto&) {
    if (region.contains(p)) held.push_back(VoxelKey(p, cell_m));
    return true;
  });
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  std::vector<std::uint64_t> cells;
  cells.reserve(27 * held.size());
  for (const std::uint64_t cell : held) {
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) cells.push_back(OffsetVoxelKey(cell, dx, dy, dz));
      }
    }
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

}  // namespace

ColoredPoints ObjectMap::ModelPoints(const MapObject& object) const {
  const int views = object.Views();
  const auto required =
      static_cast<std::uint32_t>(std::max(1, std::min(config_.min_voxel_observations, views)));
  const std::vector<const MapObject*> rivals = Rivals(object);
  if (rivals.empty()) return object.model_W.Points(required);
  const float reach = config_.model_voxel_size_m;
  const float cell_m = kRivalCellVoxels * reach;
  // A voxel's neighbours reach up to two voxels beyond it.
  const Eigen::AlignedBox3f own_region(object.min_W.array() - 2.f * reach,
                                       object.max_W.array() + 2.f * reach);
  std::vector<std::vector<std::uint64_t>> rival_cells;  // sorted
  std::vector<Eigen::AlignedBox3f> rival_reach;
  std::vector<int> rival_views;  // MapObject::Views walks the observations: once per rival
  for (const MapObject* rival : rivals) {
    rival_views.push_back(rival->Views());
    rival_cells.push_back(CellsNear(rival->model_W, own_region, cell_m));
    rival_reach.emplace_back(rival->min_W.array() - 2.f * reach,
                             rival->max_W.array() + 2.f * reach);
  }
  ColoredPoints out;
  out.points.reserve(object.model_W.size());
  out.colors.reserve(object.model_W.size());
  object.model_W.ForEachVoxel([&](const Eigen::Vector3f& p, std::uint32_t observations,
                                  const auto& color) {
    if (observations < required) return true;
    const float own_share = ViewShare(observations, views);
    for (std::size_t r = 0; r < rivals.size(); ++r) {
      // Most voxels lie beyond the rival's bounds, the rest mostly in cells far from it.
      if (!rival_reach[r].contains(p) ||
          !std::binary_search(rival_cells[r].begin(), rival_cells[r].end(), VoxelKey(p, cell_m))) {
        continue;
      }
      if (ViewShare(rivals[r]->model_W.ObservationsNear(p, 1), rival_views[r]) > own_share) {
        return true;
      }
    }
    out.points.push_back(p);
    out.colors.push_back(color());
    return true;
  });
  return out;
}

const MapObject* ObjectMap::Find(ObjectId id) const {
  auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : &it->second;
}

}  // namespace objmap
