#pragma once
// Keyframes of a later session that add nothing to the map: the same place seen again from
// nearly the same view, with nothing changed. Storing each of them would grow the map with every
// patrol of an unchanged room; the map keeps instead that the view was seen again (a revisit:
// session, time, pose), which is what the objects' last sightings need, and nothing that
// regeneration would rebuild differently.
//
// A keyframe repeats the stored views when the depth of nearly all its pixels is what those
// views measured (within the sensor's noise): little of it is new to them. And no patch of its
// pixels where a stored view measured something else (something taken away: the view now sees
// through where it stood; something put down in front) is as large as the smallest view a change
// is judged on (ChangeConfig::min_projected_area_px): a cup is a few hundredths of a frame, so
// the share alone would not see it go. The test is geometric only: the depth shows every change
// the change detection can act on, because that acts on depth too.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

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
  /// Repeated when at least this share of the pixels with depth is explained (the rest: seen by
  /// no stored view, as the strip at the border a small step brings into view, or contradicted)
  /// ...
  float min_explained_fraction = 0.95f;
  /// ... and no 8-connected patch of contradicted pixels (a stored view measured something
  /// nearer or farther there, none measured the point) covers more than this many pixels (full
  /// resolution): the smallest view a change is judged on (ChangeConfig).
  float max_contradicted_patch_px = 400.f;
  /// ... and at least this share of the image has depth (an almost blank frame says little).
  float min_depth_fraction = 0.2f;

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
  float largest_contradicted_patch_px = 0.f;  ///< full-resolution pixels
  /// The view that explained most of the pixels (0: none explained any).
  std::int64_t best_keyframe = 0;
  bool repeated = false;  ///< the config's three tests hold
};

/// True when the stored view lies within the config's distance and angle of `T_W_C`.
[[nodiscard]] bool IsNearbyView(const Eigen::Isometry3d& stored_W_C, const Eigen::Isometry3d& T_W_C,
                                const RevisitThinningConfig& config);

/// How much of the new keyframe (`depth` in metres, pose, intrinsics) `views` explain.
[[nodiscard]] ViewCoverage CoverageOf(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                                      const Eigen::Isometry3d& T_W_C,
                                      const std::vector<StoredView>& views,
                                      const RevisitThinningConfig& config);

}  // namespace objmap
