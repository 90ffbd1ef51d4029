// RgbdOdometry: tracking a frame against its keyframe (features, PnP, dense refinement),
// relocalisation after a failure, and the public interface. Loop closure is in
// odometry_loops.cc, placement in the map and provisional fragments in odometry_placement.cc.
#include "odometry/rgbd_odometry.h"

#include <exception>
#include <opencv2/imgproc.hpp>

#include "odometry/odometry_impl.h"

namespace objmap {

using namespace odometry_detail;

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
  if (relocalisation_map_candidates < 0 || relocalisation_map_ransac_iterations < 1 ||
      relocalisation_map_min_inliers < min_inliers || relocalisation_map_keyframe_min_inliers < 1 ||
      relocalisation_map_min_keyframes < 1) {
    *why =
        "odometry: relocalisation_map_candidates >= 0, relocalisation_map_ransac_iterations >= 1, "
        "relocalisation_map_min_inliers >= min_inliers, relocalisation_map_keyframe_min_inliers "
        "and relocalisation_map_min_keyframes >= 1";
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

namespace {

Eigen::Matrix<double, 6, 6> EdgeInformation(double sigma_m, double sigma_rad) {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  information.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return information;
}

}  // namespace

void RgbdOdometry::Impl::Accept(const PoseFit& fit, const Eigen::Isometry3d& T_W_C,
                                TrackingReport* report) {
  report->T_W_C = T_W_C;
  report->matches = fit.matches;
  report->inliers = fit.inliers;
  report->reprojection_rmse_px = fit.rmse_px;
  report->depth_refined = fit.depth_refined;
  report->depth_rmse_m = fit.depth_rmse_m;
  has_last = true;
  last_tracked = true;
  last_T_W_C = T_W_C;
}

void RgbdOdometry::Impl::AddOdometryEdge(int from, int to,
                                         const Eigen::Matrix<double, 6, 6>& information) {
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.T_from_to =
      poses[static_cast<std::size_t>(from)].inverse() * poses[static_cast<std::size_t>(to)];
  edge.information = information;
  const std::lock_guard<std::mutex> lock(mutex);
  edges.push_back(edge);
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
  return AlignmentInformation(fit.alignment.hessian, fit.alignment.centre, fit.alignment.radius_m,
                              fit.T_K_C.translation(), floor) +
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
  const bool solved = SeededPnPRansac(object_points, image_points, camera, config.ransac_iterations,
                                      config.ransac_reprojection_px, &rvec, &tvec, &inliers);
  fit.inliers = static_cast<int>(inliers.size());
  if (!solved || fit.inliers < config.min_inliers) {
    fit.why = std::to_string(fit.inliers) + " PnP inliers of " + std::to_string(fit.matches) +
              " matches, " + std::to_string(config.min_inliers) + " needed";
    return fit;
  }
  fit.rmse_px = RefineOnInliers(object_points, image_points, inliers, camera, &rvec, &tvec);
  // PnP maps keyframe points into this camera: T_C_K.
  Eigen::Isometry3d T_K_C = FromRvecTvec(rvec, tvec).inverse();
  if (config.depth_refinement) RefineByDepth(features, keyframe, &T_K_C, &fit);
  fit.T_K_C = T_K_C;
  fit.ok = true;
  return fit;
}

RgbdOdometry::RgbdOdometry(const OdometryConfig& config) : impl_(std::make_unique<Impl>(config)) {}
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
  const int with_depth =
      static_cast<int>(std::count(features->valid.begin(), features->valid.end(), std::uint8_t{1}));

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
    if (step.translation().norm() > config.max_step_m ||
        AngleDeg(step.linear()) > config.max_step_deg) {
      *why = "implausible motion since the last frame";
      return false;
    }
    return true;
  };

  // Without a recent tracked pose, the camera may be anywhere: every fit must be strong.
  const bool strict = !impl.has_last || !impl.last_tracked;
  auto strong = [&](const PoseFit& candidate) { return impl.Strong(candidate); };
  PoseFit fit =
      impl.Fit(*features, *impl.keyframes[static_cast<std::size_t>(impl.current_keyframe)],
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
    if (!accepted) {
      std::string conflict;
      int chosen = votes.empty() ? -1
                                 : impl.ConsensusWithNeighbours(*features, frame.intrinsics, &votes,
                                                                &conflict);
      if (!conflict.empty()) first_failure = conflict;
      if (chosen < 0) {
        // No keyframe alone: the look-alikes' points together.
        std::string pooled;
        chosen = impl.PlaceByMapPoints(*features, frame.intrinsics, &votes, &pooled);
        if (chosen < 0 && conflict.empty() && !pooled.empty()) first_failure = pooled;
      }
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
      impl.Accept(placement, T_W_C, &report);
      return finish();
    }
    report.status = TrackingStatus::kProvisional;
    report.fragment = fragment;
    report.why = not_placed;
  }
  const Eigen::Isometry3d T_W_C = pose_of(report.reference_keyframe) * fit.T_K_C;
  impl.Accept(fit, T_W_C, &report);

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
