#pragma once

#include <Eigen/Geometry>
#include <array>
#include <bitset>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "objects/observation_segment.h"
#include "objects/voxel_model.h"
#include "types/coco_classes.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// One detection of an object in one keyframe: enough to rebuild the object after the
/// keyframe's pose changes (paper Sec. III-D: the segments are stored with pose references).
struct ObjectObservation {
  KeyframeId keyframe_id = 0;
  BoundingBox2D box;  ///< detection box, colour pixels
  /// Class scores of this observation. Usually one entry; several when detections of different
  /// classes in the same keyframe picked the same segment.
  std::vector<std::pair<int, float>> class_scores;
  ColoredPoints segment_C;  ///< the detection's 3D segment, camera frame, downsampled
  /// The keyframe's depth pixels segment_C was made from (SegmentPointsFromDepth at
  /// segment_voxel_size_m, from the keyframe's depth as stored), so the store keeps these
  /// instead of the points. Empty when the points were made otherwise: the store keeps them.
  PixelRuns segment_pixels;
  float segment_voxel_size_m = 0.f;
  /// The independent view of its keyframe (ViewGroupingConfig), >= 0, or -1: a view of its own.
  /// Derived from the keyframe poses (the mapper sets it), not stored.
  std::int64_t view = -1;
};

/// True when no detection named what the observation shows: an object-like segment of class
/// kUnknownClassId (score 0), from UnknownObjectConfig.
[[nodiscard]] bool IsUnclassified(const ObjectObservation& observation);

struct ObjectMapConfig {
  /// Voxel size of the object models, metres (paper: 5 mm).
  float model_voxel_size_m = 0.005f;
  /// The published model (ModelPoints: queries, exports) keeps the voxels that at least this many
  /// independent views of the object (ObjectObservation::view) reached, or all of them when it
  /// has fewer views: a voxel one view put there and no other confirmed is mostly depth noise or
  /// a border pixel. The association keeps matching against every voxel. 1 keeps all.
  int min_voxel_observations = 2;
  /// Objects of one class that touch (mugs side by side, books in a stack) often share a
  /// segment, and a view that boxes only one of them adds a slice of the other to its model.
  /// With this on, a voxel that the models of two such objects both hold (within one voxel) is
  /// published only with the object whose views reached it in the larger share: each keeps its
  /// own surface. The association keeps matching against every voxel.
  bool resolve_shared_voxels = true;
  /// Classes thin whichever way they lie (a phone, a remote: at most 2.5 cm), and the thickness
  /// their models may measure: the spread (5th to 95th percentile) of the model along its least
  /// principal axis. Detectors often name a mouse (about 4 cm tall) a phone or a remote; a model
  /// thicker than this rules those classes out, and the label is the best of the other classes
  /// its detections gave (a size prior, on the one extent that does not depend on the view).
  std::vector<int> thin_classes = {67 /* cell phone */, 65 /* remote */};
  float max_thin_thickness_m = 0.03f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// An object of the map: its observations, accumulated class scores and point model.
struct MapObject {
  ObjectId id = 0;
  std::vector<ObjectObservation> observations;
  /// Sum over observations of each class's score (paper Eq. 1).
  std::array<float, kNumCocoClasses> accumulated_scores{};
  VoxelModel model_W;
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f min_W = Eigen::Vector3f::Zero();  ///< axis-aligned bounds of the model
  Eigen::Vector3f max_W = Eigen::Vector3f::Zero();
  /// Changes whenever the model changes, so caches (association grids, snapshot views) know when to
  /// rebuild. Unique within an ObjectMap's life, also across Restore: an id that now names
  /// another model never shows a version a cache saw before.
  std::uint64_t version = 0;
  /// Classes the model's shape rules out (ObjectMapConfig::thin_classes on a thick model).
  std::bitset<kNumCocoClasses> ruled_out_classes;

  /// argmax_c of the accumulated scores; kUnknownClassId while no detection has named it (only
  /// unclassified observations). When the argmax is a class the shape rules out, the best
  /// class it does not rule out, if that class got at least a quarter of the ruled-out one's score;
  /// otherwise kUnknownClassId (the detections named only what it cannot be).
  [[nodiscard]] int Label() const;
  /// max_c s_c / n with n the number of observations that a detection named (paper Sec. III-D;
  /// a view that only segmented it says nothing of its class); 0 for an unknown object. When
  /// the label replaces a best class the shape rules out, s_c is scaled by (sum of all scores) /
  /// (sum of the allowed classes' scores): the ruled-out share goes to the others in proportion.
  [[nodiscard]] float Confidence() const;
  /// Keyframes that saw this object, ascending, without repeats.
  [[nodiscard]] std::vector<KeyframeId> Keyframes() const;
  /// Independent views that saw it (observations without a view count one each).
  [[nodiscard]] int Views() const;
};

/// Sets each observation's view from its keyframe's in `view_of` (-1 where the keyframe has none).
void AssignViews(const std::map<KeyframeId, int>& view_of,
                 std::vector<ObjectObservation>* observations);

/// Returns the world pose of a keyframe; used to rebuild models after pose updates.
using KeyframePoseLookup = std::function<std::optional<Eigen::Isometry3d>(KeyframeId)>;

/// The set of objects. Ids are never reused and survive Rebuild(). Thread-safety: none.
class ObjectMap {
 public:
  explicit ObjectMap(const ObjectMapConfig& config = ObjectMapConfig{});

  /// Creates an object from a first observation; returns its id.
  ObjectId AddObject(ObjectObservation observation, const Eigen::Isometry3d& T_W_C);

  /// Adds an observation to an existing object (false when the id is unknown).
  bool AddObservation(ObjectId id, ObjectObservation observation, const Eigen::Isometry3d& T_W_C);

  /// Moves every observation of `absorbed` into `kept` and removes `absorbed`.
  bool Merge(ObjectId kept, ObjectId absorbed);

  /// Removes an object (false when unknown).
  bool Remove(ObjectId id);

  /// Sets the view of every observation (keyframes missing from `view_of`: -1) without rebuilding
  /// the models; Rebuild after it counts model voxels by these views.
  void AssignViews(const std::map<KeyframeId, int>& view_of);

  /// Rebuilds every model from its stored segments with the poses `pose_of` returns now.
  /// Observations whose keyframe has no pose are kept but not drawn.
  void Rebuild(const KeyframePoseLookup& pose_of);
  /// Rebuilds only the objects observed from one of `moved` keyframes (the others keep their
  /// models: their segments are drawn with unchanged poses). Returns how many were rebuilt.
  std::size_t RebuildObserving(const std::set<KeyframeId>& moved,
                               const KeyframePoseLookup& pose_of);

  /// Replaces the whole map by objects with the given ids and observations (a restart from
  /// stored state); ids handed out afterwards start at `next_id` (at least past the largest).
  void Restore(std::map<ObjectId, std::vector<ObjectObservation>> observations, ObjectId next_id,
               const KeyframePoseLookup& pose_of);
  [[nodiscard]] ObjectId next_id() const { return next_id_; }

  [[nodiscard]] const MapObject* Find(ObjectId id) const;
  /// The object's published model (min_voxel_observations, resolve_shared_voxels).
  [[nodiscard]] ColoredPoints ModelPoints(const MapObject& object) const;
  /// What the published model depends on: the model versions of the object and of the objects
  /// it shares voxels with (resolve_shared_voxels). Equal keys, equal published models.
  [[nodiscard]] std::vector<std::pair<ObjectId, std::uint64_t>> ModelKey(
      const MapObject& object) const;
  [[nodiscard]] const std::map<ObjectId, MapObject>& objects() const { return objects_; }
  [[nodiscard]] std::size_t size() const { return objects_.size(); }
  [[nodiscard]] const ObjectMapConfig& config() const { return config_; }

 private:
  void AddToModel(MapObject* object, const ObjectObservation& observation,
                  const Eigen::Isometry3d& T_W_C);
  void UpdateBounds(MapObject* object);
  // Sets MapObject::ruled_out_classes from the model's shape (ObjectMapConfig::thin_classes).
  void UpdateRuledOutClasses(MapObject* object) const;
  void InsertIntoModel(MapObject* object, const ObjectObservation& observation,
                       const Eigen::Isometry3d& T_W_C);
  void RebuildObject(MapObject* object, const KeyframePoseLookup& pose_of);
  /// Objects of the same class whose models come within a voxel of the object's bounds.
  [[nodiscard]] std::vector<const MapObject*> Rivals(const MapObject& object) const;

  ObjectMapConfig config_;
  std::map<ObjectId, MapObject> objects_;
  ObjectId next_id_ = 1;
  std::uint64_t last_model_version_ = 0;
};

}  // namespace objmap
