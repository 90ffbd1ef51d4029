#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "objects/object_map.h"

namespace objmap {

/// Data association (paper Sec. III-C): candidate objects by centroid distance, then a k-d tree
/// nearest-neighbour test on the points.
struct AssociationConfig {
  /// Objects whose centroid is farther from the segment's centroid than the two bounding radii
  /// plus this margin are not candidates, metres.
  float candidate_margin_m = 0.10f;
  /// A segment point matches when an object point lies within this distance (paper: 2 cm).
  float match_distance_m = 0.02f;
  /// A segment joins an object when at least this fraction of its points match (paper: 50 %).
  float min_match_fraction = 0.5f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One segment that may join an object.
struct SegmentToAssociate {
  std::vector<Eigen::Vector3f> points_W;
  int class_id = -1;
};

/// Associates segments with objects. Keeps one k-d tree per object, rebuilt when the object's
/// model version changes. Thread-safety: none (the tree cache is mutable state).
class Associator {
 public:
  explicit Associator(const AssociationConfig& config);
  ~Associator();
  Associator(Associator&&) noexcept;
  Associator& operator=(Associator&&) noexcept;

  /// Fraction of `points_W` within match_distance_m of the object's model.
  [[nodiscard]] float MatchFraction(const MapObject& object,
                                    const std::vector<Eigen::Vector3f>& points_W);

  /// Candidate objects of a segment by centroid distance (the first stage).
  [[nodiscard]] std::vector<ObjectId> Candidates(
      const ObjectMap& map, const std::vector<Eigen::Vector3f>& points_W) const;

  /// Decides, for all segments of one keyframe together, which object each joins (nullopt: a
  /// new object). Pairs are taken best match first, and an object takes at most one segment per
  /// keyframe: two monitors side by side in one image stay two objects even where one existing
  /// object overlaps both.
  [[nodiscard]] std::vector<std::optional<ObjectId>> AssignKeyframe(
      const ObjectMap& map, const std::vector<SegmentToAssociate>& segments);

  /// Pairs of objects (kept, absorbed) among `ids` and their neighbours that describe the same
  /// thing: same label, and most of the smaller model lies within match distance of the larger.
  [[nodiscard]] std::vector<std::pair<ObjectId, ObjectId>> FindDuplicates(
      const ObjectMap& map, const std::vector<ObjectId>& ids);

  /// Drops cached trees of objects that no longer exist.
  void ForgetMissing(const ObjectMap& map);

  [[nodiscard]] const AssociationConfig& config() const { return config_; }

 private:
  struct TreeCache;
  AssociationConfig config_;
  std::unique_ptr<TreeCache> trees_;
};

}  // namespace objmap
