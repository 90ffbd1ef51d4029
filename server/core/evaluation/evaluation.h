#pragma once
// Scoring a map against ground truth: objects matched to real objects per class (true and false
// positives, misses, duplicates, merges, wrong labels, as in the paper's Table I), the accuracy
// of the object models against the real surfaces, and inventory counts for data without object
// poses. docs/evaluation.md defines every figure.

#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "types/frame.h"

namespace objmap {

class OccupancyMap;

/// A real object: its class, an oriented box (pose of the box centre, full extents along the
/// box axes) and points sampled on its surface (may be empty: no model accuracy then).
struct GroundTruthObject {
  int id = 0;
  int class_id = -1;
  Eigen::Isometry3d T_W_B = Eigen::Isometry3d::Identity();  ///< box frame: centre, axes
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> surface_W;
  /// The real surface itself (may be empty): triangles over `mesh_vertices_W`. When present,
  /// model accuracy is the exact distance to it; otherwise the distance to the nearest surface
  /// sample, which overstates it by about half the samples' spacing (1.6 cm for 2000 samples
  /// on a chair).
  std::vector<Eigen::Vector3f> mesh_vertices_W;
  std::vector<Eigen::Vector3i> mesh_triangles;
  /// Frames of the sequence that showed the object well enough to detect it (-1: not known).
  /// An object the sequence never showed is not a real object of the map's scene: no map can
  /// find it (a chair behind the camera's path all along).
  int visible_frames = -1;
};

/// A mapped object as the evaluation sees it: what the map claims (its inventory objects).
struct MappedObject {
  ObjectId id = 0;
  int class_id = -1;
  Eigen::Vector3d centroid_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d min_W = Eigen::Vector3d::Zero();  ///< axis-aligned bounds
  Eigen::Vector3d max_W = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> model_W;  ///< the point model (may be empty)
};

struct EvaluationConfig {
  /// A mapped object can stand for a real one of its class when its centroid lies in the real
  /// object's box grown by this margin on every side (partly seen objects have off-centre
  /// centroids), or when their axis-aligned boxes overlap by at least min_box_iou.
  double centroid_margin_m = 0.05;
  double min_box_iou = 0.25;
  /// A mapped object merges real objects when at least merge_point_share of its model points lie
  /// in each of two or more real objects of its class (in its box grown by merge_box_margin_m and
  /// in no other's of the class, since boxes of things side by side overlap): two monitors mapped
  /// as one put half their points on each, while a mug whose model took in a rim of its
  /// neighbour does not. Without a model: when its axis-aligned box holds at least
  /// merge_box_share of the axis-aligned boxes of two or more of them.
  double merge_point_share = 0.25;
  double merge_box_margin_m = 0.01;
  double merge_box_share = 0.5;
  /// Model distances are capped here (a model point farther from every surface sample counts
  /// as this far), so one stray point cannot dominate the mean.
  double max_model_distance_m = 0.1;
  /// Real objects with a known visible_frames below this are left out (counted as unseen).
  int min_visible_frames = 1;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Counts of one class (or of all classes, for the totals).
struct ClassCounts {
  int real = 0;             ///< real objects
  int mapped = 0;           ///< mapped objects
  int true_positives = 0;   ///< real objects that a mapped object stands for
  int false_positives = 0;  ///< mapped objects that stand for no real object of their class
  int misses = 0;           ///< real objects no mapped object stands for
  int duplicates = 0;       ///< mapped objects beyond the first that stand for one real object
  int merges = 0;           ///< mapped objects that cover two or more real objects
  int wrong_labels = 0;     ///< false positives that stand on a real object of another class
  int unseen = 0;           ///< objects of the ground truth the sequence never showed (not real)

  [[nodiscard]] double Precision() const;  ///< TP / (TP + FP + duplicates); 1 when nothing mapped
  [[nodiscard]] double Recall() const;     ///< TP / real; 1 when nothing is real
  void Add(const ClassCounts& other);
};

/// One real object and the mapped object that stands for it, with model accuracy.
struct ObjectMatch {
  int real_id = 0;
  ObjectId mapped_id = 0;
  /// Mean distance from the mapped model's points to the real surface (its mesh, or its samples
  /// when the ground truth has no mesh: accuracy), and
  /// from the samples to the model (completeness); negative when either set is empty.
  double model_to_surface_m = -1.0;
  double surface_to_model_m = -1.0;
};

/// Mapped objects of class unknown (segmented, never named): no class to be right or wrong
/// about, so they are counted apart from the classes' figures.
struct UnknownObjectCounts {
  int mapped = 0;
  int on_real = 0;    ///< that stand on a real object (any class; the class margins hold)
  int on_missed = 0;  ///< of those, on a real object that no named mapped object stands for
  /// Real objects that no named mapped object stands for and an unknown one does: misses the
  /// map still knows to be something.
  int missed_marked = 0;
};

struct ObjectEvaluation {
  std::map<int, ClassCounts> per_class;  ///< by class id; unknown objects are not among them
  ClassCounts totals;
  UnknownObjectCounts unknown;
  std::vector<ObjectMatch> matches;  ///< one per true positive
  /// Mean of the matches' model_to_surface_m (those that have one); negative when none.
  double mean_model_to_surface_m = -1.0;
};

/// Matches mapped objects to real ones (docs/evaluation.md): each mapped object goes to the
/// nearest real object of its class that it can stand for; the first one a real object gets is
/// its match (the one with the most model points), the others are duplicates.
[[nodiscard]] ObjectEvaluation EvaluateObjects(const std::vector<GroundTruthObject>& real,
                                               const std::vector<MappedObject>& mapped,
                                               const EvaluationConfig& config);

/// The real surface a sequence's sensor saw (ground_truth.json "seen_surface"): exact surface
/// points, at most one per voxel of the map resolution, of the structure and of the objects.
struct SeenSurface {
  double voxel_size_m = 0.01;
  std::vector<Eigen::Vector3f> structure_W;
  std::vector<Eigen::Vector3f> objects_W;
};

/// The OctoMap against the seen surface, voxel by voxel at the map resolution. "Within one
/// voxel": the voxel or one of its 26 neighbours.
struct OccupancyEvaluation {
  double voxel_size_m = 0.0;
  std::size_t occupied = 0;               ///< occupied voxels of the map
  std::size_t occupied_on_surface = 0;    ///< ... within one voxel of a seen surface voxel
  std::size_t occupied_near_surface = 0;  ///< ... within two voxels
  std::size_t structure_surface = 0;      ///< seen structure surface voxels
  std::size_t structure_occupied = 0;     ///< ... with an occupied voxel within one voxel
  std::size_t structure_free = 0;         ///< ... whose own voxel the map calls free
  std::size_t object_surface = 0;         ///< seen object surface voxels
  std::size_t object_free = 0;            ///< ... whose own voxel the map calls free

  /// occupied_on_surface / occupied: how much of what the map calls occupied is real surface.
  [[nodiscard]] double OccupiedPrecision() const;
  /// structure_occupied / structure_surface: how much of the seen structure the map holds.
  [[nodiscard]] double StructureCompleteness() const;
  /// structure_free / structure_surface and object_free / object_surface: seen surface that a
  /// planner trusting the OctoMap would take for air (objects are kept out of the OctoMap, and
  /// should be unknown there, not free).
  [[nodiscard]] double StructureFreeShare() const;
  [[nodiscard]] double ObjectFreeShare() const;
};

/// Scores `map` against `surface` (the map's resolution must be the surface's voxel size).
[[nodiscard]] OccupancyEvaluation EvaluateOccupancy(const OccupancyMap& map,
                                                    const SeenSurface& surface);

/// Expected count of a class for data without object poses: between min and max (inclusive).
struct CountRange {
  int min = 0;
  int max = 0;
};

/// Scores per-class counts against expected ranges: a count inside the range is all true
/// positives; above it, the excess are false positives; below it, the shortfall are misses.
/// Classes found but not expected are all false positives.
[[nodiscard]] std::map<int, ClassCounts> ScoreCounts(const std::map<int, CountRange>& expected,
                                                     const std::map<int, int>& found);

}  // namespace objmap
