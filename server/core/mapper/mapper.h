#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "association/associator.h"
#include "mapper/object_changes.h"
#include "mapper/object_evidence.h"
#include "objects/object_map.h"
#include "occupancy/occupancy_map.h"
#include "segmentation/segmenter.h"
#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// Whether a pose update re-associates the objects. Association depends on where the keyframes
/// are relative to each other: after a loop closure bends the trajectory, segments that drift
/// put beside their object (a duplicate) or on top of a neighbour (a merge) belong elsewhere, and
/// only replaying the association with the corrected poses undoes that. A rigid move of the whole
/// map changes no association and only moves the models.
struct ReassociationConfig {
  bool enabled = true;
  /// The update re-associates when some keyframe's correction (new pose * old pose^-1) differs
  /// from the first keyframe's correction by more than this translation (metres) ...
  float min_translation_m = 0.02f;
  /// ... or this rotation (radians).
  float min_rotation_rad = 0.0175f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// How a pose update rebuilds the OctoMap.
struct RegenerationConfig {
  /// Keyframes whose rays are cast at once (the OcTree still takes them in order, so the map is
  /// the same for any number).
  int threads = 2;
  /// When at most this fraction of the keyframes moved, the map is rebuilt only inside the
  /// space those keyframes' rays reach (before and after the update), from the keyframes that
  /// reach into it; the result is the same as rebuilding everything. Above it, everything is
  /// rebuilt (cheaper than clearing most of the map).
  float incremental_max_moved_fraction = 0.5f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Objects no detector names: object-like segments that stand on a supporting plane and that no
/// detection picked become observations of class `unknown` (kUnknownClassId), associated like
/// any other, so a planner or a manipulator learns that something is there. A later detection
/// that matches such an object gives it its class. Which of them count (how many views must
/// have segmented them) is InventoryConfig's. Their pixels stay in the OctoMap as structure:
/// nothing names them, so a planner keeps avoiding them.
struct UnknownObjectConfig {
  bool enabled = true;
  /// Segments with fewer pixels are left out (a few hundred points make no object model).
  int min_segment_px = 150;
  /// Segments within this many pixels of the image border are cut off by the view: a part of
  /// something larger (a cupboard, a wall's edge) that another view shows whole.
  int image_border_px = 3;
  /// Segments that detections of the keyframe took more than this share of are theirs.
  float max_claimed_fraction = 0.2f;
  /// Its foot (5th percentile of its heights above the up-facing plane around it) lies within
  /// this of the plane: it stands there, rather than hanging above or being seen below it.
  float max_support_gap_m = 0.03f;
  /// Its top (95th percentile) rises at least this far above the plane: lower is a patch of the
  /// plane's own depth noise or a flat thing no geometry separates from it.
  float min_height_m = 0.03f;
  /// Its largest extent (5th to 95th percentile per camera axis, or its height) lies in this
  /// range, metres: smaller is noise or a cable, larger is furniture or a wall's part, which a
  /// detector names or which is structure.
  float min_extent_m = 0.04f;
  float max_extent_m = 1.0f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The aggregate configuration of the mapping pipeline: one struct per component.
struct MapperConfig {
  SegmenterConfig segmenter;
  DetectionSegmentConfig detection_segment;
  AssociationConfig association;
  ObjectMapConfig objects;
  OccupancyConfig occupancy;
  InventoryConfig inventory;
  ChangeConfig changes;
  ViewGroupingConfig views;
  ReassociationConfig reassociation;
  RegenerationConfig regeneration;
  UnknownObjectConfig unknown_objects;
  /// Keep a second copy of the OctoMap so that ReadOccupancy() on other threads never waits for
  /// the writer (SharedOccupancyMap): for a mapper that is queried while it maps (the server,
  /// the ROS node). Off (a mapper read only between writes, as in `objmap map`): half the
  /// OctoMap memory, and ReadOccupancy() waits while the OcTree is written or rebuilt.
  bool occupancy_second_copy = true;
  /// Detections scoring lower are ignored.
  float min_detection_score = 0.15f;
  /// Segments with fewer points after model downsampling are dropped (too small to model).
  int min_segment_points = 30;
  /// Detections of these COCO classes may take a supporting-plane segment (a table's top is the
  /// plane the segmentation separates everything else from).
  std::vector<int> surface_classes = {60 /* dining table */, 59 /* bed */};
  /// Detections of these COCO classes are often flat on a supporting plane (screens on walls,
  /// keyboards and laptops on desks, sinks in counters) or show one large flat face (a fridge's
  /// or an oven's front): when plane pixels dominate their box, they take the part of the plane
  /// the box covers; when no segment of their own fills min_segment_box_fill of the box, the
  /// part of the surface that dominates it. Books lying on a desk are as flat: seen from a few
  /// metres a stack of them joins the desk's segment. Phones and remotes are left out: their
  /// spurious detections (often on patches of a table) would outnumber them.
  std::vector<int> flat_classes = {
      62 /* tv */,    63 /* laptop */,       66 /* keyboard */, 71 /* sink */,
      74 /* clock */, 72 /* refrigerator */, 69 /* oven */,     73 /* book */};
  /// Two detections of one class whose boxes overlap by less than this IoU but pick the same
  /// segment (two cups touching, books in a stack: one convex segment) share it out between
  /// their boxes and stay two observations. 0: the later one only adds its score to the first
  /// (the paper's one segment, one object).
  float split_max_box_iou = 0.3f;
  /// Detections of these COCO classes may lie stacked (books on a desk): when two or more of one
  /// class pick one segment, their boxes overlap whatever the view, and a split by box cuts the
  /// stack across its layers. The segment is cut by height above the supporting plane under it
  /// instead: each box takes the layer at the median height of the pixels only it covers.
  std::vector<int> stack_classes = {73 /* book */};
  /// Boxes of a stack whose layers lie closer in height than this are one object boxed twice
  /// (two boxes of one book); layers of a real stack lie at least a thin book's thickness apart.
  float min_stack_layer_gap_m = 0.01f;
  /// Flat-object boxes shrink by this fraction of their size on every side before cropping the
  /// plane (colour and depth are not registered, so box borders are unreliable).
  float flat_box_shrink_fraction = 0.1f;
  /// A detection's segment must span at least this share of its box (the bounding box of the
  /// segment's pixels over the detection box's area). A box bounds the visible object, so a
  /// segment far smaller than it is a fragment: a handle, a patch of floor between the legs of
  /// a fridge the segmentation did not separate, or whatever a spurious box landed on. Such an
  /// observation would start an object with a model of the wrong thing.
  float min_segment_box_fill = 0.2f;
  /// A detection of one of part_classes whose box lies at least part_inside_fraction inside the
  /// box of a detection of one of whole_classes in the same image shows a part of that object,
  /// and is dropped: a detector boxes a laptop's keyboard deck as a keyboard about as often as
  /// it boxes the laptop, and those boxes would make a keyboard out of the laptop, or out of the
  /// desk under it once the laptop's detection has taken the laptop's segment. The whole's box
  /// must also be at least min_whole_to_part_area times the part's: two boxes of about one size
  /// are two guesses at one object (a keyboard boxed as a laptop as well), which fuse as one
  /// observation with both scores. An external keyboard is wider than a laptop and lies in
  /// front of it, so its box is not inside the laptop's.
  std::vector<int> part_classes = {66 /* keyboard */};
  std::vector<int> whole_classes = {63 /* laptop */};
  float part_inside_fraction = 0.8f;
  float min_whole_to_part_area = 1.5f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Milliseconds spent in each stage for one keyframe.
struct StageTimings {
  double segmentation_ms = 0.0;  ///< back-projection, segmentation, detection-to-segment
  double association_ms = 0.0;   ///< association, object update, duplicate merging
  double occupancy_ms = 0.0;     ///< OctoMap integration
};

/// What one keyframe did to the map.
struct KeyframeResult {
  KeyframeId keyframe_id = 0;
  int detections_used = 0;  ///< detections that got a 3D segment
  /// Object-like segments no detection picked, associated as class `unknown` (UnknownObjectConfig).
  int unclassified_segments = 0;
  std::vector<ObjectId> created;
  std::vector<ObjectId> updated;
  std::vector<std::pair<ObjectId, ObjectId>> merged;  ///< (kept, absorbed)
  StageTimings timings;
};

/// One line of the inventory.
struct InventoryEntry {
  int class_id = -1;
  int count = 0;
  float mean_confidence = 0.f;
  std::vector<ObjectId> objects;
};

/// Groups objects by label: count, mean confidence and ids per class, most frequent first.
/// Unknown objects (kUnknownClassId) are left out unless `count_unknown`. With `changes`, each
/// object is listed under the id it is published under (a moved object's first id).
[[nodiscard]] std::vector<InventoryEntry> InventoryOf(const std::vector<const MapObject*>& objects,
                                                      bool count_unknown = false,
                                                      const ObjectChanges* changes = nullptr);

/// What a pose update did.
struct PoseUpdateReport {
  int keyframes_moved = 0;
  /// The objects were re-associated from their observations (ReassociationConfig); ids of
  /// objects that keep most of their observations survive, the others are new or gone.
  bool reassociated = false;
  int objects_before = 0;
  int objects_after = 0;
  /// The OctoMap was rebuilt only where the moved keyframes' rays reach, before and after
  /// (RegenerationConfig), from this many keyframes; otherwise from all of them.
  bool occupancy_incremental = false;
  int keyframes_reintegrated = 0;
};

/// What the mapper keeps of a keyframe to regenerate the map after its pose changes: the depth
/// image (millimetres, as sensors deliver it: 2 bytes a pixel) and which pixels belong to objects.
/// Clouds are re-made from it, so a regenerated map is the map full-resolution integration builds.
struct KeyframeRecord {
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  CameraIntrinsics intrinsics;
  std::vector<std::uint16_t> depth_mm;    ///< row-major, 0: no depth
  std::vector<std::uint8_t> object_mask;  ///< row-major, 1: the pixel belongs to an object
  /// The mapping session it was taken in (Mapper::SetSession): views of one session saw one
  /// world; between sessions objects may have been put down or taken away.
  std::int64_t session = 0;
};

/// Depth in millimetres as a keyframe keeps it: 0 where there is none (or beyond 65 m).
[[nodiscard]] std::vector<std::uint16_t> DepthMillimetres(const DepthImage& depth);
/// A frame's depth as a keyframe keeps it (millimetres, 0 where there is none), no object pixels.
[[nodiscard]] KeyframeRecord RecordOf(const RgbdFrame& frame);
/// A keyframe's depth, pose and object mask as the occupancy map's input.
[[nodiscard]] DepthScanW DepthScanOf(const KeyframeRecord& record);

/// The OctoMap with the poses its keyframes were integrated with (Mapper::Restore).
struct OccupancyCheckpoint {
  std::string state;  ///< OccupancyMap::WriteState()
  std::map<KeyframeId, Eigen::Isometry3d> keyframe_poses;
};

/// What Mapper::Restore did with the OctoMap.
struct RestoreOutcome {
  bool from_checkpoint = false;
  int keyframes_integrated = 0;    ///< keyframes whose rays were cast (those after the checkpoint)
  std::string checkpoint_refused;  ///< why a given checkpoint was not used; empty otherwise
};

/// The facade of the core: keyframes in, objects and occupancy out (paper Fig. 3).
/// Thread-safety: the writers (AddKeyframe, UpdatePoses, Restore) and every other method must be
/// called from one thread at a time, except ReadOccupancy, which may run on any thread at any
/// time. With MapperConfig::occupancy_second_copy it never waits for the writer: keyframes and
/// regenerations are written into a copy that readers do not see, which is then published
/// (SharedOccupancyMap).
class Mapper {
 public:
  /// `config` must satisfy IsValid(); an invalid config is a programming error.
  explicit Mapper(const MapperConfig& config);
  ~Mapper();

  /// Segments, associates and integrates one keyframe with its detections (boxes in colour
  /// pixels). Returns false with a reason naming the frame when the frame is invalid; the map is
  /// then unchanged.
  [[nodiscard]] bool AddKeyframe(const RgbdFrame& frame, const std::vector<Detection>& detections,
                                 KeyframeResult* result, std::string* why);

  /// Keyframes added from now on belong to this mapping session (0 until set). Within a session
  /// a view that looked through the place of an object detected in that session is a miss of
  /// it; a view of another session that did is none (ObjectEvidence).
  void SetSession(std::int64_t session);

  /// Replaces keyframe poses (a pose-graph update) and regenerates the object models and the
  /// occupancy map from the stored keyframe clouds. Unknown ids or bad poses: false, map unchanged.
  /// A non-rigid correction (ReassociationConfig) replays the association of every stored
  /// observation, keyframe by keyframe, with the new poses; otherwise only objects seen from
  /// moved keyframes are rebuilt. The OctoMap is rebuilt (aside, then swapped) when any keyframe
  /// moved. A pose within 1 um and 1 urad of the current one is the same pose sent again and
  /// moves nothing. `report` may be null.
  [[nodiscard]] bool UpdatePoses(const std::map<KeyframeId, Eigen::Isometry3d>& poses,
                                 std::string* why, PoseUpdateReport* report = nullptr);

  /// Replays the association of every observation, keyframe by keyframe, with the current poses
  /// (what a non-rigid UpdatePoses does); ids follow the observations as there. For a restart
  /// that finds a pose update whose regeneration was cut off. Returns the object count after.
  int ReassociateObjects();

  /// Replaces the whole state by stored keyframes and object observations (a restart): object
  /// models are rebuilt from them; keyframe ids continue after the largest one. The OctoMap is
  /// loaded from `checkpoint` (may be null) when it is usable: OccupancyMap state at this
  /// resolution, every keyframe in it still has the pose it was integrated with (within the
  /// same-pose tolerance of UpdatePoses) and no keyframe up to its last one is missing; then only
  /// later keyframes are integrated into it. Otherwise every keyframe is integrated anew.
  RestoreOutcome Restore(std::map<KeyframeId, KeyframeRecord> keyframes,
                         std::map<ObjectId, std::vector<ObjectObservation>> observations,
                         ObjectId next_object_id, const OccupancyCheckpoint* checkpoint = nullptr);

  /// The OctoMap as a checkpoint for a later Restore (writer's thread).
  [[nodiscard]] OccupancyCheckpoint MakeOccupancyCheckpoint() const;

  /// The stored record of a keyframe, or nullptr.
  [[nodiscard]] const KeyframeRecord* FindKeyframe(KeyframeId id) const;

  /// Runs `read` on the latest published OctoMap, which does not change meanwhile (safe from any
  /// thread, see the class note).
  void ReadOccupancy(const std::function<void(const OccupancyMap&)>& read) const;

  /// The object's existence evidence from every keyframe that could see it (InventoryConfig).
  /// Visibility is cached per object model and keyframe, so repeated calls cost only the
  /// keyframes added and the objects changed since.
  [[nodiscard]] ObjectEvidence Evidence(const MapObject& object) const;

  /// Objects that pass the inventory thresholds (evidence, confidence), by id; unknown objects
  /// among them once enough views segmented them (InventoryConfig::unknown_min_views). Objects
  /// whose place was seen empty since (Changes().gone) are not among them.
  [[nodiscard]] std::vector<const MapObject*> ConfirmedObjects() const;
  /// The same with the changes already computed (Changes() projects every object into every
  /// keyframe; callers that need both compute them once).
  [[nodiscard]] std::vector<const MapObject*> ConfirmedObjects(const ObjectChanges& changes) const;

  /// What changed over the keyframes (MapperConfig::changes): removed, moved and added objects,
  /// and the ids the objects are published under. Derived from the keyframes and observations
  /// (a Restore gives the same changes); the visibility behind it is cached as for Evidence.
  [[nodiscard]] ObjectChanges Changes() const;
  /// Per-class counts of the confirmed objects, most frequent first.
  [[nodiscard]] std::vector<InventoryEntry> Inventory() const;

  [[nodiscard]] const ObjectMap& objects() const;
  /// The OctoMap; on the writer's thread only (others use ReadOccupancy).
  [[nodiscard]] const OccupancyMap& occupancy() const;
  [[nodiscard]] std::size_t num_keyframes() const;
  [[nodiscard]] const MapperConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap
