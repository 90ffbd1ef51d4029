// Placing a camera that may be anywhere in RgbdOdometry's map (a new session, tracking lost): the
// keyframes that look like the frame, fits voted on by consensus, and the provisional fragments
// that frames no keyframe places are tracked in until one of them is placed.
#include <cstdio>

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
