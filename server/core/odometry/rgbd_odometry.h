#pragma once
// Camera tracking from the RGB-D frames alone, for sources without poses (a bare camera, a
// recording or a bag without them): each frame is tracked against a keyframe by ORB features
// with depth, PnP in RANSAC and a least-squares refinement on the inliers.

#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "posegraph/pose_graph.h"
#include "types/frame.h"

namespace objmap {

struct OdometryConfig {
  /// ORB keypoints detected per frame.
  int features = 1000;
  /// A match is kept when its distance is below this fraction of the second best (Lowe).
  float match_ratio = 0.8f;
  /// Keypoints whose depth lies outside [min_depth_m, max_depth_m] have no 3D point (noise of
  /// structured-light sensors grows with the square of the range).
  double min_depth_m = 0.2;
  double max_depth_m = 4.0;
  /// PnP in RANSAC: reprojection tolerance of an inlier, pixels, and iterations.
  double ransac_reprojection_px = 3.0;
  int ransac_iterations = 300;
  /// A pose needs at least this many inliers; fewer: the frame is not tracked (blank wall,
  /// dark, blurred or too fast), and no pose is given for it.
  int min_inliers = 30;
  /// Motion between consecutive tracked frames beyond these is refused as implausible (a wrong
  /// PnP solution), so that no wild pose enters the map.
  double max_step_m = 0.3;
  double max_step_deg = 30.0;
  /// The frame becomes the keyframe that later frames are tracked against when it is this far
  /// from the current keyframe, or when fewer inliers than keyframe_min_inliers remain.
  double keyframe_distance_m = 0.1;
  double keyframe_angle_deg = 10.0;
  int keyframe_min_inliers = 100;
  /// Loop closure: when a keyframe is added, up to loop_candidates keyframes at least
  /// loop_min_keyframe_gap older, within loop_search_radius_m and loop_search_angle_deg of it,
  /// are matched to it; each with loop_min_inliers PnP inliers adds a loop edge, and the pose
  /// graph of the keyframes (PoseGraph) is optimized and every keyframe moved. 0 candidates: no
  /// loop closure.
  int loop_candidates = 3;
  int loop_min_keyframe_gap = 10;
  double loop_search_radius_m = 1.0;
  double loop_search_angle_deg = 45.0;
  int loop_min_inliers = 60;
  /// Loop candidates by appearance, wherever the drifted pose estimate puts them: the older
  /// keyframes whose strongest appearance_descriptors ORB descriptors match most of the new
  /// keyframe's (at least loop_min_inliers matches), up to loop_appearance_candidates of them
  /// besides those near the estimate; verified like the others (PnP, ICP, the pose graph's
  /// robust loss). 0: candidates by pose only.
  int loop_appearance_candidates = 2;
  int appearance_descriptors = 300;
  /// The appearance candidates are chosen among the keyframes an index of their descriptors
  /// (AppearanceIndex: hashed bits, votes) ranks most alike, this many, instead of among every
  /// older keyframe: the search then costs the same whatever the map's size. 0: every keyframe.
  int appearance_shortlist = 10;
  /// Loop search, verification and graph solve on a thread of their own: Track hands each new
  /// keyframe over and returns, and the loops found move the keyframes at the start of a later
  /// Track (TrackingReport::loops_closed says when). For a live camera, whose frames must not
  /// wait on a solve. Off: each keyframe's loops are closed before its Track returns, so the
  /// same frames always give the same trajectory (recordings, datasets, tests).
  bool background_loop_closure = false;
  /// Standard deviations of a keyframe-to-keyframe measurement (odometry and loop edges).
  double edge_sigma_m = 0.01;
  double edge_sigma_deg = 0.5;
  /// With depth_refinement: each edge's information from the dense step's Hessian
  /// (AlignmentInformation; edge_sigma in the directions the depth fixes, next to nothing in
  /// those it leaves free: a wall's plane) plus the features' own (edge_feature_sigma in every
  /// direction: the features fix what the depth leaves free). Off: edge_sigma in every
  /// direction. On redkitchen: 2.75 cm ATE against 2.77 (docs/benchmarks.md); the depth's
  /// Hessian alone, without the features' share, gave 3.57 cm.
  bool edge_information_from_alignment = true;
  double edge_feature_sigma_m = 0.02;
  double edge_feature_sigma_deg = 1.0;
  /// Dense refinement of every feature pose by point-to-plane ICP of the two depth images
  /// (AlignDepth), on cells of coarse then fine step pixels. Feature depths are read at edges,
  /// where depth is worst; the dense step uses every smooth surface and lowers the drift (on
  /// 7-Scenes redkitchen the ATE falls by a third, docs/benchmarks.md).
  bool depth_refinement = true;
  int depth_refinement_coarse_step = 8;
  int depth_refinement_fine_step = 4;
  int depth_refinement_coarse_iterations = 10;
  int depth_refinement_fine_iterations = 20;
  /// Fewer cell correspondences than this: the feature pose is kept.
  int depth_refinement_min_correspondences = 100;
  /// A refinement that moves the feature pose farther than this is ICP slid along a plane or
  /// caught by another surface: the feature pose is kept.
  double depth_refinement_max_correction_m = 0.2;
  double depth_refinement_max_correction_deg = 15.0;
  /// Keyframes tried, nearest to the last pose first, when tracking against the current one
  /// fails (relocalisation).
  int relocalisation_keyframes = 8;
  /// ... and the keyframes anywhere in the map that look most like the frame (an appearance
  /// index over every keyframe, the saved map's included, then the ratio test on the strongest
  /// descriptors), this many: how a session that starts elsewhere is placed.
  int relocalisation_appearance_candidates = 4;
  /// Without a recent tracked pose (a new session, a restart, tracking lost) nothing checks a
  /// relocalised pose against the motion, so the fit itself must be strong: at least this many
  /// PnP inliers and, with depth_refinement, the dense step agreeing with the features (a wrong
  /// place that shares a few features with the frame rarely passes both).
  int relocalisation_min_inliers = 60;
  /// ... or this many when another keyframe's fit (min_inliers) places the camera within the
  /// consensus limits of it (a view the first session saw from farther or higher shares fewer
  /// features with each keyframe; synthetic revisits: desk sessions placed 1 of 5 at 60 alone,
  /// 5 of 5 at 40).
  int relocalisation_corroborated_min_inliers = 40;
  /// ... and every other keyframe that fits the frame (min_inliers) agreeing with the strongest
  /// within these: a repeated pattern (identical objects in a row, along a wall that leaves the
  /// depth free in that direction) fits strongly at a wrong place, but other keyframes then
  /// place the camera elsewhere (synthetic revisits: wrong placements 6-15 cm from each other's;
  /// redkitchen's correct ones within 2-3 cm, the reference poses' own disagreement).
  double relocalisation_consensus_m = 0.05;
  double relocalisation_consensus_deg = 5.0;
  /// When no single keyframe places the frame: its features matched to the points of the
  /// relocalisation_map_candidates map keyframes that look most like it (appearance index), all
  /// in the map's frame, and one PnP RANSAC (relocalisation_map_ransac_iterations) over them, as
  /// a camera is placed in a map of points. A view from farther or higher than any stored one
  /// shares 30-65 right matches with each keyframe but 200-400 with them together (synthetic
  /// revisits, lab 51). Placed with at least relocalisation_map_min_inliers inliers (distinct
  /// keypoints of the frame), relocalisation_map_keyframe_min_inliers or more from each of at
  /// least relocalisation_map_min_keyframes keyframes, and the dense step against the keyframe
  /// with the most agreeing within the consensus limits (a slide along a plane is refused).
  /// Sessions of rooms the map does not hold reached at most 19 such inliers (80 sessions,
  /// docs/evaluation.md). 0 candidates: off.
  int relocalisation_map_candidates = 10;
  int relocalisation_map_ransac_iterations = 1000;
  int relocalisation_map_min_inliers = 60;
  int relocalisation_map_keyframe_min_inliers = 10;
  int relocalisation_map_min_keyframes = 3;
  /// A frame that can be neither tracked nor placed in the map (a session starting where its
  /// first views share too little with the map's, tracking lost mid-session) starts a
  /// provisional fragment: it and the frames after it are tracked among themselves in a frame of
  /// their own (TrackingStatus::kProvisional), and every frame of the fragment is tried against
  /// the map's keyframes by appearance (the strict test above). The first that is placed attaches
  /// the fragment: each of its keyframes moves into the map's frame, nothing is dropped. A
  /// fragment of a place the map does not hold stays apart. Off: such frames are kLost.
  bool provisional_fragments = true;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

enum class TrackingStatus {
  kInitialized,  ///< the first frame: the world frame is its camera frame
  kTracked,      ///< pose found against the current keyframe
  kRelocalized,  ///< pose found against another keyframe after tracking failed
  /// Pose found, but in a provisional fragment's frame (`fragment` > 0), not yet placed in the
  /// map's (OdometryConfig::provisional_fragments); T_W_C is in that frame.
  kProvisional,
  kLost,  ///< no pose: `why` says what failed
};

/// What tracking one frame found.
struct TrackingReport {
  TrackingStatus status = TrackingStatus::kLost;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< valid unless kLost
  int keypoints = 0;       ///< ORB keypoints in the frame
  int matches = 0;         ///< to the keyframe tracked against, after the ratio test
  int inliers = 0;         ///< of PnP RANSAC
  double reprojection_rmse_px = 0.0;  ///< of the PnP inliers, after least squares
  bool depth_refined = false;         ///< the dense depth step moved the feature pose
  double depth_rmse_m = 0.0;          ///< point-to-plane residual of the dense step
  int reference_keyframe = -1;        ///< index of the keyframe tracked against
  bool new_keyframe = false;          ///< this frame became a keyframe (reference_keyframe)
  /// Loop edges kept (every keyframe then moved): those closed for this frame's keyframe, or with
  /// background_loop_closure those the worker found since the last frame.
  int loops_closed = 0;
  /// Loop-closure detection, verification and graph solve for those loops; part of `ms`
  /// unless they ran in the background.
  double loop_ms = 0.0;
  double ms = 0.0;                    ///< time spent
  /// The frame T_W_C is in: 0 the map's, > 0 a provisional fragment's (kProvisional).
  int fragment = 0;
  /// This frame placed provisional fragment `attached_fragment` (> 0) in the map: every keyframe
  /// of it moved into the map's frame (KeyframePose), and T_W_C is the map's. -1: none.
  int attached_fragment = -1;
  std::string why;  ///< kLost: the reason; kProvisional: why not placed
};

/// Thread-safety: none (one camera, one thread); with background_loop_closure a thread of its
/// own searches loops, and every method but the constructor stays on the caller's thread.
class RgbdOdometry {
 public:
  /// `config` must satisfy IsValid().
  explicit RgbdOdometry(const OdometryConfig& config);
  ~RgbdOdometry();
  RgbdOdometry(RgbdOdometry&&) noexcept;
  RgbdOdometry& operator=(RgbdOdometry&&) noexcept;

  /// Tracks one frame (its T_W_C is ignored). Frames must come in time order; a frame without
  /// colour or depth, or whose sizes differ from the intrinsics, is kLost with the reason.
  TrackingReport Track(const RgbdFrame& frame);

  /// Starts tracking from a frame whose pose is known (its T_W_C): it becomes the first keyframe,
  /// where later frames are tracked from. How tracking resumes on a map made before (a server
  /// restart: the newest stored keyframe). Only before the first Track or seed; false with the
  /// reason otherwise, or when the frame has too few keypoints with depth.
  bool StartFromKnownPose(const RgbdFrame& frame, std::string* why);

  /// Adds a keyframe of a saved map at its known pose (frame.T_W_C), before the first Track: it
  /// is held where it is in every pose-graph solve (the map is settled; a new session joins it),
  /// and relocalisation finds it by appearance and by distance. Tracking resumes at the last one
  /// added, but only after a strong fit (relocalisation_min_inliers), since the camera may be
  /// anywhere. False with the reason when tracking has started or the frame has too few
  /// keypoints with depth (the keyframe is then left out).
  bool AddMapKeyframe(const RgbdFrame& frame, std::string* why);

  /// With background_loop_closure: waits for the loop searches under way and applies what they
  /// found (the end of a recording). Returns the loops closed by them; 0 without the option.
  int FinishLoopClosure();

  [[nodiscard]] int num_keyframes() const;
  /// The keyframe's current pose (moved by every loop closure and by its fragment's attachment).
  [[nodiscard]] Eigen::Isometry3d KeyframePose(int keyframe) const;
  /// The frame the keyframe's pose is in: 0 the map's, > 0 a provisional fragment not attached.
  [[nodiscard]] int KeyframeFragment(int keyframe) const;
  /// Provisional fragments started and, of them, those attached to the map so far.
  [[nodiscard]] int fragments_started() const;
  [[nodiscard]] int fragments_attached() const;
  [[nodiscard]] int loops_closed() const;
  /// The pose graph's edges between keyframes (node = keyframe index): odometry and the loops
  /// kept, so that a caller can add constraints of its own (ConstrainTrajectory).
  [[nodiscard]] const std::vector<PoseGraphEdge>& graph_edges() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

[[nodiscard]] const char* TrackingStatusName(TrackingStatus status);

}  // namespace objmap
