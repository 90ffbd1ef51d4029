#include "odometry/rgbd_odometry.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "odometry/appearance_index.h"
#include "odometry/depth_alignment.h"
#include "posegraph/pose_graph.h"

namespace objmap {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kDegPerRad = 57.29577951308232;

double AngleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * kDegPerRad; }

// ORB keypoints of one frame, with their 3D points where the depth is usable.
struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;                  // one row per keypoint
  std::vector<cv::Point3f> points_C;    // per keypoint; valid[i] says whether it has one
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
cv::Mat StrongestDescriptors(const FrameFeatures& features, int count) {
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
void IndexKeyframes(const KeyframeList& keyframes, int last, AppearanceIndex* index, int* indexed) {
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
std::vector<int> MostMatched(const cv::Mat& mine, const std::vector<int>& candidates,
                             const std::function<bool(int)>& eligible,
                             const KeyframeList& keyframes, float match_ratio, int min_matches,
                             int count) {
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

Eigen::Isometry3d FromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(R, rotation);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation;
  T.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T;
}

}  // namespace

bool OdometryConfig::IsValid(std::string* why) const {
  if (features < 50 || !(match_ratio > 0.f && match_ratio <= 1.f)) {
    *why = "odometry: features must be >= 50 and match_ratio in (0, 1]";
    return false;
  }
  if (!(min_depth_m >= 0.0 && max_depth_m > min_depth_m && std::isfinite(max_depth_m))) {
    *why = "odometry: need 0 <= min_depth_m < max_depth_m, finite";
    return false;
  }
  if (!(ransac_reprojection_px > 0.0) || ransac_iterations < 1 || min_inliers < 6) {
    *why = "odometry: ransac_reprojection_px > 0, ransac_iterations >= 1 and min_inliers >= 6";
    return false;
  }
  if (!(max_step_m > 0.0) || !(max_step_deg > 0.0) || !(keyframe_distance_m > 0.0) ||
      !(keyframe_angle_deg > 0.0) || keyframe_min_inliers < min_inliers ||
      relocalisation_keyframes < 0 || relocalisation_appearance_candidates < 0 ||
      relocalisation_min_inliers < min_inliers ||
      relocalisation_corroborated_min_inliers < min_inliers ||
      relocalisation_corroborated_min_inliers > relocalisation_min_inliers ||
      !(relocalisation_consensus_m > 0.0) || !(relocalisation_consensus_deg > 0.0)) {
    *why =
        "odometry: step and keyframe limits must be positive, keyframe_min_inliers >= "
        "min_inliers, relocalisation_keyframes and relocalisation_appearance_candidates >= 0 "
        "relocalisation_min_inliers >= relocalisation_corroborated_min_inliers >= min_inliers "
        "and the relocalisation consensus limits positive";
    return false;
  }
  if (!(edge_sigma_m > 0.0) || !(edge_sigma_deg > 0.0) || !(edge_feature_sigma_m > 0.0) ||
      !(edge_feature_sigma_deg > 0.0)) {
    *why = "odometry: edge_sigma_m, edge_sigma_deg and the edge_feature sigmas must be positive";
    return false;
  }
  if (loop_appearance_candidates < 0 || appearance_descriptors < 2 || appearance_shortlist < 0) {
    *why =
        "odometry: loop_appearance_candidates and appearance_shortlist must be >= 0 and "
        "appearance_descriptors >= 2";
    return false;
  }
  if (depth_refinement &&
      (depth_refinement_coarse_step < 1 || depth_refinement_fine_step < 1 ||
       depth_refinement_coarse_iterations < 0 || depth_refinement_fine_iterations < 1 ||
       depth_refinement_min_correspondences < 6 || !(depth_refinement_max_correction_m > 0.0) ||
       !(depth_refinement_max_correction_deg > 0.0))) {
    *why =
        "odometry: depth_refinement needs steps >= 1, coarse iterations >= 0, fine iterations "
        ">= 1, min_correspondences >= 6 and positive correction limits";
    return false;
  }
  return true;
}

const char* TrackingStatusName(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kInitialized:
      return "initialized";
    case TrackingStatus::kTracked:
      return "tracked";
    case TrackingStatus::kRelocalized:
      return "relocalized";
    case TrackingStatus::kProvisional:
      return "provisional";
    case TrackingStatus::kLost:
      return "lost";
  }
  return "?";
}

// A loop search for one new keyframe: its features and everything it reads, copied when it
// starts (keyframes are shared, being immutable), so that tracking goes on meanwhile.
struct LoopJob {
  int newest = -1;
  std::shared_ptr<const FrameFeatures> features;
  CameraIntrinsics intrinsics;
  std::vector<std::shared_ptr<const Keyframe>> keyframes;  // 0..newest
  std::vector<Eigen::Isometry3d> poses;                   // 0..newest
  std::vector<int> fragments;                             // 0..newest: Impl::fragment_of
  std::vector<PoseGraphEdge> edges;
};

// What a loop search found: with loops, every keyframe's pose up to the job's newest after the
// solve, and the graph's edges (the job's, the loops added, wrong loops dropped).
struct LoopClosure {
  int newest = -1;
  int loops = 0;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<PoseGraphEdge> edges;
  std::size_t job_edges = 0;  // edges the job started from: later ones were added meanwhile
  std::vector<int> fragments;  // the job's: only keyframes in the map's frame (0) were solved
  double ms = 0.0;
};

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
  // Consensus, and if it places the camera, again with the keyframes nearest that place (up to
  // relocalisation_keyframes, in its frame) voting too: the keyframes a wrong placement among
  // look-alikes would skip. Adds their votes to `votes`; returns the index of the chosen one.
  int ConsensusWithNeighbours(const FrameFeatures& features, const CameraIntrinsics& K,
                              std::vector<Vote>* votes, std::string* why);
  // The first keyframe, at T_W_C: tracking starts from it. False when too few keypoints have
  // depth.
  bool Start(const FrameFeatures& features, const Eigen::Isometry3d& T_W_C, std::string* why);
  // Dense step after PnP: moves T_K_C when the depth alignment succeeds within the limits.
  void RefineByDepth(const FrameFeatures& features, const Keyframe& keyframe,
                     Eigen::Isometry3d* T_K_C, PoseFit* fit) const;
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

Eigen::Matrix<double, 6, 6> EdgeInformation(double sigma_m, double sigma_rad) {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  information.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return information;
}

void RgbdOdometry::Impl::AddOdometryEdge(int from, int to,
                                         const Eigen::Matrix<double, 6, 6>& information) {
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.T_from_to = poses[static_cast<std::size_t>(from)].inverse() * poses[static_cast<std::size_t>(to)];
  edge.information = information;
  const std::lock_guard<std::mutex> lock(mutex);
  edges.push_back(edge);
}

LoopJob RgbdOdometry::Impl::MakeLoopJob(std::shared_ptr<const FrameFeatures> features,
                                        const CameraIntrinsics& K) const {
  LoopJob job;
  job.newest = static_cast<int>(keyframes.size()) - 1;
  job.features = std::move(features);
  job.intrinsics = K;
  job.keyframes = keyframes;
  job.poses = poses;
  job.fragments = fragment_of;
  job.edges = edges;
  return job;
}

std::vector<int> RgbdOdometry::Impl::AppearanceCandidates(const LoopJob& job,
                                                          const std::vector<int>& already) {
  if (config.loop_appearance_candidates <= 0) return {};
  // Keyframes made since the last search join the index first.
  IndexKeyframes(job.keyframes, job.newest, &appearance_index, &indexed_keyframes);
  const cv::Mat& mine = job.keyframes[static_cast<std::size_t>(job.newest)]->strongest_descriptors;
  if (mine.rows < 2) return {};
  const int last_old = job.newest - config.loop_min_keyframe_gap;
  std::vector<int> shortlist;
  if (config.appearance_shortlist > 0 && mine.isContinuous()) {
    for (const auto& [votes, k] : appearance_index.MostAlike(
             mine.ptr<std::uint8_t>(), mine.rows, last_old, config.appearance_shortlist)) {
      shortlist.push_back(k);
    }
  } else {
    for (int k = 0; k <= last_old; ++k) shortlist.push_back(k);
  }
  // Keyframes of a provisional fragment have poses in another frame: no loop to them.
  auto eligible = [&](int k) {
    return job.fragments[static_cast<std::size_t>(k)] == 0 &&
           std::find(already.begin(), already.end(), k) == already.end();
  };
  return MostMatched(mine, shortlist, eligible, job.keyframes, config.match_ratio,
                     config.loop_min_inliers, config.loop_appearance_candidates);
}

LoopClosure RgbdOdometry::Impl::CloseLoops(const LoopJob& job) {
  const auto start = Clock::now();
  LoopClosure closure;
  closure.newest = job.newest;
  closure.job_edges = job.edges.size();
  closure.fragments = job.fragments;
  auto finish = [&]() -> LoopClosure {
    closure.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return closure;
  };
  if (config.loop_candidates <= 0) return finish();
  const int newest = job.newest;
  const Eigen::Isometry3d& T_W_new = job.poses[static_cast<std::size_t>(newest)];
  auto in_map_frame = [&](int k) { return job.fragments[static_cast<std::size_t>(k)] == 0; };
  if (!in_map_frame(newest)) return finish();
  std::vector<std::pair<double, int>> near;
  for (int k = 0; k + config.loop_min_keyframe_gap <= newest; ++k) {
    if (!in_map_frame(k)) continue;
    const Eigen::Isometry3d offset = job.poses[static_cast<std::size_t>(k)].inverse() * T_W_new;
    if (offset.translation().norm() <= config.loop_search_radius_m &&
        AngleDeg(offset.linear()) <= config.loop_search_angle_deg) {
      near.emplace_back(offset.translation().norm(), k);
    }
  }
  std::sort(near.begin(), near.end());
  std::vector<int> candidates;
  for (std::size_t c = 0; c < near.size() && static_cast<int>(c) < config.loop_candidates; ++c) {
    candidates.push_back(near[c].second);
  }
  for (int k : AppearanceCandidates(job, candidates)) candidates.push_back(k);
  std::vector<PoseGraphEdge> edges = job.edges;
  std::vector<std::pair<int, PoseFit>> loops;
  for (const int k : candidates) {
    PoseFit fit = Fit(*job.features, *job.keyframes[static_cast<std::size_t>(k)], job.intrinsics);
    if (fit.ok && fit.inliers >= config.loop_min_inliers) loops.emplace_back(k, std::move(fit));
  }
  // Loops to the saved map's keyframes must agree on where the newest keyframe is (within the
  // relocalisation consensus limits), the tracked pose voting too: a repeated pattern fits
  // strongly at a wrong place, and a wrong loop to keyframes held fixed would pull the whole
  // session there (the graph's robust loss sorts out the session's own loops). The loops that
  // agree with the largest group are kept; without one group larger than the others, none.
  const bool to_map = std::any_of(loops.begin(), loops.end(),
                                  [&](const auto& loop) { return loop.first < map_keyframes; });
  std::vector<Eigen::Isometry3d> voters;  // the loops' poses of the newest keyframe, then its own
  for (const auto& [k, fit] : loops)
    voters.push_back(job.poses[static_cast<std::size_t>(k)] * fit.T_K_C);
  voters.push_back(T_W_new);
  auto agree = [&](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    const Eigen::Isometry3d apart = a.inverse() * b;
    return apart.translation().norm() <= config.relocalisation_consensus_m &&
           AngleDeg(apart.linear()) <= config.relocalisation_consensus_deg;
  };
  std::vector<int> support(voters.size(), 0);
  for (std::size_t v = 0; v < voters.size(); ++v) {
    for (const Eigen::Isometry3d& other : voters) support[v] += agree(voters[v], other);
  }
  const auto best =
      static_cast<std::size_t>(std::max_element(support.begin(), support.end()) - support.begin());
  const bool one_group = std::count(support.begin(), support.end(), support[best]) == support[best];
  int added = 0;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (to_map && !(one_group && agree(voters[best], voters[l]))) continue;
    PoseGraphEdge loop;
    loop.from = loops[l].first;
    loop.to = newest;
    loop.T_from_to = loops[l].second.T_K_C;
    loop.information = EdgeInformationOf(loops[l].second);
    loop.loop = true;
    edges.push_back(loop);
    ++added;
  }
  if (added == 0) return finish();
  // The graph of the keyframes in the map's frame: a provisional fragment's are tied to it by
  // no edge until it is attached.
  PoseGraph graph;
  for (int k = 0; k <= newest; ++k) {
    if (in_map_frame(k)) graph.AddNode(k, job.poses[static_cast<std::size_t>(k)]);
  }
  for (int k = 0; k < map_keyframes && k <= newest; ++k) graph.SetFixed(k);
  std::string why;
  std::vector<std::size_t> in_graph;  // graph edge -> index in `edges`
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].from > newest || edges[e].to > newest || !in_map_frame(edges[e].from) ||
        !in_map_frame(edges[e].to)) {
      continue;
    }
    if (!graph.AddEdge(edges[e], &why)) return finish();
    in_graph.push_back(e);
  }
  PoseGraphReport report;
  if (!graph.Optimize(&report, &why)) return finish();
  // Wrong loops stay out of later solves.
  std::vector<bool> dropped(edges.size(), false);
  for (int e : report.rejected_loops) dropped[in_graph[static_cast<std::size_t>(e)]] = true;
  int kept_loops = added;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (!dropped[e]) {
      closure.edges.push_back(edges[e]);
    } else if (edges[e].to == newest && e >= job.edges.size()) {
      --kept_loops;
    }
  }
  closure.loops = kept_loops;
  closure.poses.assign(job.poses.begin(), job.poses.begin() + newest + 1);
  for (const auto& [k, pose] : graph.poses()) closure.poses[static_cast<std::size_t>(k)] = pose;
  return finish();
}

int RgbdOdometry::Impl::Apply(LoopClosure closure) {
  if (closure.poses.empty()) return 0;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto newest = static_cast<std::size_t>(closure.newest);
  const Eigen::Isometry3d correction = closure.poses[newest] * poses[newest].inverse();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (fragment_of[k] != 0) continue;  // a provisional fragment's frame is its own
    // Solved, or made or attached since the job: these follow the newest's correction.
    poses[k] = k <= newest && closure.fragments[k] == 0 ? closure.poses[k] : correction * poses[k];
  }
  // Edges added since the job (odometry edges of newer keyframes) follow the solved ones.
  closure.edges.insert(closure.edges.end(),
                       edges.begin() + static_cast<std::ptrdiff_t>(closure.job_edges), edges.end());
  edges = std::move(closure.edges);
  if (has_last && current_fragment == 0) last_T_W_C = correction * last_T_W_C;
  loops_closed += closure.loops;
  return closure.loops;
}

int RgbdOdometry::Impl::ApplyFinished(double* ms) {
  std::vector<LoopClosure> finished;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    finished.swap(results);
  }
  int loops = 0;
  for (LoopClosure& closure : finished) {
    *ms += closure.ms;
    loops += Apply(std::move(closure));
  }
  if (!finished.empty()) wake.notify_all();  // the worker waits for its result to be applied
  return loops;
}

void RgbdOdometry::Impl::WorkerLoop() {
  for (;;) {
    LoopJob job;
    {
      std::unique_lock<std::mutex> lock(mutex);
      wake.wait(lock, [&] { return stop || (!jobs.empty() && results.empty()); });
      if (stop) return;
      job = std::move(jobs.front());
      jobs.pop_front();
      // The job was queued before the loops applied since: it starts from the current state.
      job.poses.assign(poses.begin(), poses.begin() + job.newest + 1);
      job.fragments.assign(fragment_of.begin(), fragment_of.begin() + job.newest + 1);
      job.edges = edges;
      busy = true;
    }
    LoopClosure closure;
    try {
      closure = CloseLoops(job);
    } catch (const std::exception&) {
      // A search that fails (OpenCV or Ceres on a degenerate case, memory) closes no loop;
      // tracking goes on without it rather than the process ending on this thread.
      closure = LoopClosure{};
    }
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (!closure.poses.empty()) results.push_back(std::move(closure));
      busy = false;
    }
    settled.notify_all();
  }
}

void RgbdOdometry::Impl::StopWorker() {
  if (!worker.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    stop = true;
  }
  wake.notify_all();
  worker.join();
}

std::vector<int> RgbdOdometry::Impl::LookAlikeKeyframes(const FrameFeatures& features, int count,
                                                        const std::function<bool(int)>& eligible) {
  if (count <= 0) return {};
  IndexKeyframes(keyframes, static_cast<int>(keyframes.size()) - 1, &relocalisation_index,
                 &relocalisation_indexed);
  const cv::Mat mine = StrongestDescriptors(features, config.appearance_descriptors);
  if (mine.rows < 2 || !mine.isContinuous()) return {};
  const int shortlist_size = std::max(config.appearance_shortlist, count);
  std::vector<int> shortlist;
  for (const auto& [votes, k] :
       relocalisation_index.MostAlike(mine.ptr<std::uint8_t>(), mine.rows,
                                      static_cast<int>(keyframes.size()) - 1, shortlist_size)) {
    shortlist.push_back(k);
  }
  return MostMatched(mine, shortlist, eligible, keyframes, config.match_ratio, config.min_inliers,
                     count);
}

bool RgbdOdometry::Impl::Extract(const RgbdFrame& frame, FrameFeatures* features,
                                 std::string* why) {
  const CameraIntrinsics& K = frame.intrinsics;
  if (frame.color.empty() || frame.depth.empty()) {
    *why = "the frame needs colour and depth";
    return false;
  }
  if (frame.color.width != frame.depth.width || frame.color.height != frame.depth.height ||
      frame.depth.width != K.width || frame.depth.height != K.height) {
    *why = "colour, depth and intrinsics sizes differ";
    return false;
  }
  const cv::Mat rgb(frame.color.height, frame.color.width, CV_8UC3,
                    const_cast<std::uint8_t*>(frame.color.rgb.data()));
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  orb->detectAndCompute(grey, cv::noArray(), features->keypoints, features->descriptors);
  const std::size_t n = features->keypoints.size();
  features->points_C.assign(n, cv::Point3f());
  features->valid.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const cv::Point2f& p = features->keypoints[i].pt;
    const int u = static_cast<int>(std::lround(p.x)), v = static_cast<int>(std::lround(p.y));
    if (u < 0 || v < 0 || u >= K.width || v >= K.height) continue;
    const float z = frame.depth.depth_m[static_cast<std::size_t>(v) * K.width + u];
    if (!std::isfinite(z) || z < config.min_depth_m || z > config.max_depth_m) continue;
    features->points_C[i] = cv::Point3f(static_cast<float>((p.x - K.cx) * z / K.fx),
                                        static_cast<float>((p.y - K.cy) * z / K.fy), z);
    features->valid[i] = 1;
  }
  if (config.depth_refinement) {
    features->coarse_depth =
        MakeDepthGrid(frame.depth, K, config.depth_refinement_coarse_step, config.max_depth_m);
    features->fine_depth =
        MakeDepthGrid(frame.depth, K, config.depth_refinement_fine_step, config.max_depth_m);
  }
  return true;
}

void RgbdOdometry::Impl::AddKeyframe(const FrameFeatures& features,
                                     const Eigen::Isometry3d& T_W_C) {
  auto made = std::make_shared<Keyframe>();
  Keyframe& keyframe = *made;
  keyframe.strongest_descriptors = StrongestDescriptors(features, config.appearance_descriptors);
  keyframe.coarse_depth = features.coarse_depth;
  keyframe.fine_depth = features.fine_depth;
  for (std::size_t i = 0; i < features.keypoints.size(); ++i) {
    if (!features.valid[i]) continue;
    keyframe.points_K.push_back(features.points_C[i]);
    keyframe.descriptors.push_back(features.descriptors.row(static_cast<int>(i)));
  }
  {
    const std::lock_guard<std::mutex> lock(mutex);
    keyframes.push_back(std::move(made));
    poses.push_back(T_W_C);
    fragment_of.push_back(current_fragment);
  }
  current_keyframe = static_cast<int>(keyframes.size()) - 1;
}

bool RgbdOdometry::Impl::StartFragment(const FrameFeatures& features) {
  const auto with_depth = std::count(features.valid.begin(), features.valid.end(), std::uint8_t{1});
  if (with_depth < config.min_inliers) return false;
  current_fragment = ++fragments_started;
  AddKeyframe(features, Eigen::Isometry3d::Identity());
  has_last = true;
  last_tracked = true;
  last_T_W_C = Eigen::Isometry3d::Identity();
  return true;
}

bool RgbdOdometry::Impl::Strong(const PoseFit& fit) const {
  return fit.ok && fit.inliers >= config.relocalisation_min_inliers &&
         (!config.depth_refinement || fit.depth_refined);
}

int RgbdOdometry::Impl::Consensus(const std::vector<Vote>& votes, std::string* why) const {
  auto pose_of_vote = [&](const Vote& vote) {
    return poses[static_cast<std::size_t>(vote.keyframe)] * vote.fit.T_K_C;
  };
  auto agree = [&](const Vote& a, const Vote& b) {
    if (fragment_of[static_cast<std::size_t>(a.keyframe)] !=
        fragment_of[static_cast<std::size_t>(b.keyframe)]) {
      return false;
    }
    const Eigen::Isometry3d apart = pose_of_vote(a).inverse() * pose_of_vote(b);
    return apart.translation().norm() <= config.relocalisation_consensus_m &&
           AngleDeg(apart.linear()) <= config.relocalisation_consensus_deg;
  };
  // Strong alone, or nearly so and another keyframe's fit agrees.
  int best = -1;
  for (std::size_t v = 0; v < votes.size(); ++v) {
    const PoseFit& fit = votes[v].fit;
    if (!fit.ok || (config.depth_refinement && !fit.depth_refined)) continue;
    bool eligible = fit.inliers >= config.relocalisation_min_inliers;
    if (!eligible && fit.inliers >= config.relocalisation_corroborated_min_inliers) {
      for (std::size_t other = 0; other < votes.size() && !eligible; ++other) {
        eligible = other != v && agree(votes[v], votes[other]);
      }
    }
    if (eligible && (best < 0 || fit.inliers > votes[static_cast<std::size_t>(best)].fit.inliers)) {
      best = static_cast<int>(v);
    }
  }
  if (best < 0) return -1;
  const Vote& chosen = votes[static_cast<std::size_t>(best)];
  const auto fragment = fragment_of[static_cast<std::size_t>(chosen.keyframe)];
  const Eigen::Isometry3d T_W_C =
      poses[static_cast<std::size_t>(chosen.keyframe)] * chosen.fit.T_K_C;
  for (const Vote& vote : votes) {
    if (fragment_of[static_cast<std::size_t>(vote.keyframe)] != fragment) continue;
    const Eigen::Isometry3d apart =
        T_W_C.inverse() * poses[static_cast<std::size_t>(vote.keyframe)] * vote.fit.T_K_C;
    if (apart.translation().norm() > config.relocalisation_consensus_m ||
        AngleDeg(apart.linear()) > config.relocalisation_consensus_deg) {
      char text[200];
      std::snprintf(text, sizeof(text),
                    "keyframes %d and %d place the camera %.1f cm and %.1f deg apart (a repeated "
                    "pattern?): not placed",
                    chosen.keyframe, vote.keyframe, 100.0 * apart.translation().norm(),
                    AngleDeg(apart.linear()));
      *why = text;
      return -1;
    }
  }
  return best;
}

int RgbdOdometry::Impl::ConsensusWithNeighbours(const FrameFeatures& features,
                                                const CameraIntrinsics& K, std::vector<Vote>* votes,
                                                std::string* why) {
  const int chosen = Consensus(*votes, why);
  if (chosen < 0) return -1;
  const Vote& placed = (*votes)[static_cast<std::size_t>(chosen)];
  const int fragment = fragment_of[static_cast<std::size_t>(placed.keyframe)];
  const Eigen::Vector3d where =
      (poses[static_cast<std::size_t>(placed.keyframe)] * placed.fit.T_K_C).translation();
  std::vector<std::pair<double, int>> near;
  for (int k = 0; k < static_cast<int>(keyframes.size()); ++k) {
    if (fragment_of[static_cast<std::size_t>(k)] != fragment) continue;
    if (std::any_of(votes->begin(), votes->end(), [&](const Vote& v) { return v.keyframe == k; })) {
      continue;
    }
    near.emplace_back((poses[static_cast<std::size_t>(k)].translation() - where).norm(), k);
  }
  std::sort(near.begin(), near.end());
  if (static_cast<int>(near.size()) > config.relocalisation_keyframes) {
    near.resize(static_cast<std::size_t>(config.relocalisation_keyframes));
  }
  for (const auto& [distance, k] : near) {
    PoseFit fit = Fit(features, *keyframes[static_cast<std::size_t>(k)], K);
    if (fit.ok) votes->push_back({k, std::move(fit)});
  }
  return Consensus(*votes, why);
}

bool RgbdOdometry::Impl::AttachFragment(const FrameFeatures& features, const CameraIntrinsics& K,
                                        const Eigen::Isometry3d& T_F_C, Eigen::Isometry3d* T_W_C,
                                        PoseFit* fit, int* reference, std::string* why) {
  auto in_map_frame = [&](int k) { return fragment_of[static_cast<std::size_t>(k)] == 0; };
  std::vector<Vote> votes;
  for (const int k :
       LookAlikeKeyframes(features, config.relocalisation_appearance_candidates, in_map_frame)) {
    PoseFit candidate = Fit(features, *keyframes[static_cast<std::size_t>(k)], K);
    if (candidate.ok) votes.push_back({k, std::move(candidate)});
  }
  std::string conflict;
  const int chosen = ConsensusWithNeighbours(features, K, &votes, &conflict);
  if (chosen >= 0) {
    const int k = votes[static_cast<std::size_t>(chosen)].keyframe;
    PoseFit& candidate = votes[static_cast<std::size_t>(chosen)].fit;
    *T_W_C = poses[static_cast<std::size_t>(k)] * candidate.T_K_C;
    const Eigen::Isometry3d T_W_F = *T_W_C * T_F_C.inverse();
    {
      const std::lock_guard<std::mutex> lock(mutex);
      for (std::size_t j = 0; j < poses.size(); ++j) {
        if (fragment_of[j] != current_fragment) continue;
        poses[j] = T_W_F * poses[j];
        fragment_of[j] = 0;
      }
    }
    current_fragment = 0;
    ++fragments_attached;
    last_T_W_C = T_W_F * last_T_W_C;
    *fit = std::move(candidate);
    *reference = k;
    return true;
  }
  *why = !conflict.empty() ? conflict
         : votes.empty()   ? "no keyframe of the map fits the frame"
                           : "no keyframe of the map fits the frame strongly";
  return false;
}

bool RgbdOdometry::Impl::Start(const FrameFeatures& features, const Eigen::Isometry3d& T_W_C,
                               std::string* why) {
  const auto with_depth = std::count(features.valid.begin(), features.valid.end(), std::uint8_t{1});
  if (with_depth < config.min_inliers) {
    *why = std::to_string(with_depth) + " keypoints with depth, " +
           std::to_string(config.min_inliers) + " needed to start";
    return false;
  }
  AddKeyframe(features, T_W_C);
  has_last = true;
  last_tracked = true;
  last_T_W_C = T_W_C;
  return true;
}

void RgbdOdometry::Impl::RefineByDepth(const FrameFeatures& features, const Keyframe& keyframe,
                                       Eigen::Isometry3d* T_K_C, PoseFit* fit) const {
  std::vector<const DepthGrid*> model_levels, frame_levels;
  std::vector<DepthAlignmentLevel> levels;
  if (config.depth_refinement_coarse_iterations > 0) {
    model_levels.push_back(&keyframe.coarse_depth);
    frame_levels.push_back(&features.coarse_depth);
    levels.push_back({config.depth_refinement_coarse_iterations, 0.08, 0.03});
  }
  model_levels.push_back(&keyframe.fine_depth);
  frame_levels.push_back(&features.fine_depth);
  levels.push_back({config.depth_refinement_fine_iterations, 0.03, 0.01});
  Eigen::Isometry3d refined = *T_K_C;
  DepthAlignmentReport report;
  if (!AlignDepth(model_levels, frame_levels, levels, config.depth_refinement_min_correspondences,
                  &refined, &report)) {
    return;
  }
  const Eigen::Isometry3d correction = T_K_C->inverse() * refined;
  if (correction.translation().norm() > config.depth_refinement_max_correction_m ||
      AngleDeg(correction.linear()) > config.depth_refinement_max_correction_deg) {
    return;
  }
  *T_K_C = refined;
  fit->depth_refined = true;
  fit->depth_rmse_m = report.rmse_m;
  fit->alignment = report;
}

Eigen::Matrix<double, 6, 6> RgbdOdometry::Impl::EdgeInformationOf(const PoseFit& fit) const {
  if (!fit.depth_refined || !config.edge_information_from_alignment) {
    return EdgeInformation(config.edge_sigma_m, config.edge_sigma_deg / kDegPerRad);
  }
  AlignmentInformationConfig floor;
  floor.floor_sigma_m = config.edge_sigma_m;
  floor.floor_sigma_deg = config.edge_sigma_deg;
  // The features fix what the depth leaves free (a wall's plane): their own information is
  // added to the depth's.
  return AlignmentInformation(fit.alignment.hessian, fit.alignment.centre,
                              fit.alignment.radius_m, fit.T_K_C.translation(), floor) +
         EdgeInformation(config.edge_feature_sigma_m, config.edge_feature_sigma_deg / kDegPerRad);
}

PoseFit RgbdOdometry::Impl::Fit(const FrameFeatures& features, const Keyframe& keyframe,
                                const CameraIntrinsics& K) const {
  PoseFit fit;
  if (features.descriptors.empty() || keyframe.descriptors.rows < 2) {
    fit.why = "no features to match";
    return fit;
  }
  std::vector<std::vector<cv::DMatch>> knn;
  const cv::BFMatcher matcher(cv::NORM_HAMMING);
  matcher.knnMatch(features.descriptors, keyframe.descriptors, knn, 2);
  std::vector<cv::Point3f> object_points;
  std::vector<cv::Point2f> image_points;
  for (const auto& pair : knn) {
    if (pair.size() < 2 || pair[0].distance >= config.match_ratio * pair[1].distance) continue;
    object_points.push_back(keyframe.points_K[static_cast<std::size_t>(pair[0].trainIdx)]);
    image_points.push_back(features.keypoints[static_cast<std::size_t>(pair[0].queryIdx)].pt);
  }
  fit.matches = static_cast<int>(object_points.size());
  if (fit.matches < config.min_inliers) {
    fit.why = std::to_string(fit.matches) + " feature matches, " +
              std::to_string(config.min_inliers) + " needed";
    return fit;
  }
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  // RANSAC draws from OpenCV's per-thread generator: a fixed seed per fit makes the trajectory
  // the same whichever thread tracks and whatever ran on it before (reproducible runs and
  // tests); the caller's generator state is given back.
  cv::RNG& generator = cv::theRNG();
  const std::uint64_t caller_state = generator.state;
  generator.state = 0x9E3779B97F4A7C15ull;
  const bool solved = cv::solvePnPRansac(
      object_points, image_points, camera, cv::noArray(), rvec, tvec, false,
      config.ransac_iterations, static_cast<float>(config.ransac_reprojection_px), 0.999,
      inliers, cv::SOLVEPNP_EPNP);
  generator.state = caller_state;
  fit.inliers = static_cast<int>(inliers.size());
  if (!solved || fit.inliers < config.min_inliers) {
    fit.why = std::to_string(fit.inliers) + " PnP inliers of " + std::to_string(fit.matches) +
              " matches, " + std::to_string(config.min_inliers) + " needed";
    return fit;
  }
  // Least squares on the inliers (RANSAC's pose comes from a minimal set).
  std::vector<cv::Point3f> inlier_object;
  std::vector<cv::Point2f> inlier_image;
  for (int i : inliers) {
    inlier_object.push_back(object_points[static_cast<std::size_t>(i)]);
    inlier_image.push_back(image_points[static_cast<std::size_t>(i)]);
  }
  cv::solvePnPRefineLM(inlier_object, inlier_image, camera, cv::noArray(), rvec, tvec);
  std::vector<cv::Point2f> projected;
  cv::projectPoints(inlier_object, rvec, tvec, camera, cv::noArray(), projected);
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < projected.size(); ++i) {
    const cv::Point2f d = projected[i] - inlier_image[i];
    sum_sq += d.dot(d);
  }
  fit.rmse_px = std::sqrt(sum_sq / static_cast<double>(std::max<std::size_t>(1, projected.size())));
  // PnP maps keyframe points into this camera: T_C_K.
  Eigen::Isometry3d T_K_C = FromRvecTvec(rvec, tvec).inverse();
  if (config.depth_refinement) RefineByDepth(features, keyframe, &T_K_C, &fit);
  fit.T_K_C = T_K_C;
  fit.ok = true;
  return fit;
}

RgbdOdometry::RgbdOdometry(const OdometryConfig& config)
    : impl_(std::make_unique<Impl>(config)) {}
RgbdOdometry::~RgbdOdometry() = default;
RgbdOdometry::RgbdOdometry(RgbdOdometry&&) noexcept = default;
RgbdOdometry& RgbdOdometry::operator=(RgbdOdometry&&) noexcept = default;

bool RgbdOdometry::StartFromKnownPose(const RgbdFrame& frame, std::string* why) {
  Impl& impl = *impl_;
  if (!impl.keyframes.empty()) {
    *why = "tracking has already started";
    return false;
  }
  FrameFeatures features;
  if (!impl.Extract(frame, &features, why) || !impl.Start(features, frame.T_W_C, why)) {
    return false;
  }
  return true;
}

bool RgbdOdometry::AddMapKeyframe(const RgbdFrame& frame, std::string* why) {
  Impl& impl = *impl_;
  if (impl.tracking_started || impl.map_keyframes != static_cast<int>(impl.keyframes.size())) {
    *why = "tracking has already started";
    return false;
  }
  FrameFeatures features;
  if (!impl.Extract(frame, &features, why)) return false;
  const auto with_depth = std::count(features.valid.begin(), features.valid.end(), std::uint8_t{1});
  if (with_depth < impl.config.min_inliers) {
    *why = std::to_string(with_depth) + " keypoints with depth, " +
           std::to_string(impl.config.min_inliers) + " needed";
    return false;
  }
  impl.AddKeyframe(features, frame.T_W_C);
  impl.map_keyframes = static_cast<int>(impl.keyframes.size());
  impl.has_last = true;
  impl.last_T_W_C = frame.T_W_C;
  impl.last_tracked = false;
  return true;
}

int RgbdOdometry::num_keyframes() const { return static_cast<int>(impl_->keyframes.size()); }

TrackingReport RgbdOdometry::Track(const RgbdFrame& frame) {
  const auto start = Clock::now();
  TrackingReport report;
  auto finish = [&]() -> TrackingReport {
    report.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return report;
  };
  Impl& impl = *impl_;
  const OdometryConfig& config = impl.config;
  impl.tracking_started = true;
  // Loops the worker closed since the last frame move the keyframes before this frame is
  // tracked against them.
  report.loops_closed = impl.ApplyFinished(&report.loop_ms);
  auto features = std::make_shared<FrameFeatures>();
  if (!impl.Extract(frame, features.get(), &report.why)) return finish();
  report.keypoints = static_cast<int>(features->keypoints.size());
  const int with_depth = static_cast<int>(
      std::count(features->valid.begin(), features->valid.end(), std::uint8_t{1}));

  if (impl.keyframes.empty()) {
    if (!impl.Start(*features, Eigen::Isometry3d::Identity(), &report.why)) return finish();
    report.status = TrackingStatus::kInitialized;
    report.new_keyframe = true;
    report.reference_keyframe = impl.current_keyframe;
    return finish();
  }
  auto pose_of = [&](int k) -> const Eigen::Isometry3d& {
    return impl.poses[static_cast<std::size_t>(k)];
  };

  // A pose that moved implausibly far from the last one is a wrong PnP solution.
  auto plausible = [&](const Eigen::Isometry3d& T_W_C, std::string* why) {
    if (!impl.has_last) return true;
    const Eigen::Isometry3d step = impl.last_T_W_C.inverse() * T_W_C;
    if (step.translation().norm() > config.max_step_m || AngleDeg(step.linear()) > config.max_step_deg) {
      *why = "implausible motion since the last frame";
      return false;
    }
    return true;
  };

  // Without a recent tracked pose, the camera may be anywhere: every fit must be strong.
  const bool strict = !impl.has_last || !impl.last_tracked;
  auto strong = [&](const PoseFit& candidate) { return impl.Strong(candidate); };
  PoseFit fit = impl.Fit(*features, *impl.keyframes[static_cast<std::size_t>(impl.current_keyframe)],
                         frame.intrinsics);
  std::string implausible;
  // Without a recent pose the fit is a vote among several keyframes' (Consensus), not accepted
  // alone.
  bool accepted =
      fit.ok && plausible(pose_of(impl.current_keyframe) * fit.T_K_C, &implausible) && !strict;
  std::vector<Impl::Vote> votes;
  if (strict && fit.ok) votes.push_back({impl.current_keyframe, fit});
  if (fit.ok && strict && !strong(fit)) {
    fit.why = std::to_string(fit.inliers) + " PnP inliers" +
              (config.depth_refinement && !fit.depth_refined ? " without a dense alignment" : "") +
              " against the saved map's keyframe, " +
              std::to_string(config.relocalisation_min_inliers) + " needed to place the camera";
    fit.ok = false;
  }
  report.reference_keyframe = impl.current_keyframe;
  report.status = TrackingStatus::kTracked;
  if (!accepted) {
    // Relocalisation: the other keyframes of the current fragment (poses in other frames do
    // not compare), nearest to the last known pose first.
    auto in_current_fragment = [&](int k) {
      return impl.fragment_of[static_cast<std::size_t>(k)] == impl.current_fragment;
    };
    std::vector<int> order;
    for (int k = 0; k < static_cast<int>(impl.keyframes.size()); ++k) {
      if (k != impl.current_keyframe && in_current_fragment(k)) order.push_back(k);
    }
    std::sort(order.begin(), order.end(), [&](int a, int b) {
      return (pose_of(a).translation() - impl.last_T_W_C.translation()).norm() <
             (pose_of(b).translation() - impl.last_T_W_C.translation()).norm();
    });
    if (static_cast<int>(order.size()) > config.relocalisation_keyframes) {
      order.resize(static_cast<std::size_t>(config.relocalisation_keyframes));
    }
    // Then those that look like the frame, wherever they are, in the map's frame or the
    // current fragment's: only these can place a camera that starts far from the last pose.
    std::vector<int> tried = order;
    tried.push_back(impl.current_keyframe);
    const std::size_t by_distance = order.size();
    auto untried = [&](int k) {
      return (impl.fragment_of[static_cast<std::size_t>(k)] == 0 || in_current_fragment(k)) &&
             std::find(tried.begin(), tried.end(), k) == tried.end();
    };
    for (int k :
         impl.LookAlikeKeyframes(*features, config.relocalisation_appearance_candidates, untried)) {
      order.push_back(k);
    }
    std::string first_failure = fit.ok ? implausible : fit.why;
    // After a loss the last pose may be old: only the fits themselves are checked. Where no
    // recent motion or nearness vouches for them, every keyframe tried votes and the strongest
    // fit places the camera only if none of the others places it elsewhere.
    for (std::size_t i = 0; i < order.size(); ++i) {
      const int k = order[i];
      PoseFit candidate =
          impl.Fit(*features, *impl.keyframes[static_cast<std::size_t>(k)], frame.intrinsics);
      const bool must_be_strong = strict || i >= by_distance;
      if (!candidate.ok) continue;
      if (must_be_strong) {
        votes.push_back({k, std::move(candidate)});
        continue;
      }
      fit = std::move(candidate);
      accepted = true;
      report.reference_keyframe = k;
      report.status = TrackingStatus::kRelocalized;
      impl.current_keyframe = k;
      break;
    }
    if (!accepted && !votes.empty()) {
      std::string conflict;
      const int chosen =
          impl.ConsensusWithNeighbours(*features, frame.intrinsics, &votes, &conflict);
      if (!conflict.empty()) first_failure = conflict;
      if (chosen >= 0) {
        const int k = votes[static_cast<std::size_t>(chosen)].keyframe;
        fit = std::move(votes[static_cast<std::size_t>(chosen)].fit);
        accepted = true;
        report.reference_keyframe = k;
        report.status = TrackingStatus::kRelocalized;
        impl.current_keyframe = k;
        // Placed in the map's frame from a provisional fragment, against a keyframe of the map:
        // this frame's pose in the fragment is not known, so the fragment stays apart.
        impl.current_fragment = impl.fragment_of[static_cast<std::size_t>(k)];
      }
    }
    if (!accepted) {
      report.matches = fit.matches;
      report.inliers = fit.inliers;
      report.why = first_failure;
      impl.has_last = false;  // the motion check needs a recent pose
      if (config.provisional_fragments && impl.StartFragment(*features)) {
        report.status = TrackingStatus::kProvisional;
        report.fragment = impl.current_fragment;
        report.T_W_C = Eigen::Isometry3d::Identity();
        report.new_keyframe = true;
        report.reference_keyframe = impl.current_keyframe;
        return finish();
      }
      report.status = TrackingStatus::kLost;
      return finish();
    }
  }
  // Tracked in a provisional fragment: placed in the map when a map keyframe fits strongly.
  if (impl.current_fragment != 0) {
    const Eigen::Isometry3d T_F_C = pose_of(report.reference_keyframe) * fit.T_K_C;
    const int fragment = impl.current_fragment;
    Eigen::Isometry3d T_W_C;
    PoseFit placement;
    int map_keyframe = -1;
    std::string not_placed;
    if (impl.AttachFragment(*features, frame.intrinsics, T_F_C, &T_W_C, &placement, &map_keyframe,
                            &not_placed)) {
      report.attached_fragment = fragment;
      report.status = TrackingStatus::kRelocalized;
      // The frame becomes a keyframe tied to both: its fragment's keyframe (odometry edge) and
      // the map's keyframe that placed it, so that the graph stays one.
      const int fragment_keyframe = report.reference_keyframe;
      impl.AddKeyframe(*features, T_W_C);
      impl.AddOdometryEdge(fragment_keyframe, impl.current_keyframe, impl.EdgeInformationOf(fit));
      impl.AddOdometryEdge(map_keyframe, impl.current_keyframe, impl.EdgeInformationOf(placement));
      report.new_keyframe = true;
      report.reference_keyframe = impl.current_keyframe;
      report.T_W_C = T_W_C;
      report.matches = placement.matches;
      report.inliers = placement.inliers;
      report.reprojection_rmse_px = placement.rmse_px;
      report.depth_refined = placement.depth_refined;
      report.depth_rmse_m = placement.depth_rmse_m;
      impl.has_last = true;
      impl.last_tracked = true;
      impl.last_T_W_C = T_W_C;
      return finish();
    }
    report.status = TrackingStatus::kProvisional;
    report.fragment = fragment;
    report.why = not_placed;
  }
  const Eigen::Isometry3d T_W_C = pose_of(report.reference_keyframe) * fit.T_K_C;
  report.T_W_C = T_W_C;
  report.matches = fit.matches;
  report.inliers = fit.inliers;
  report.reprojection_rmse_px = fit.rmse_px;
  report.depth_refined = fit.depth_refined;
  report.depth_rmse_m = fit.depth_rmse_m;
  impl.has_last = true;
  impl.last_tracked = true;
  impl.last_T_W_C = T_W_C;

  const bool needs_keyframe = fit.T_K_C.translation().norm() > config.keyframe_distance_m ||
                              AngleDeg(fit.T_K_C.linear()) > config.keyframe_angle_deg ||
                              fit.inliers < config.keyframe_min_inliers;
  if (!needs_keyframe || with_depth < config.min_inliers) return finish();
  const int reference_keyframe = impl.current_keyframe;
  impl.AddKeyframe(*features, T_W_C);
  report.new_keyframe = true;
  report.reference_keyframe = impl.current_keyframe;
  impl.AddOdometryEdge(reference_keyframe, impl.current_keyframe, impl.EdgeInformationOf(fit));
  // Loops are closed in the map's frame only; a provisional fragment has none to close.
  if (config.loop_candidates <= 0 || impl.current_fragment != 0) return finish();
  if (config.background_loop_closure) {
    {
      const std::lock_guard<std::mutex> lock(impl.mutex);
      LoopJob job;
      job.newest = impl.current_keyframe;
      job.features = std::move(features);
      job.intrinsics = frame.intrinsics;
      job.keyframes = impl.keyframes;  // poses and edges: taken when the job starts
      impl.jobs.push_back(std::move(job));
      if (!impl.worker.joinable()) {
        impl.worker = std::thread([&impl] { impl.WorkerLoop(); });
      }
    }
    impl.wake.notify_all();
    return finish();
  }
  LoopClosure closure = impl.CloseLoops(impl.MakeLoopJob(std::move(features), frame.intrinsics));
  report.loop_ms += closure.ms;
  const int loops = impl.Apply(std::move(closure));
  report.loops_closed += loops;
  if (loops > 0) report.T_W_C = impl.last_T_W_C;
  return finish();
}

int RgbdOdometry::FinishLoopClosure() {
  Impl& impl = *impl_;
  int loops = 0;
  double ms = 0.0;
  for (;;) {
    loops += impl.ApplyFinished(&ms);
    std::unique_lock<std::mutex> lock(impl.mutex);
    impl.settled.wait(lock, [&] {
      return !impl.results.empty() || (impl.jobs.empty() && !impl.busy) || !impl.worker.joinable();
    });
    if (impl.results.empty() && ((impl.jobs.empty() && !impl.busy) || !impl.worker.joinable())) {
      return loops;
    }
  }
}

Eigen::Isometry3d RgbdOdometry::KeyframePose(int keyframe) const {
  return impl_->poses.at(static_cast<std::size_t>(keyframe));
}

int RgbdOdometry::KeyframeFragment(int keyframe) const {
  return impl_->fragment_of.at(static_cast<std::size_t>(keyframe));
}

int RgbdOdometry::fragments_started() const { return impl_->fragments_started; }

int RgbdOdometry::fragments_attached() const { return impl_->fragments_attached; }

int RgbdOdometry::loops_closed() const { return impl_->loops_closed; }

const std::vector<PoseGraphEdge>& RgbdOdometry::graph_edges() const { return impl_->edges; }

}  // namespace objmap
