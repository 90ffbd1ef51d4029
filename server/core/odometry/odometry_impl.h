#pragma once
// RgbdOdometry's insides, shared by its source files: the features of a frame and a keyframe,
// a fit against one keyframe, loop-search jobs, and RgbdOdometry::Impl. Private to
// objmap_odometry (rgbd_odometry.cc: tracking; odometry_loops.cc: loop closure;
// odometry_placement.cc: placing a camera that may be anywhere, provisional fragments).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>
#include <thread>
#include <vector>

#include "odometry/appearance_index.h"
#include "odometry/depth_alignment.h"
#include "odometry/rgbd_odometry.h"
#include "posegraph/pose_graph.h"

namespace objmap {
namespace odometry_detail {

using Clock = std::chrono::steady_clock;

constexpr double kDegPerRad = 57.29577951308232;

inline double AngleDeg(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle() * kDegPerRad;
}

// ORB keypoints of one frame, with their 3D points where the depth is usable.
struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;                // one row per keypoint
  std::vector<cv::Point3f> points_C;  // per keypoint; valid[i] says whether it has one
  std::vector<std::uint8_t> valid;
  DepthGrid coarse_depth;  // for the dense refinement (empty without it)
  DepthGrid fine_depth;
};

// A frame that later frames are tracked against: only its keypoints with a 3D point. Immutable
// once made, so that the loop-closure worker reads it while tracking goes on; its pose lives
// apart (Impl::poses), since loop closures move it.
struct Keyframe {
  std::vector<cv::Point3f> points_K;
  cv::Mat descriptors;
  cv::Mat strongest_descriptors;  // its appearance: the strongest keypoints with depth
  DepthGrid coarse_depth;
  DepthGrid fine_depth;
};

// What PnP found for a frame against one keyframe.
struct PoseFit {
  bool ok = false;
  Eigen::Isometry3d T_K_C = Eigen::Isometry3d::Identity();
  int matches = 0;
  int inliers = 0;
  double rmse_px = 0.0;
  bool depth_refined = false;
  double depth_rmse_m = 0.0;
  // The dense step's last Hessian, for the information of T_K_C as an edge (made only for the
  // fits that become edges: EdgeInformationOf).
  DepthAlignmentReport alignment;
  std::string why;
};

// The descriptors of the `count` keypoints with depth and the strongest response: a frame's
// appearance, cheap to compare with another's.
inline cv::Mat StrongestDescriptors(const FrameFeatures& features, int count) {
  std::vector<int> order;
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    if (features.valid[i]) order.push_back(static_cast<int>(i));
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return features.keypoints[static_cast<std::size_t>(a)].response >
           features.keypoints[static_cast<std::size_t>(b)].response;
  });
  if (static_cast<int>(order.size()) > count) order.resize(static_cast<std::size_t>(count));
  cv::Mat strongest;
  for (int i : order) strongest.push_back(features.descriptors.row(i));
  return strongest;
}

using KeyframeList = std::vector<std::shared_ptr<const Keyframe>>;

// Adds keyframes *indexed..last to `index` by their strongest descriptors; *indexed then is
// last + 1, so that each keyframe joins an index once.
inline void IndexKeyframes(const KeyframeList& keyframes, int last, AppearanceIndex* index,
                           int* indexed) {
  for (; *indexed <= last; ++*indexed) {
    const cv::Mat& descriptors =
        keyframes[static_cast<std::size_t>(*indexed)]->strongest_descriptors;
    if (descriptors.rows > 0 && descriptors.isContinuous()) {
      index->Add(*indexed, descriptors.ptr<std::uint8_t>(), descriptors.rows);
    }
  }
}

// Of `candidates` (those `eligible`), the at most `count` keyframes whose strongest
// descriptors pass the ratio test against `mine` most often, and at least `min_matches` times;
// the most matched first.
inline std::vector<int> MostMatched(const cv::Mat& mine, const std::vector<int>& candidates,
                                    const std::function<bool(int)>& eligible,
                                    const KeyframeList& keyframes, float match_ratio,
                                    int min_matches, int count) {
  const cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<std::pair<int, int>> scored;  // (matches, keyframe)
  for (const int k : candidates) {
    if (!eligible(k)) continue;
    const cv::Mat& theirs = keyframes[static_cast<std::size_t>(k)]->strongest_descriptors;
    if (theirs.rows < 2) continue;
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(mine, theirs, knn, 2);
    int matches = 0;
    for (const auto& pair : knn) {
      matches += pair.size() == 2 && pair[0].distance < match_ratio * pair[1].distance;
    }
    if (matches >= min_matches) scored.emplace_back(matches, k);
  }
  std::sort(scored.rbegin(), scored.rend());
  std::vector<int> best;
  for (std::size_t i = 0; i < scored.size() && static_cast<int>(i) < count; ++i) {
    best.push_back(scored[i].second);
  }
  return best;
}

inline Eigen::Isometry3d FromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(R, rotation);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation;
  T.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T;
}

// PnP RANSAC (EPnP) of image points on 3D points. RANSAC draws from OpenCV's per-thread
// generator: a fixed seed per solve makes the trajectory the same whichever thread tracks and
// whatever ran on it before (reproducible runs and tests); the caller's generator state is given
// back. False when RANSAC finds no pose.
inline bool SeededPnPRansac(const std::vector<cv::Point3f>& object_points,
                            const std::vector<cv::Point2f>& image_points, const cv::Matx33d& camera,
                            int iterations, double reprojection_px, cv::Mat* rvec, cv::Mat* tvec,
                            std::vector<int>* inliers) {
  cv::RNG& generator = cv::theRNG();
  const std::uint64_t caller_state = generator.state;
  generator.state = 0x9E3779B97F4A7C15ull;
  const bool solved = cv::solvePnPRansac(
      object_points, image_points, camera, cv::noArray(), *rvec, *tvec, false, iterations,
      static_cast<float>(reprojection_px), 0.999, *inliers, cv::SOLVEPNP_EPNP);
  generator.state = caller_state;
  return solved;
}

// Least squares on RANSAC's inliers (its pose comes from a minimal set); returns their
// reprojection RMSE, pixels.
inline double RefineOnInliers(const std::vector<cv::Point3f>& object_points,
                              const std::vector<cv::Point2f>& image_points,
                              const std::vector<int>& inliers, const cv::Matx33d& camera,
                              cv::Mat* rvec, cv::Mat* tvec) {
  std::vector<cv::Point3f> inlier_object;
  std::vector<cv::Point2f> inlier_image;
  for (const int i : inliers) {
    inlier_object.push_back(object_points[static_cast<std::size_t>(i)]);
    inlier_image.push_back(image_points[static_cast<std::size_t>(i)]);
  }
  cv::solvePnPRefineLM(inlier_object, inlier_image, camera, cv::noArray(), *rvec, *tvec);
  std::vector<cv::Point2f> projected;
  cv::projectPoints(inlier_object, *rvec, *tvec, camera, cv::noArray(), projected);
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < projected.size(); ++i) {
    const cv::Point2f d = projected[i] - inlier_image[i];
    sum_sq += d.dot(d);
  }
  return std::sqrt(sum_sq / static_cast<double>(std::max<std::size_t>(1, projected.size())));
}

// A loop search for one new keyframe: its features and everything it reads, copied when it
// starts (keyframes are shared, being immutable), so that tracking goes on meanwhile.
struct LoopJob {
  int newest = -1;
  std::shared_ptr<const FrameFeatures> features;
  CameraIntrinsics intrinsics;
  std::vector<std::shared_ptr<const Keyframe>> keyframes;  // 0..newest
  std::vector<Eigen::Isometry3d> poses;                    // 0..newest
  std::vector<int> fragments;                              // 0..newest: Impl::fragment_of
  std::vector<PoseGraphEdge> edges;
};

// What a loop search found: with loops, every keyframe's pose up to the job's newest after the
// solve, and the graph's edges (the job's, the loops added, wrong loops dropped).
struct LoopClosure {
  int newest = -1;
  int loops = 0;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<PoseGraphEdge> edges;
  std::size_t job_edges = 0;   // edges the job started from: later ones were added meanwhile
  std::vector<int> fragments;  // the job's: only keyframes in the map's frame (0) were solved
  double ms = 0.0;
};

}  // namespace odometry_detail

using odometry_detail::FrameFeatures;
using odometry_detail::Keyframe;
using odometry_detail::LoopClosure;
using odometry_detail::LoopJob;
using odometry_detail::PoseFit;

struct RgbdOdometry::Impl {
  explicit Impl(const OdometryConfig& c) : config(c), orb(cv::ORB::create(c.features)) {}
  ~Impl() { StopWorker(); }

  OdometryConfig config;
  cv::Ptr<cv::ORB> orb;
  // Written by the tracking thread only, under `mutex` (the worker copies them under it).
  std::vector<std::shared_ptr<const Keyframe>> keyframes;
  std::vector<Eigen::Isometry3d> poses;
  // The frame each keyframe's pose is in: 0 the map's, > 0 a provisional fragment's
  // (OdometryConfig::provisional_fragments). Poses compare only within one fragment.
  std::vector<int> fragment_of;
  int current_fragment = 0;  // the fragment of current_keyframe
  int fragments_started = 0;
  int fragments_attached = 0;
  // Pose graph over the keyframes: an odometry edge from each keyframe to the one it was
  // tracked from, loop edges to older keyframes that see the same place.
  std::vector<PoseGraphEdge> edges;
  int loops_closed = 0;
  int current_keyframe = -1;
  bool has_last = false;
  Eigen::Isometry3d last_T_W_C = Eigen::Isometry3d::Identity();
  // The last pose came from a tracked frame (not from a saved map's keyframe): relocalisation
  // may then trust a weaker fit, checked against the motion.
  bool last_tracked = false;
  // Keyframes [0, map_keyframes) are a saved map's (AddMapKeyframe): held in every solve.
  int map_keyframes = 0;
  bool tracking_started = false;
  // Relocalisation's own appearance index (the loop search's may be on the worker thread).
  AppearanceIndex relocalisation_index;
  int relocalisation_indexed = 0;

  // Background loop closure (OdometryConfig::background_loop_closure): the worker takes one
  // job at a time, and waits until its result is applied before it starts the next, so that
  // each search starts from every loop found before.
  std::mutex mutex;
  std::condition_variable wake;     // worker: a job, or stop
  std::condition_variable settled;  // FinishLoopClosure: the worker is idle or has a result
  std::deque<LoopJob> jobs;
  std::vector<LoopClosure> results;
  bool busy = false;
  bool stop = false;
  std::thread worker;

  bool Extract(const RgbdFrame& frame, FrameFeatures* features, std::string* why);
  PoseFit Fit(const FrameFeatures& features, const Keyframe& keyframe,
              const CameraIntrinsics& K) const;
  // Adds a keyframe in current_fragment's frame and makes it the current one.
  void AddKeyframe(const FrameFeatures& features, const Eigen::Isometry3d& T_W_C);
  // Starts provisional fragment number fragments_started + 1 with the frame as its first
  // keyframe, at the identity of the fragment's frame. False when too few keypoints have depth.
  bool StartFragment(const FrameFeatures& features);
  // Tries to place the frame, tracked at T_F_C in the current provisional fragment, in the map
  // by the map's keyframes that look like it (strict test). Placed: every keyframe of the
  // fragment moves into the map's frame, the frame's pose in it is *T_W_C and *fit, *reference
  // say against which keyframe.
  bool AttachFragment(const FrameFeatures& features, const CameraIntrinsics& K,
                      const Eigen::Isometry3d& T_F_C, Eigen::Isometry3d* T_W_C, PoseFit* fit,
                      int* reference, std::string* why);
  // A fit strong enough to place a camera that may be anywhere (relocalisation_min_inliers, the
  // dense step agreeing with the features).
  bool Strong(const PoseFit& fit) const;
  // A frame's fit against one keyframe, for a placement by several.
  struct Vote {
    int keyframe = -1;
    PoseFit fit;
  };
  // Of `votes` (ok fits of one frame), the one with the most inliers that is strong alone
  // (relocalisation_min_inliers) or corroborated (relocalisation_corroborated_min_inliers and
  // another vote agreeing), unless another vote places the camera farther than the consensus
  // limits from it (then -1 and `why`); -1 without one.
  int Consensus(const std::vector<Vote>& votes, std::string* why) const;
  // Two poses of one camera `apart` (a^-1 b) within the relocalisation consensus limits.
  bool WithinConsensus(const Eigen::Isometry3d& apart) const;
  // Consensus, and if it places the camera, again with the keyframes nearest that place (up to
  // relocalisation_keyframes, in its frame) voting too: the keyframes a wrong placement among
  // look-alikes would skip. Adds their votes to `votes`; returns the index of the chosen one.
  int ConsensusWithNeighbours(const FrameFeatures& features, const CameraIntrinsics& K,
                              std::vector<Vote>* votes, std::string* why);
  // When no vote places the frame: one PnP over the points of the map keyframes that look most
  // like it (OdometryConfig::relocalisation_map_candidates). Placed: the fit against the
  // keyframe with the most inliers is appended to `votes` and its index returned; -1 and `why`
  // otherwise.
  int PlaceByMapPoints(const FrameFeatures& features, const CameraIntrinsics& K,
                       std::vector<Vote>* votes, std::string* why);
  // The first keyframe, at T_W_C: tracking starts from it. False when too few keypoints have
  // depth.
  bool Start(const FrameFeatures& features, const Eigen::Isometry3d& T_W_C, std::string* why);
  // Dense step after PnP: moves T_K_C when the depth alignment succeeds within the limits.
  void RefineByDepth(const FrameFeatures& features, const Keyframe& keyframe,
                     Eigen::Isometry3d* T_K_C, PoseFit* fit) const;
  // The frame is tracked at T_W_C by `fit`: the report says so and later frames start there.
  void Accept(const PoseFit& fit, const Eigen::Isometry3d& T_W_C, TrackingReport* report);
  void AddOdometryEdge(int from, int to, const Eigen::Matrix<double, 6, 6>& information);
  // The information of a fit's T_K_C as an edge (OdometryConfig::edge_information_from_alignment).
  Eigen::Matrix<double, 6, 6> EdgeInformationOf(const PoseFit& fit) const;

  // The job for the newest keyframe, from the current state (caller holds `mutex` or is the
  // only thread).
  LoopJob MakeLoopJob(std::shared_ptr<const FrameFeatures> features,
                      const CameraIntrinsics& K) const;
  // Older keyframes (at least loop_min_keyframe_gap before the newest, not in `already`) that
  // look most like it, best first, up to loop_appearance_candidates.
  std::vector<int> AppearanceCandidates(const LoopJob& job, const std::vector<int>& already);
  // Tries the older keyframes near the newest one and those that look like it; for each that
  // tracks it (PnP, enough inliers), a loop edge; then optimizes the graph. Reads the job and
  // the appearance index, which only it touches (one search at a time: in Track, or on the
  // worker).
  LoopClosure CloseLoops(const LoopJob& job);
  // Keyframes anywhere in the map that look most like `features` (appearance index, then the
  // ratio test on the strongest descriptors), best first, at most `count`, none of `skip`.
  std::vector<int> LookAlikeKeyframes(const FrameFeatures& features, int count,
                                      const std::function<bool(int)>& eligible);
  AppearanceIndex appearance_index;
  int indexed_keyframes = 0;
  // Moves the keyframes as `closure` says (those made since its job by the same correction as
  // its newest) and the last pose with them. Returns the loops kept.
  int Apply(LoopClosure closure);
  // Applies the worker's finished results (tracking thread); loops kept and their search time.
  int ApplyFinished(double* ms);
  void WorkerLoop();
  void StopWorker();
};

}  // namespace objmap
