#pragma once
// Existence evidence of map objects: which keyframes could see an object, and what their
// detector said of it. An object earns its place in the inventory from the views that could have
// detected it, not from a count of detections, so the inventory does not depend on how densely
// keyframes are sampled.

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "objects/object_map.h"
#include "types/frame.h"

namespace objmap {

/// Which keyframes are one independent view: frames a few centimetres apart see the same thing,
/// so taking every frame instead of every tenth must count neither a detection, a miss nor a
/// model voxel ten times. A keyframe whose camera lies within translation_m and rotation_deg of
/// the first keyframe of the current view joins it; otherwise it starts the next view. The
/// defaults are those of the motion keyframe policy (keyframes section).
struct ViewGroupingConfig {
  float translation_m = 0.10f;
  float rotation_deg = 10.f;

  [[nodiscard]] bool IsValid(std::string* why) const;
  /// True when `T_W_C` lies within the bounds of `anchor_W_C`.
  [[nodiscard]] bool SameView(const Eigen::Isometry3d& anchor_W_C,
                              const Eigen::Isometry3d& T_W_C) const;
};

/// Which objects count in the inventory. Each independent view (ViewGroupingConfig) adds, for an
/// object it could see, the mean over its keyframes of: the detection score where the object was
/// detected, and -miss_weight x visible fraction x detectability where it was visible and not
/// detected. Keyframes that could not see the object (outside the image, occluded, no depth) add
/// nothing. The object is in the inventory when that evidence reaches min_evidence: one good close
/// view of a mug can do it, thirty views of a rare false detection among many views that see the
/// same place cannot.
struct InventoryConfig {
  /// Evidence an object needs (one detection with score s alone gives s).
  float min_evidence = 0.3f;
  /// What a view that could see the object and did not detect it costs, at full visibility and
  /// detectability. A view that detects it gains its score, so an object is kept when its
  /// detection rate r over the views that see it satisfies r * score > miss_weight * (1 - r).
  float miss_weight = 0.3f;
  /// Objects whose confidence (max accumulated class score / observations) is lower are left out
  /// (the paper's final threshold).
  float min_confidence = 0.2f;
  /// Objects with fewer observations are left out; 1 leaves it to the evidence.
  int min_observations = 1;
  /// Projected area (pixels of the box around the visible part) at which a detector is expected
  /// to find an object; smaller views cost proportionally less when they miss it. 4096 = 64 x 64,
  /// the middle of COCO's medium band: detectors' recall climbs through that band (AP_small is
  /// about half of AP_large), so a mouse or a far mug (30-50 px across) that a detector finds
  /// in a third of the views is real, while a miss of anything larger costs in full.
  float detectable_area_px = 4096.f;
  /// A keyframe saw an object absent (ObjectEvidence::last_absent) when it did not detect it
  /// while at least this much of it was in view: visible fraction x detectability (0..1].
  float absent_min_visibility = 0.5f;
  /// A model point counts as hidden when the measured depth at its pixel is more than this (plus
  /// occlusion_margin_per_m2 x depth squared, the sensor's noise) in front of it, metres.
  float occlusion_margin_m = 0.05f;
  float occlusion_margin_per_m2 = 0.01f;
  /// The visibility of an object is measured on at most this many evenly spaced model points.
  int max_visibility_points = 256;
  /// Unknown objects (UnknownObjectConfig: segmented, never named): what a view that segmented
  /// one adds to its evidence, in place of a detection score. Views that could see it and did
  /// not segment it cost as misses do.
  float unknown_view_score = 0.5f;
  /// ... and an unknown object counts only once this many independent views segmented it: a
  /// thing that persists, not a passing fragment of the segmentation.
  int unknown_min_views = 3;
  /// Confirmed unknown objects are counted in the inventory (class "unknown"). Off: they are
  /// map objects (queries by region or by class "unknown" return them) but not in the counts.
  bool count_unknown = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// When the map says an object was removed, moved or added (DetectChanges). A keyframe saw an
/// object's place empty when it had enough of it in view and measured depth well behind most of
/// its visible points: the sensor looked through where the object was. Detector misses alone
/// never remove an object (a detector misses things that are there); an object whose surface
/// the depth still shows is there, detected or not.
struct ChangeConfig {
  bool enabled = true;
  /// A point is seen through when the measured depth lies more than this (plus per_m2 x depth
  /// squared: the sensor's noise grows with the square of the range) behind it, metres.
  float see_through_margin_m = 0.02f;
  float see_through_margin_per_m2 = 0.005f;
  /// A view judges a place only when this share of the object's sample points is in view
  /// (ObjectVisibility::visible_fraction) ...
  float min_visible_fraction = 0.3f;
  /// ... covering at least this many pixels (the box around them): fewer are too few to tell
  /// an empty place from depth noise at an object's border.
  float min_projected_area_px = 400.f;
  /// A view saw the place empty when at least this share of its visible points was seen through
  /// ...
  float min_empty_fraction = 0.5f;
  /// ... and this much more than the views that detected the object there saw through (its
  /// baseline: their 90th percentile; with three such views or more). A view of a later session
  /// than those that detected it needs the baseline only, less or more than min_empty_fraction:
  /// a model that took in a rim of its support keeps the rim in view when the object goes, and a
  /// chair is seen through between its legs while it stands. 0: min_empty_fraction alone.
  float min_empty_fraction_over_present = 0.25f;
  /// Independent views (ViewGroupingConfig) that must have seen a place empty: after an
  /// object's last sighting to call it removed, before its first sighting to call it added.
  int min_empty_views = 2;
  /// A removed object and an object that appeared later are one object moved when they have
  /// one label, their models' sizes (the two largest extents of the bounding boxes) differ by at
  /// most this factor each, and they lie at least min_move_distance_m apart (nearer, the
  /// association would have kept them one object). A loose limit: a model's bounds take in what
  /// its segments took in of the neighbours (synthetic revisits: a chair's 1.3 m where it is
  /// 0.44 m, a mug's 0.46 m where it is 0.1 m), so the size tells only the absurd pairs; colour
  /// tells the rest (docs/evaluation.md, 2026-12-07: with 2.0, 0.881 / 0.855 on seeds 41/42 and
  /// 0.831 / 0.761 on 51/52; with 4 to 10, 0.909 / 0.870 and 0.892 / 0.817).
  float max_move_size_ratio = 4.0f;
  float min_move_distance_m = 0.2f;
  /// ... and their models share at least this much of their colours (the intersection of
  /// coarse colour histograms, 0..1): a red mug taken away and a white one put down elsewhere are
  /// two changes, not one move. 0: colour is not compared.
  float min_move_colour_overlap = 0.3f;
  /// A move is undecided, and the removal and the arrival are reported as such, when another
  /// arrival (or another removed object) of the label, as sure, shares within this much as many
  /// colours: look-alikes, which a guess may pair wrongly. 0: the best fit is always taken. Off by
  /// default: split moves are two errors each (docs/evaluation.md).
  float move_ambiguity_overlap_margin = 0.f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// What one keyframe could see of an object.
struct ObjectVisibility {
  /// Share of the object's sample points that project into the image with depth measured at or
  /// behind them (not hidden by something nearer); points without depth do not count.
  float visible_fraction = 0.f;
  /// Area of the pixel box around the visible points.
  float projected_area_px = 0.f;
  /// Share of the visible points with depth measured well behind them (ChangeConfig's
  /// see-through margin): the view looked through the place where those points were.
  float empty_fraction = 0.f;
};

/// Evenly spaced points of the object's model, at most `max_points`.
[[nodiscard]] std::vector<Eigen::Vector3f> VisibilitySamples(const MapObject& object,
                                                             int max_points);

/// How much of `samples_W` (points of an object within `bounds_W`) a keyframe with this pose,
/// intrinsics and depth (millimetres, row-major, 0: none) sees, and how much of that it sees
/// through (`changes`' margins).
[[nodiscard]] ObjectVisibility VisibilityIn(const std::vector<Eigen::Vector3f>& samples_W,
                                            const Eigen::AlignedBox3f& bounds_W,
                                            const Eigen::Isometry3d& T_W_C,
                                            const CameraIntrinsics& intrinsics,
                                            const std::vector<std::uint16_t>& depth_mm,
                                            const InventoryConfig& config,
                                            const ChangeConfig& changes = ChangeConfig{});

/// True when the keyframe saw the object's place empty (ChangeConfig).
[[nodiscard]] bool SawPlaceEmpty(const ObjectVisibility& seen, const ChangeConfig& config);
/// True when the keyframe had enough of the object in view to judge its place
/// (ChangeConfig::min_visible_fraction, min_projected_area_px).
[[nodiscard]] bool CouldJudgePlace(const ObjectVisibility& seen, const ChangeConfig& config);

/// Groups keyframes (ascending ids, with their poses) into independent views (ViewGroupingConfig).
/// Returns the view index of each keyframe, from 0 up.
[[nodiscard]] std::map<KeyframeId, int> IndependentViews(
    const std::map<KeyframeId, Eigen::Isometry3d>& poses, const ViewGroupingConfig& config);

/// An object's evidence and what it was made of.
struct ObjectEvidence {
  float evidence = 0.f;
  int keyframes_seeing = 0;  ///< keyframes that saw it (visible) or detected it
  int views_seeing = 0;      ///< independent views among them
  int views_detecting = 0;   ///< independent views with at least one detection of it
  /// The newest keyframe that had it in view (absent_min_visibility) and did not detect it:
  /// where it should have been seen and was not; 0: none.
  KeyframeId last_absent = 0;
};

/// The mapping session of a keyframe (KeyframeRecord::session; 0 when not known).
using KeyframeSessionLookup = std::function<std::int64_t(KeyframeId)>;

/// The evidence of `object` from its visibility in each keyframe (keyframes missing from
/// `visibility` saw nothing of it), the keyframes' independent views and their mapping sessions.
/// For a named object only its detections count as detected (views that only segmented it are
/// misses of the detector); for an unknown object, its segmentations (unknown_view_score). A view
/// that saw the object's place and did not detect it is a miss, except for the part of the place it
/// looked through (ObjectVisibility::empty_fraction) in a session without a detection of the
/// object: the object may have been put there or taken away between sessions, not within one.
[[nodiscard]] ObjectEvidence EvidenceOf(const MapObject& object,
                                        const std::map<KeyframeId, ObjectVisibility>& visibility,
                                        const std::map<KeyframeId, int>& view_of_keyframe,
                                        const KeyframeSessionLookup& session_of,
                                        const InventoryConfig& config);

}  // namespace objmap
