#include "mapper/object_evidence.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "objects/observation_segment.h"

namespace objmap {

bool InventoryConfig::IsValid(std::string* why) const {
  if (!(min_evidence >= 0.f) || !(miss_weight >= 0.f)) {
    *why = "InventoryConfig: min_evidence and miss_weight must be >= 0";
    return false;
  }
  if (min_observations < 1 || !(min_confidence >= 0.f && min_confidence <= 1.f)) {
    *why = "InventoryConfig: min_observations must be >= 1 and min_confidence in [0, 1]";
    return false;
  }
  if (!(absent_min_visibility > 0.f && absent_min_visibility <= 1.f)) {
    *why = "InventoryConfig: absent_min_visibility must be in (0, 1]";
    return false;
  }
  if (!(detectable_area_px > 0.f)) {
    *why = "InventoryConfig: detectable_area_px must be positive";
    return false;
  }
  if (!(occlusion_margin_m >= 0.f) || !(occlusion_margin_per_m2 >= 0.f)) {
    *why = "InventoryConfig: occlusion_margin_m and occlusion_margin_per_m2 must be >= 0";
    return false;
  }
  if (!(unknown_view_score >= 0.f) || unknown_min_views < 1) {
    *why = "InventoryConfig: unknown_view_score must be >= 0 and unknown_min_views >= 1";
    return false;
  }
  if (max_visibility_points < 1) {
    *why = "InventoryConfig: max_visibility_points must be >= 1";
    return false;
  }
  return true;
}

bool ChangeConfig::IsValid(std::string* why) const {
  if (!(see_through_margin_m >= 0.f) || !(see_through_margin_per_m2 >= 0.f)) {
    *why = "ChangeConfig: see_through_margin_m and see_through_margin_per_m2 must be >= 0";
    return false;
  }
  if (!(min_visible_fraction > 0.f && min_visible_fraction <= 1.f) ||
      !(min_empty_fraction > 0.f && min_empty_fraction <= 1.f) ||
      !(min_empty_fraction_over_present >= 0.f && min_empty_fraction_over_present <= 1.f)) {
    *why =
        "ChangeConfig: min_visible_fraction and min_empty_fraction must be in (0, 1], "
        "min_empty_fraction_over_present in [0, 1]";
    return false;
  }
  if (!(min_projected_area_px >= 0.f) || min_empty_views < 1) {
    *why = "ChangeConfig: min_projected_area_px must be >= 0 and min_empty_views >= 1";
    return false;
  }
  if (!(max_move_size_ratio >= 1.f) || !(min_move_distance_m >= 0.f)) {
    *why = "ChangeConfig: max_move_size_ratio must be >= 1 and min_move_distance_m >= 0";
    return false;
  }
  if (!(min_move_colour_overlap >= 0.f && min_move_colour_overlap <= 1.f) ||
      !(move_ambiguity_overlap_margin >= 0.f && move_ambiguity_overlap_margin <= 1.f)) {
    *why =
        "ChangeConfig: min_move_colour_overlap and move_ambiguity_overlap_margin must be in "
        "[0, 1]";
    return false;
  }
  return true;
}

bool CouldJudgePlace(const ObjectVisibility& seen, const ChangeConfig& config) {
  return seen.visible_fraction >= config.min_visible_fraction &&
         seen.projected_area_px >= config.min_projected_area_px;
}

bool SawPlaceEmpty(const ObjectVisibility& seen, const ChangeConfig& config) {
  return CouldJudgePlace(seen, config) && seen.empty_fraction >= config.min_empty_fraction;
}

bool ViewGroupingConfig::IsValid(std::string* why) const {
  if (!(translation_m >= 0.f) || !(rotation_deg >= 0.f)) {
    *why = "ViewGroupingConfig: translation_m and rotation_deg must be >= 0";
    return false;
  }
  return true;
}

bool ViewGroupingConfig::SameView(const Eigen::Isometry3d& anchor_W_C,
                                  const Eigen::Isometry3d& T_W_C) const {
  const Eigen::Isometry3d delta = anchor_W_C.inverse() * T_W_C;
  return delta.translation().norm() <= translation_m &&
         Eigen::AngleAxisd(delta.linear()).angle() <= rotation_deg * M_PI / 180.0;
}

std::vector<Eigen::Vector3f> VisibilitySamples(const MapObject& object, int max_points) {
  const std::size_t size = object.model_W.size();
  const std::size_t step = std::max<std::size_t>(
      1, (size + static_cast<std::size_t>(max_points) - 1) / static_cast<std::size_t>(max_points));
  std::vector<Eigen::Vector3f> samples;
  samples.reserve(std::min(size, static_cast<std::size_t>(max_points)));
  std::size_t index = 0;
  object.model_W.ForEachPoint([&](const Eigen::Vector3f& p) {
    if (index++ % step == 0) samples.push_back(p);
    return true;
  });
  return samples;
}

ObjectVisibility VisibilityIn(const std::vector<Eigen::Vector3f>& samples_W,
                              const Eigen::AlignedBox3f& bounds_W, const Eigen::Isometry3d& T_W_C,
                              const CameraIntrinsics& intrinsics,
                              const std::vector<std::uint16_t>& depth_mm,
                              const InventoryConfig& config, const ChangeConfig& changes) {
  ObjectVisibility visibility;
  if (samples_W.empty()) return visibility;
  const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
  const Eigen::Isometry3f T_W_C_f = T_W_C.cast<float>();
  const float fx = static_cast<float>(intrinsics.fx), fy = static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx), cy = static_cast<float>(intrinsics.cy);
  const int width = intrinsics.width, height = intrinsics.height;
  int visible = 0, seen_through = 0;
  int u_min = width, u_max = -1, v_min = height, v_max = -1;
  for (const Eigen::Vector3f& p_W : samples_W) {
    const Eigen::Vector3f p_C = T_C_W * p_W;
    if (!(p_C.z() > 0.01f)) continue;
    const float u_f = fx * p_C.x() / p_C.z() + cx;
    const float v_f = fy * p_C.y() / p_C.z() + cy;
    if (!(u_f >= 0.f && v_f >= 0.f && u_f < static_cast<float>(width) &&
          v_f < static_cast<float>(height))) {
      continue;
    }
    const int u = static_cast<int>(u_f), v = static_cast<int>(v_f);
    const std::uint16_t measured_mm = depth_mm[static_cast<std::size_t>(v) * width + u];
    if (measured_mm == 0) continue;  // no depth: the view cannot tell whether it is there
    const float measured_m = DepthSampleMetres(measured_mm);
    const float margin_m =
        config.occlusion_margin_m + config.occlusion_margin_per_m2 * measured_m * measured_m;
    // Depth well in front of the point: something hides it, unless that something lies within
    // the object's own bounds (its front hiding its back still shows the object). Depth at or
    // behind it: the view saw the point's place (the object, or through where it should be).
    if (measured_m < p_C.z() - margin_m) {
      const Eigen::Vector3f measured_C = p_C * (measured_m / p_C.z());
      if (!bounds_W.contains(T_W_C_f * measured_C)) continue;
    }
    ++visible;
    const float see_through_m =
        changes.see_through_margin_m + changes.see_through_margin_per_m2 * measured_m * measured_m;
    if (measured_m > p_C.z() + see_through_m) ++seen_through;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  visibility.visible_fraction = static_cast<float>(visible) / static_cast<float>(samples_W.size());
  if (visible > 0) {
    visibility.projected_area_px = static_cast<float>((u_max - u_min + 1) * (v_max - v_min + 1));
    visibility.empty_fraction = static_cast<float>(seen_through) / static_cast<float>(visible);
  }
  return visibility;
}

std::map<KeyframeId, int> IndependentViews(const std::map<KeyframeId, Eigen::Isometry3d>& poses,
                                           const ViewGroupingConfig& config) {
  std::map<KeyframeId, int> view_of;
  const Eigen::Isometry3d* anchor = nullptr;
  int view = -1;
  for (const auto& [id, T_W_C] : poses) {
    if (anchor == nullptr || !config.SameView(*anchor, T_W_C)) {
      anchor = &T_W_C;
      ++view;
    }
    view_of[id] = view;
  }
  return view_of;
}

ObjectEvidence EvidenceOf(const MapObject& object,
                          const std::map<KeyframeId, ObjectVisibility>& visibility,
                          const std::map<KeyframeId, int>& view_of_keyframe,
                          const KeyframeSessionLookup& session_of, const InventoryConfig& config) {
  // The best score any detection of this object had in each keyframe.
  const bool unknown = object.Label() == kUnknownClassId;
  std::map<KeyframeId, float> detected;
  for (const ObjectObservation& observation : object.observations) {
    if (IsUnclassified(observation) != unknown) continue;
    if (unknown) {
      detected[observation.keyframe_id] = config.unknown_view_score;
      continue;
    }
    float best = 0.f;
    for (const auto& [class_id, score] : observation.class_scores) best = std::max(best, score);
    float& entry = detected[observation.keyframe_id];
    entry = std::max(entry, best);
  }
  struct ViewSum {
    double sum = 0.0;
    int keyframes = 0;
    bool detecting = false;
  };
  std::map<int, ViewSum> views;
  ObjectEvidence evidence;
  auto add = [&](KeyframeId keyframe, double value, bool detecting) {
    auto view = view_of_keyframe.find(keyframe);
    if (view == view_of_keyframe.end()) return;
    ViewSum& sum = views[view->second];
    sum.sum += value;
    ++sum.keyframes;
    sum.detecting = sum.detecting || detecting;
    ++evidence.keyframes_seeing;
  };
  std::set<std::int64_t> detecting_sessions;
  for (const auto& [keyframe, score] : detected) {
    add(keyframe, score, true);
    detecting_sessions.insert(session_of(keyframe));
  }
  for (const auto& [keyframe, seen] : visibility) {
    if (detected.count(keyframe) > 0 || !(seen.visible_fraction > 0.f)) continue;
    const float detectability = std::min(1.f, seen.projected_area_px / config.detectable_area_px);
    // Within a session that detected the object, looking through its place says the detection
    // was wrong (a drifted pose, a phantom): a miss like any other. In another session it says
    // the object was not there yet, or no longer: only what the view saw of its surface could
    // have been detected.
    const bool same_world = detecting_sessions.count(session_of(keyframe)) > 0;
    const float there =
        same_world ? seen.visible_fraction : seen.visible_fraction * (1.f - seen.empty_fraction);
    if (there > 0.f) add(keyframe, -config.miss_weight * there * detectability, false);
    if (seen.visible_fraction * detectability >= config.absent_min_visibility) {
      evidence.last_absent = std::max(evidence.last_absent, keyframe);
    }
  }
  double total = 0.0;
  for (const auto& [view, sum] : views) {
    total += sum.sum / sum.keyframes;
    if (sum.detecting) ++evidence.views_detecting;
  }
  evidence.evidence = static_cast<float>(total);
  evidence.views_seeing = static_cast<int>(views.size());
  return evidence;
}

}  // namespace objmap
