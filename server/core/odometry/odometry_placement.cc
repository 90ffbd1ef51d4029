// Placing a camera that may be anywhere in RgbdOdometry's map (a new session, tracking lost): the
// keyframes that look like the frame, fits voted on by consensus, else one fit to the points of
// those keyframes together, and the provisional fragments that frames neither places are tracked
// in until one of them is placed.
#include <cstdio>
#include <map>

#include "odometry/odometry_impl.h"

namespace objmap {

using namespace odometry_detail;

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

bool RgbdOdometry::Impl::WithinConsensus(const Eigen::Isometry3d& apart) const {
  return apart.translation().norm() <= config.relocalisation_consensus_m &&
         AngleDeg(apart.linear()) <= config.relocalisation_consensus_deg;
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
    return WithinConsensus(pose_of_vote(a).inverse() * pose_of_vote(b));
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
  const Eigen::Isometry3d T_W_C = pose_of_vote(chosen);
  for (const Vote& vote : votes) {
    if (fragment_of[static_cast<std::size_t>(vote.keyframe)] != fragment) continue;
    const Eigen::Isometry3d apart = T_W_C.inverse() * pose_of_vote(vote);
    if (!WithinConsensus(apart)) {
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

int RgbdOdometry::Impl::PlaceByMapPoints(const FrameFeatures& features, const CameraIntrinsics& K,
                                         std::vector<Vote>* votes, std::string* why) {
  if (config.relocalisation_map_candidates <= 0 || features.descriptors.empty()) return -1;
  // The map keyframes that look most like the frame (the map's frame only: their points must
  // share one frame).
  IndexKeyframes(keyframes, static_cast<int>(keyframes.size()) - 1, &relocalisation_index,
                 &relocalisation_indexed);
  const cv::Mat mine = StrongestDescriptors(features, config.appearance_descriptors);
  if (mine.rows < 2 || !mine.isContinuous()) return -1;
  std::vector<int> candidates;
  for (const auto& [alike, k] : relocalisation_index.MostAlike(
           mine.ptr<std::uint8_t>(), mine.rows, static_cast<int>(keyframes.size()) - 1,
           static_cast<int>(keyframes.size()))) {
    if (fragment_of[static_cast<std::size_t>(k)] != 0) continue;
    candidates.push_back(k);
    if (static_cast<int>(candidates.size()) >= config.relocalisation_map_candidates) break;
  }
  // Every candidate's ratio-test matches, its points in the map's frame.
  std::vector<cv::Point3f> object_points;
  std::vector<cv::Point2f> image_points;
  std::vector<int> keyframe_of, keypoint_of;
  const cv::BFMatcher matcher(cv::NORM_HAMMING);
  for (const int k : candidates) {
    const Keyframe& keyframe = *keyframes[static_cast<std::size_t>(k)];
    if (keyframe.descriptors.rows < 2) continue;
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(features.descriptors, keyframe.descriptors, knn, 2);
    const Eigen::Isometry3d& T_W_K = poses[static_cast<std::size_t>(k)];
    for (const auto& pair : knn) {
      if (pair.size() < 2 || pair[0].distance >= config.match_ratio * pair[1].distance) continue;
      const cv::Point3f& p = keyframe.points_K[static_cast<std::size_t>(pair[0].trainIdx)];
      const Eigen::Vector3d p_W = T_W_K * Eigen::Vector3d(p.x, p.y, p.z);
      object_points.emplace_back(static_cast<float>(p_W.x()), static_cast<float>(p_W.y()),
                                 static_cast<float>(p_W.z()));
      image_points.push_back(features.keypoints[static_cast<std::size_t>(pair[0].queryIdx)].pt);
      keyframe_of.push_back(k);
      keypoint_of.push_back(pair[0].queryIdx);
    }
  }
  auto refuse = [&](const std::string& reason) {
    *why = reason;
    return -1;
  };
  if (static_cast<int>(object_points.size()) < config.relocalisation_map_min_inliers) {
    return refuse("no keyframe of the map fits the frame, nor " +
                  std::to_string(candidates.size()) + " look-alikes together (" +
                  std::to_string(object_points.size()) + " matches)");
  }
  const cv::Matx33d camera(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (!SeededPnPRansac(object_points, image_points, camera,
                       config.relocalisation_map_ransac_iterations, config.ransac_reprojection_px,
                       &rvec, &tvec, &inliers))
    return refuse("no pose fits the look-alike keyframes' points together");
  // Inliers are counted once per keypoint of the frame (one keypoint may match a point of
  // several keyframes), and per keyframe.
  std::vector<std::uint8_t> keypoint_inlier(features.keypoints.size(), 0);
  std::map<int, int> per_keyframe;
  for (const int i : inliers) {
    keypoint_inlier[static_cast<std::size_t>(keypoint_of[static_cast<std::size_t>(i)])] = 1;
    ++per_keyframe[keyframe_of[static_cast<std::size_t>(i)]];
  }
  const int distinct =
      static_cast<int>(std::count(keypoint_inlier.begin(), keypoint_inlier.end(), std::uint8_t{1}));
  int supporting = 0, reference = -1, most = 0;
  for (const auto& [k, n] : per_keyframe) {
    supporting += n >= config.relocalisation_map_keyframe_min_inliers;
    if (n > most) {
      most = n;
      reference = k;
    }
  }
  if (distinct < config.relocalisation_map_min_inliers ||
      supporting < config.relocalisation_map_min_keyframes) {
    char text[240];
    std::snprintf(text, sizeof(text),
                  "no keyframe of the map fits the frame strongly; the %zu look-alikes together: "
                  "%d inliers (%d needed), %d keyframes with %d or more (%d needed)",
                  candidates.size(), distinct, config.relocalisation_map_min_inliers, supporting,
                  config.relocalisation_map_keyframe_min_inliers,
                  config.relocalisation_map_min_keyframes);
    return refuse(text);
  }
  PoseFit fit;
  fit.rmse_px = RefineOnInliers(object_points, image_points, inliers, camera, &rvec, &tvec);
  const Eigen::Isometry3d T_W_C = FromRvecTvec(rvec, tvec).inverse();
  fit.matches = static_cast<int>(object_points.size());
  fit.inliers = distinct;
  const Eigen::Isometry3d T_K_C_features =
      poses[static_cast<std::size_t>(reference)].inverse() * T_W_C;
  Eigen::Isometry3d T_K_C = T_K_C_features;
  if (config.depth_refinement) {
    RefineByDepth(features, *keyframes[static_cast<std::size_t>(reference)], &T_K_C, &fit);
    if (!fit.depth_refined) {
      return refuse(
          "the look-alike keyframes together place the frame, but its depth does not "
          "align with keyframe " +
          std::to_string(reference) + "'s there");
    }
    // Features of many keyframes fix the pose within a few millimetres; a dense step that moves
    // it farther than the consensus limits slid along a plane (a desk top and the wall behind it
    // leave one direction free): the frame is not placed, a later one is.
    const Eigen::Isometry3d correction = T_K_C_features.inverse() * T_K_C;
    if (!WithinConsensus(correction)) {
      char text[200];
      std::snprintf(text, sizeof(text),
                    "the look-alike keyframes together place the frame, but its depth moves the "
                    "pose %.1f cm and %.1f deg from there (a plane leaving a direction free?)",
                    100.0 * correction.translation().norm(), AngleDeg(correction.linear()));
      return refuse(text);
    }
  }
  fit.T_K_C = T_K_C;
  fit.ok = true;
  votes->push_back({reference, std::move(fit)});
  return static_cast<int>(votes->size()) - 1;
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
  int chosen = ConsensusWithNeighbours(features, K, &votes, &conflict);
  if (chosen < 0) {
    std::string pooled;
    chosen = PlaceByMapPoints(features, K, &votes, &pooled);
    if (chosen < 0 && conflict.empty() && !pooled.empty()) conflict = pooled;
  }
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
    *fit = std::move(candidate);
    *reference = k;
    return true;
  }
  *why = !conflict.empty() ? conflict
         : votes.empty()   ? "no keyframe of the map fits the frame"
                           : "no keyframe of the map fits the frame strongly";
  return false;
}

}  // namespace objmap
