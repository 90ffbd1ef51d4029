#pragma once
// Keyframes of a later session that add nothing to the map: the same place seen again from
// nearly the same view, with nothing changed. Storing each of them would grow the map with every
// patrol of an unchanged room; the map keeps instead that the view was seen again (a revisit:
// session, time, pose), which is what the objects' last sightings need, and nothing that
// regeneration would rebuild differently.
//
// A keyframe repeats the stored views when the depth of nearly all its pixels is what those
// views measured (within the sensor's noise): little of it is new to them. And no patch of its
// pixels shows a change as large as the smallest view a change is judged on
// (ChangeConfig::min_projected_area_px): something put down (a stored view looked through the
// place where the keyframe now measures a surface) or something taken away (the keyframe looks
// through a surface a stored view measured). A cup is a few hundredths of a frame, so the share
// alone would not see it go. What a stored view could not see, hidden behind what it measured,
// is new to it, not a change. The test is geometric only: the depth shows every change the
// change detection can act on, because that acts on depth too.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "types/detection.h"
#include "types/frame.h"

namespace objmap {

/// Config section `thinning`.
struct RevisitThinningConfig {
  /// Off: every keyframe is mapped and stored, as before sessions were thinned.
  bool enabled = true;
  /// Stored keyframes compared with a new one: from sessions before the keyframe's own (a
  /// session's own keyframes are the client's choice of keyframes, spaced by its policy), with
  /// the camera within this distance and its optical axis within this angle of the new one's.
  double max_distance_m = 0.5;
  double max_angle_deg = 30.0;
  /// At most this many of them, nearest first (together they may explain a view none covers).
  int max_views = 4;
  /// Every stride-th pixel in both directions is compared.
  int pixel_stride = 4;
  /// A pixel is explained when a stored view measured its point within this distance along its
  /// own ray (plus per_m2 x depth squared: the sensor's noise), at the pixel it projects to or
  /// one of its 8 neighbours (depth edges move by a pixel between views).
  float depth_margin_m = 0.02f;
  float depth_margin_per_m2 = 0.005f;
  /// Repeated when at least this share of the pixels with depth is explained (the rest: new to
  /// the stored views, as the strip at the border a small step brings into view) ...
  float min_explained_fraction = 0.95f;
  /// ... and no 8-connected patch of pixels that show a change covers more than this many
  /// pixels (full resolution): the smallest view a change is judged on (ChangeConfig).
  float max_changed_patch_px = 400.f;
  /// ... and at least this share of the image has depth (an almost blank frame says little).
  float min_depth_fraction = 0.2f;
  /// A keyframe that passes the other tests with a smaller explained share, at least this one,
  /// repeats stored views in part (a later session's path a little farther or higher sees
  /// around their borders): it is mapped and stored with the depth of its unexplained pixels
  /// only, the part new to the map, and the part it repeats is a revisit. 1: such keyframes are
  /// mapped whole.
  float min_partial_explained_fraction = 0.3f;
  /// ... keeping the depth of a detection's whole box when at least this share of its compared
  /// pixels is new, and leaving out the whole box's depth otherwise: an object is segmented
  /// whole or not at all (a fragment of a known object, cut where the stored views' part ends,
  /// would not join it and become a second object) ...
  float min_new_fraction_in_box = 0.1f;
  /// ... a kept box with this much of its size around it on each side: the surface it stands
  /// on, which the segmentation tells it from.
  float box_margin = 1.0f;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// A stored view to compare with: its pose, intrinsics and depth (millimetres, row-major, 0:
/// none), borrowed.
struct StoredView {
  std::int64_t keyframe_id = 0;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  const CameraIntrinsics* intrinsics = nullptr;
  const std::vector<std::uint16_t>* depth_mm = nullptr;
};

/// What the stored views explain of a new keyframe.
struct ViewCoverage {
  int depth_pixels = 0;  ///< compared pixels with depth
  float explained_fraction = 0.f;
  float largest_changed_patch_px = 0.f;  ///< full-resolution pixels
  /// The view that explained most of the pixels (0: none explained any).
  std::int64_t best_keyframe = 0;
  bool repeated = false;  ///< the config's three tests hold
  /// Not repeated, but only for a smaller explained share (min_partial_explained_fraction).
  bool repeated_in_part = false;
  /// Per compared pixel (every stride-th in both directions, row-major, grid_cols x grid_rows):
  /// 1 where a stored view explained it.
  std::vector<std::uint8_t> explained;
  int grid_cols = 0, grid_rows = 0, stride = 1;
};

/// True when the stored view lies within the config's distance and angle of `T_W_C`.
[[nodiscard]] bool IsNearbyView(const Eigen::Isometry3d& stored_W_C, const Eigen::Isometry3d& T_W_C,
                                const RevisitThinningConfig& config);

/// Removes the depth of the pixels `coverage` found explained (each compared pixel stands for
/// the stride x stride block it starts): what is left is the part new to the stored views.
/// Each of `boxes` (the keyframe's detections, depth pixels) keeps all its depth, with the
/// margin around it, when at least min_new_fraction_in_box of its compared pixels is new, and
/// loses all of it otherwise.
void KeepUnexplained(const ViewCoverage& coverage, const std::vector<BoundingBox2D>& boxes,
                     const RevisitThinningConfig& config, DepthImage* depth);

/// How much of the new keyframe (`depth` in metres, pose, intrinsics) `views` explain.
[[nodiscard]] ViewCoverage CoverageOf(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                                      const Eigen::Isometry3d& T_W_C,
                                      const std::vector<StoredView>& views,
                                      const RevisitThinningConfig& config);

}  // namespace objmap
