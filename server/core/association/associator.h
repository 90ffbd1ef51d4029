#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "objects/object_map.h"

namespace objmap {

/// Data association (paper Sec. III-C): candidate objects by centroid distance, then the
/// nearest-neighbour test on the points (the paper's k-d tree test, answered from a grid of the
/// object's points with the same result).
struct AssociationConfig {
  /// Objects whose centroid is farther from the segment's centroid than the two bounding radii
  /// plus this margin are not candidates, metres.
  float candidate_margin_m = 0.10f;
  /// A segment point matches when an object point lies within this distance (paper: 2 cm).
  float match_distance_m = 0.02f;
  /// Two objects of one label are one object when this fraction of the smaller model lies within
  /// duplicate_distance_m of the larger: wider than match_distance_m because two partial views
  /// of a far, flat object (a screen at 3 m, depth noise ~1.5 cm) rarely agree within 2 cm,
  /// while two distinct objects side by side share only their border strip.
  float duplicate_distance_m = 0.05f;
  /// A segment joins an object when at least this fraction of its points match (paper: 50 %).
  float min_match_fraction = 0.5f;
  /// The match fraction is measured on at most this many evenly spaced points of the segment
  /// (standard error under 1.6 % at 1000), which bounds the cost for large segments and models.
  int max_test_points = 1000;
  /// A segment may join an object only when the object's accumulated score for the segment's
  /// class is at least this share of its best class score (0 disables: the paper associates by
  /// geometry alone). Without it a table absorbs the books and phones lying on it, because their
  /// points are within 2 cm of the table's.
  float min_class_share = 0.25f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One segment that may join an object.
struct SegmentToAssociate {
  std::vector<Eigen::Vector3f> points_W;
  int class_id = -1;
};

/// Associates segments with objects. Keeps one ProximityGrid per object and distance, rebuilt
/// only when the object's model version changes. Thread-safety: none (the cache is mutable state).
class Associator {
 public:
  explicit Associator(const AssociationConfig& config);
  ~Associator();
  Associator(Associator&&) noexcept;
  Associator& operator=(Associator&&) noexcept;

  /// Fraction of `points_W` within `distance_m` of the object's model (match_distance_m when
  /// not given).
  [[nodiscard]] float MatchFraction(const MapObject& object,
                                    const std::vector<Eigen::Vector3f>& points_W,
                                    float distance_m = 0.f);

  /// Candidate objects of a segment by centroid distance (the first stage).
  [[nodiscard]] std::vector<ObjectId> Candidates(
      const ObjectMap& map, const std::vector<Eigen::Vector3f>& points_W) const;

  /// Decides, for all segments of one keyframe together, which object each joins (nullopt: a
  /// new object). Pairs are taken best match first, and an object takes at most one segment per
  /// keyframe: two monitors side by side in one image stay two objects even where one existing
  /// object overlaps both. Pairs whose classes disagree (min_class_share) are not considered.
  [[nodiscard]] std::vector<std::optional<ObjectId>> AssignKeyframe(
      const ObjectMap& map, const std::vector<SegmentToAssociate>& segments);

  /// Pairs of objects (kept, absorbed) among `ids` and their neighbours that describe the same
  /// thing: same label (or one of them unknown, kUnknownClassId), most of the smaller model lies within duplicate distance of the larger,
  /// and no keyframe observed both (objects seen apart at one moment are two objects).
  [[nodiscard]] std::vector<std::pair<ObjectId, ObjectId>> FindDuplicates(
      const ObjectMap& map, const std::vector<ObjectId>& ids);

  /// True when `class_id` has enough of the object's accumulated score (min_class_share), or
  /// when the segment or the object is of class unknown (kUnknownClassId).
  [[nodiscard]] bool ClassCompatible(const MapObject& object, int class_id) const;

  /// Drops the cached search structures of objects that no longer exist.
  void ForgetMissing(const ObjectMap& map);

  [[nodiscard]] const AssociationConfig& config() const { return config_; }

 private:
  struct SearchCache;

  [[nodiscard]] std::vector<ObjectId> CandidatesAround(const ObjectMap& map,
                                                       const Eigen::Vector3f& centroid,
                                                       float radius) const;
  /// True when min_match_fraction of the smaller model's test points lie within
  /// duplicate_distance_m of the larger model.
  [[nodiscard]] bool OverlapsEnough(const MapObject& small, const MapObject& large);

  AssociationConfig config_;
  std::unique_ptr<SearchCache> cache_;
};

}  // namespace objmap
