#include "association/associator.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <unordered_map>

#include "association/proximity_grid.h"

namespace objmap {
namespace {

Eigen::Vector3f Centroid(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const Eigen::Vector3f& p : points) sum += p;
  return points.empty() ? sum : Eigen::Vector3f(sum / static_cast<float>(points.size()));
}

float BoundingRadius(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& centre) {
  float radius_sq = 0.f;
  for (const Eigen::Vector3f& p : points)
    radius_sq = std::max(radius_sq, (p - centre).squaredNorm());
  return std::sqrt(radius_sq);
}

// Two objects observed in one keyframe were two detections with segments of their own there:
// things seen apart at the same moment are not one thing, however close (two mugs touching).
bool SeenTogether(const MapObject& a, const MapObject& b) {
  const std::vector<KeyframeId> ka = a.Keyframes(), kb = b.Keyframes();
  std::vector<KeyframeId> common;
  std::set_intersection(ka.begin(), ka.end(), kb.begin(), kb.end(), std::back_inserter(common));
  return !common.empty();
}

// One label, or one of them is an unknown object: the views that segmented a chair the
// detector missed and those where it named it make one chair.
bool SameOrUnknownLabel(const MapObject& a, const MapObject& b) {
  const int label_a = a.Label(), label_b = b.Label();
  return label_a == label_b || label_a == kUnknownClassId || label_b == kUnknownClassId;
}

float ObjectRadius(const MapObject& object) {
  return std::max((object.max_W - object.centroid_W).norm(),
                  (object.min_W - object.centroid_W).norm());
}

// The test points: every `stride`-th point, as many as ceil(size / stride).
std::size_t StrideFor(std::size_t size, int max_test_points) {
  return (size + static_cast<std::size_t>(max_test_points) - 1) /
         static_cast<std::size_t>(max_test_points);
}

// The least number of matches among `tested` points whose fraction, computed in float as the
// association compares it, reaches `min_fraction`; tested + 1 when none does. Stopping a count
// at this number decides exactly as the fraction would.
std::size_t MatchesNeeded(std::size_t tested, float min_fraction) {
  const auto fraction_of = [tested](std::size_t m) {
    return static_cast<float>(m) / static_cast<float>(tested);
  };
  auto needed = static_cast<std::size_t>(std::ceil(static_cast<double>(min_fraction) * tested));
  while (needed > 0 && fraction_of(needed - 1) >= min_fraction) --needed;
  while (needed <= tested && fraction_of(needed) < min_fraction) ++needed;
  return needed;
}

// When a count of matches may stop before the last test point.
enum class StopRule {
  kNever,            ///< the exact fraction is wanted
  kWhenUnreachable,  ///< a pair below the threshold is dropped; the fraction of one above ranks it
  kWhenDecided,      ///< only whether the threshold is reached matters
};

struct MatchCount {
  std::size_t matched = 0;
  std::size_t tested = 0;
  bool reaches = false;  ///< matched / tested >= the threshold (exact also after an early stop)
};

// Counts the test points that lie within the grid's radius of the model; `for_each_test_point`
// calls its visitor with each test point until the visitor returns false.
template <typename ForEachTestPoint>
MatchCount CountMatches(const ProximityGrid& grid, std::size_t tested, float min_fraction,
                        StopRule rule, const ForEachTestPoint& for_each_test_point) {
  MatchCount count;
  count.tested = tested;
  const std::size_t needed = MatchesNeeded(tested, min_fraction);
  std::size_t visited = 0;
  for_each_test_point([&](const Eigen::Vector3f& p) {
    ++visited;
    if (grid.AnyWithin(p)) ++count.matched;
    if (rule == StopRule::kWhenDecided && count.matched >= needed) return false;
    return rule == StopRule::kNever || count.matched + (tested - visited) >= needed;
  });
  count.reaches = count.matched >= needed;
  return count;
}

// Every `stride`-th point of a list, from the first.
auto TestPointsOf(const std::vector<Eigen::Vector3f>& points, std::size_t stride) {
  return [&points, stride](const auto& visit) {
    for (std::size_t i = 0; i < points.size(); i += stride) {
      if (!visit(points[i])) return;
    }
  };
}

// How many of the test points lie inside the box `lo`..`hi` widened by `distance_m`. A point
// outside cannot be within `distance_m` of a point inside, so when fewer than the needed matches
// lie inside, the pair fails without building the object's grid. The widening is a little
// generous so that rounding never leaves out a point that could match.
std::size_t CountInWidenedBox(const std::vector<Eigen::Vector3f>& points, std::size_t stride,
                              const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                              float distance_m) {
  const float margin = distance_m * 1.001f + 1e-6f;
  const Eigen::Array3f widened_lo = lo.array() - margin, widened_hi = hi.array() + margin;
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Array3f p = points[i].array();
    inside += (p >= widened_lo).all() && (p <= widened_hi).all() ? 1 : 0;
  }
  return inside;
}

// The matches among the test points of `points` (every stride-th, AssociationConfig::
// max_test_points) within the grid's radius of the model.
MatchCount CountSegmentMatches(const ProximityGrid& grid,
                               const std::vector<Eigen::Vector3f>& points,
                               const AssociationConfig& config, StopRule rule) {
  const std::size_t stride = StrideFor(points.size(), config.max_test_points);
  return CountMatches(grid, (points.size() + stride - 1) / stride, config.min_match_fraction, rule,
                      TestPointsOf(points, stride));
}

// False when too few test points of `points` lie near the object's bounds for the fraction to
// reach min_match_fraction at `distance_m` (see CountInWidenedBox).
bool MayReach(const MapObject& object, const std::vector<Eigen::Vector3f>& points, float distance_m,
              const AssociationConfig& config) {
  const std::size_t stride = StrideFor(points.size(), config.max_test_points);
  const std::size_t tested = (points.size() + stride - 1) / stride;
  return CountInWidenedBox(points, stride, object.min_W, object.max_W, distance_m) >=
         MatchesNeeded(tested, config.min_match_fraction);
}

}  // namespace

// Search structures per object, valid for one model version: rebuilt only when the object's
// model changed, so an object met by many segments and keyframes is read once per change. The
// model's points are read into a flat list once (walking the voxel hash costs more than
// bucketing the list) and shared by the grids and the bounding sphere.
struct Associator::SearchCache {
  struct Entry {
    std::uint64_t version = 0;
    std::size_t model_size = 0;
    std::optional<std::vector<Eigen::Vector3f>> points;  ///< in VoxelModel::Points() order
    std::vector<std::unique_ptr<ProximityGrid>> grids;   ///< one per distance asked for
    std::optional<std::pair<Eigen::Vector3f, float>> bounding_sphere;
  };
  std::unordered_map<ObjectId, Entry> entries;

  Entry& EntryOf(const MapObject& object) {
    Entry& entry = entries[object.id];
    // The size check also catches a model changed behind a caller's back without a new version.
    if (entry.version != object.version || entry.model_size != object.model_W.size()) {
      entry = Entry{};
      entry.version = object.version;
      entry.model_size = object.model_W.size();
    }
    return entry;
  }

  const std::vector<Eigen::Vector3f>& PointsOf(const MapObject& object) {
    Entry& entry = EntryOf(object);
    if (!entry.points) {
      entry.points.emplace();
      entry.points->reserve(object.model_W.size());
      object.model_W.ForEachPoint([&](const Eigen::Vector3f& p) {
        entry.points->push_back(p);
        return true;
      });
    }
    return *entry.points;
  }

  const ProximityGrid& GridOf(const MapObject& object, float distance_m) {
    const std::vector<Eigen::Vector3f>& points = PointsOf(object);
    Entry& entry = EntryOf(object);
    for (const auto& grid : entry.grids) {
      if (grid->radius_m() == distance_m) return *grid;
    }
    entry.grids.push_back(std::make_unique<ProximityGrid>(points, distance_m));
    return *entry.grids.back();
  }

  // Centroid and bounding radius of the model's points, as Candidates computes them for a list.
  const std::pair<Eigen::Vector3f, float>& BoundingSphereOf(const MapObject& object) {
    const std::vector<Eigen::Vector3f>& points = PointsOf(object);
    Entry& entry = EntryOf(object);
    if (!entry.bounding_sphere) {
      const Eigen::Vector3f centroid = Centroid(points);
      entry.bounding_sphere.emplace(centroid, BoundingRadius(points, centroid));
    }
    return *entry.bounding_sphere;
  }
};

bool AssociationConfig::IsValid(std::string* why) const {
  if (!(candidate_margin_m >= 0.f) || !(match_distance_m > 0.f) ||
      !(duplicate_distance_m >= match_distance_m)) {
    *why =
        "AssociationConfig: candidate_margin_m must be >= 0, match_distance_m > 0 and "
        "duplicate_distance_m >= match_distance_m";
    return false;
  }
  if (max_test_points < 1) {
    *why = "AssociationConfig.max_test_points must be >= 1";
    return false;
  }
  if (!(min_class_share >= 0.f && min_class_share <= 1.f)) {
    *why = "AssociationConfig.min_class_share must be in [0, 1]";
    return false;
  }
  if (!(min_match_fraction > 0.f && min_match_fraction <= 1.f)) {
    *why = "AssociationConfig.min_match_fraction must be in (0, 1]";
    return false;
  }
  return true;
}

Associator::Associator(const AssociationConfig& config)
    : config_(config), cache_(std::make_unique<SearchCache>()) {}
Associator::~Associator() = default;
Associator::Associator(Associator&&) noexcept = default;
Associator& Associator::operator=(Associator&&) noexcept = default;

float Associator::MatchFraction(const MapObject& object,
                                const std::vector<Eigen::Vector3f>& points_W, float distance_m) {
  if (points_W.empty()) return 0.f;
  const float distance = distance_m > 0.f ? distance_m : config_.match_distance_m;
  const MatchCount count =
      CountSegmentMatches(cache_->GridOf(object, distance), points_W, config_, StopRule::kNever);
  return static_cast<float>(count.matched) / static_cast<float>(count.tested);
}

std::vector<ObjectId> Associator::Candidates(const ObjectMap& map,
                                             const std::vector<Eigen::Vector3f>& points_W) const {
  if (points_W.empty()) return {};
  const Eigen::Vector3f centroid = Centroid(points_W);
  return CandidatesAround(map, centroid, BoundingRadius(points_W, centroid));
}

std::vector<ObjectId> Associator::CandidatesAround(const ObjectMap& map,
                                                   const Eigen::Vector3f& centroid,
                                                   float radius) const {
  std::vector<ObjectId> candidates;
  for (const auto& [id, object] : map.objects()) {
    const float reach = radius + ObjectRadius(object) + config_.candidate_margin_m;
    if ((object.centroid_W - centroid).squaredNorm() <= reach * reach) candidates.push_back(id);
  }
  return candidates;
}

std::vector<std::optional<ObjectId>> Associator::AssignKeyframe(
    const ObjectMap& map, const std::vector<SegmentToAssociate>& segments) {
  // Named segments choose first: an unknown segment beside a detection's must not take the
  // object the detection shows.
  struct Pair {
    bool unclassified;
    float rank;
    std::size_t segment;
    ObjectId object;
  };
  std::vector<Pair> pairs;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const std::vector<Eigen::Vector3f>& points_W = segments[s].points_W;
    if (points_W.empty()) continue;
    const Eigen::Vector3f centroid = Centroid(points_W);
    for (ObjectId id : Candidates(map, points_W)) {
      const MapObject& object = *map.Find(id);
      if (!ClassCompatible(object, segments[s].class_id)) continue;
      if (!MayReach(object, points_W, config_.match_distance_m, config_)) continue;
      // Below the threshold a pair is dropped whatever its fraction, so its count may stop as
      // soon as the threshold is out of reach; a pair above it needs its fraction to rank it.
      const MatchCount count = CountSegmentMatches(cache_->GridOf(object, config_.match_distance_m),
                                                   points_W, config_, StopRule::kWhenUnreachable);
      if (!count.reaches) continue;
      // Thin things stacked or side by side (books, plates) lie within match distance of each
      // other, so a segment matches both fully; the nearer centroid tells which one it shows.
      // A centimetre of centroid distance weighs as one percent of matched points.
      const float fraction = static_cast<float>(count.matched) / static_cast<float>(count.tested);
      pairs.push_back({segments[s].class_id == kUnknownClassId,
                       fraction - (object.centroid_W - centroid).norm(), s, id});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    if (a.unclassified != b.unclassified) return b.unclassified;
    return a.rank != b.rank ? a.rank > b.rank : a.segment < b.segment;
  });
  std::vector<std::optional<ObjectId>> assignment(segments.size());
  std::vector<ObjectId> taken;
  for (const Pair& pair : pairs) {
    if (assignment[pair.segment]) continue;
    if (std::find(taken.begin(), taken.end(), pair.object) != taken.end()) continue;
    assignment[pair.segment] = pair.object;
    taken.push_back(pair.object);
  }
  return assignment;
}

bool Associator::ClassCompatible(const MapObject& object, int class_id) const {
  if (config_.min_class_share <= 0.f) return true;
  // What nobody named may be anything: an unknown segment may show any object, and a detection
  // names an unknown object.
  const int label = object.Label();
  if (class_id == kUnknownClassId || label == kUnknownClassId) return true;
  if (class_id < 0 || class_id >= kNumCocoClasses) return false;
  const float best = object.accumulated_scores[label];
  return object.accumulated_scores[class_id] >= config_.min_class_share * best;
}

std::vector<std::pair<ObjectId, ObjectId>> Associator::FindDuplicates(
    const ObjectMap& map, const std::vector<ObjectId>& ids) {
  std::vector<std::pair<ObjectId, ObjectId>> duplicates;
  std::vector<ObjectId> absorbed;
  for (ObjectId id : ids) {
    const MapObject* object = map.Find(id);
    if (object == nullptr || object->model_W.empty()) continue;
    if (std::find(absorbed.begin(), absorbed.end(), id) != absorbed.end()) continue;
    const auto& [centroid, radius] = cache_->BoundingSphereOf(*object);
    for (ObjectId other_id : CandidatesAround(map, centroid, radius)) {
      const MapObject& other = *map.Find(other_id);
      if (other_id == id || !SameOrUnknownLabel(other, *object)) continue;
      if (std::find(absorbed.begin(), absorbed.end(), other_id) != absorbed.end()) continue;
      if (SeenTogether(*object, other)) continue;
      // Test the smaller model against the larger one: a partial view of an object is a
      // duplicate of the whole even though the whole is not a duplicate of the part.
      const bool object_smaller = object->model_W.size() <= other.model_W.size();
      const MapObject& small = object_smaller ? *object : other;
      const MapObject& large = object_smaller ? other : *object;
      if (!OverlapsEnough(small, large)) continue;
      duplicates.emplace_back(large.id, small.id);
      absorbed.push_back(small.id);
      if (object_smaller) break;
    }
  }
  return duplicates;
}

bool Associator::OverlapsEnough(const MapObject& small, const MapObject& large) {
  const std::vector<Eigen::Vector3f>& points = cache_->PointsOf(small);
  if (points.empty()) return false;
  if (!MayReach(large, points, config_.duplicate_distance_m, config_)) return false;
  const ProximityGrid& grid = cache_->GridOf(large, config_.duplicate_distance_m);
  const std::size_t stride = StrideFor(points.size(), config_.max_test_points);
  return CountMatches(grid, (points.size() + stride - 1) / stride, config_.min_match_fraction,
                      StopRule::kWhenDecided, TestPointsOf(points, stride))
      .reaches;
}

void Associator::ForgetMissing(const ObjectMap& map) {
  for (auto it = cache_->entries.begin(); it != cache_->entries.end();) {
    it = map.Find(it->first) == nullptr ? cache_->entries.erase(it) : std::next(it);
  }
}

}  // namespace objmap
