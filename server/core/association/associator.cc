#include "association/associator.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <iterator>
#include <unordered_map>

namespace objmap {
namespace {

struct CachedTree {
  std::uint64_t version = 0;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  bool empty = true;
};

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

float ObjectRadius(const MapObject& object) {
  return std::max((object.max_W - object.centroid_W).norm(),
                  (object.min_W - object.centroid_W).norm());
}

}  // namespace

struct Associator::TreeCache {
  std::unordered_map<ObjectId, CachedTree> trees;

  CachedTree& TreeOf(const MapObject& object) {
    CachedTree& cached = trees[object.id];
    if (cached.version == object.version && !cached.empty) return cached;
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (const Eigen::Vector3f& p : object.model_W.Points().points) {
      cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    cached.version = object.version;
    cached.empty = cloud->empty();
    if (!cached.empty) cached.tree.setInputCloud(cloud);
    return cached;
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
    : config_(config), trees_(std::make_unique<TreeCache>()) {}
Associator::~Associator() = default;
Associator::Associator(Associator&&) noexcept = default;
Associator& Associator::operator=(Associator&&) noexcept = default;

float Associator::MatchFraction(const MapObject& object,
                                const std::vector<Eigen::Vector3f>& points_W, float distance_m) {
  if (points_W.empty()) return 0.f;
  CachedTree& cached = trees_->TreeOf(object);
  if (cached.empty) return 0.f;
  const float distance = distance_m > 0.f ? distance_m : config_.match_distance_m;
  const float max_sq = distance * distance;
  std::vector<int> index(1);
  std::vector<float> distance_sq(1);
  const std::size_t stride = (points_W.size() + config_.max_test_points - 1) /
                             static_cast<std::size_t>(config_.max_test_points);
  std::size_t matched = 0;
  std::size_t tested = 0;
  for (std::size_t i = 0; i < points_W.size(); i += stride, ++tested) {
    const Eigen::Vector3f& p = points_W[i];
    if (cached.tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, distance_sq) > 0 &&
        distance_sq[0] <= max_sq) {
      ++matched;
    }
  }
  return static_cast<float>(matched) / static_cast<float>(tested);
}

std::vector<ObjectId> Associator::Candidates(const ObjectMap& map,
                                             const std::vector<Eigen::Vector3f>& points_W) const {
  std::vector<ObjectId> candidates;
  if (points_W.empty()) return candidates;
  const Eigen::Vector3f centroid = Centroid(points_W);
  const float radius = BoundingRadius(points_W, centroid);
  for (const auto& [id, object] : map.objects()) {
    const float reach = radius + ObjectRadius(object) + config_.candidate_margin_m;
    if ((object.centroid_W - centroid).squaredNorm() <= reach * reach) candidates.push_back(id);
  }
  return candidates;
}

std::vector<std::optional<ObjectId>> Associator::AssignKeyframe(
    const ObjectMap& map, const std::vector<SegmentToAssociate>& segments) {
  struct Pair {
    float fraction;
    std::size_t segment;
    ObjectId object;
  };
  std::vector<Pair> pairs;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    for (ObjectId id : Candidates(map, segments[s].points_W)) {
      if (!ClassCompatible(*map.Find(id), segments[s].class_id)) continue;
      const float fraction = MatchFraction(*map.Find(id), segments[s].points_W);
      if (fraction >= config_.min_match_fraction) pairs.push_back({fraction, s, id});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.fraction != b.fraction ? a.fraction > b.fraction : a.segment < b.segment;
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
  if (class_id < 0 || class_id >= kNumCocoClasses) return false;
  const float best = object.accumulated_scores[object.Label()];
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
    const std::vector<Eigen::Vector3f> points = object->model_W.Points().points;
    for (ObjectId other_id : Candidates(map, points)) {
      const MapObject& other = *map.Find(other_id);
      if (other_id == id || other.Label() != object->Label()) continue;
      if (std::find(absorbed.begin(), absorbed.end(), other_id) != absorbed.end()) continue;
      if (SeenTogether(*object, other)) continue;
      // Test the smaller model against the larger one: a partial view of an object is a
      // duplicate of the whole even though the whole is not a duplicate of the part.
      const bool object_smaller = object->model_W.size() <= other.model_W.size();
      const MapObject& small = object_smaller ? *object : other;
      const MapObject& large = object_smaller ? other : *object;
      if (MatchFraction(large, small.model_W.Points().points, config_.duplicate_distance_m) <
          config_.min_match_fraction) {
        continue;
      }
      duplicates.emplace_back(large.id, small.id);
      absorbed.push_back(small.id);
      if (object_smaller) break;
    }
  }
  return duplicates;
}

void Associator::ForgetMissing(const ObjectMap& map) {
  for (auto it = trees_->trees.begin(); it != trees_->trees.end();) {
    it = map.Find(it->first) == nullptr ? trees_->trees.erase(it) : std::next(it);
  }
}

}  // namespace objmap
