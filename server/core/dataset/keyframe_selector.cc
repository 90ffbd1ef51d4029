#include "dataset/keyframe_selector.h"

#include <cmath>

namespace objmap {

bool KeyframeSelectorConfig::IsValid(std::string* why) const {
  if (!(min_translation_m >= 0.0) || !(min_rotation_deg >= 0.0) || every_nth_frame < 0) {
    *why =
        "KeyframeSelectorConfig: min_translation_m, min_rotation_deg and every_nth_frame must be "
        ">= 0";
    return false;
  }
  return true;
}

bool KeyframeSelector::IsKeyframe(const Eigen::Isometry3d& T_W_C) {
  const long long index = frames_offered_++;
  if (config_.every_nth_frame > 0) return index % config_.every_nth_frame == 0;
  if (!last_keyframe_T_W_C_) {
    last_keyframe_T_W_C_ = T_W_C;
    return true;
  }
  const Eigen::Isometry3d T_last_current = last_keyframe_T_W_C_->inverse() * T_W_C;
  const double translation_m = T_last_current.translation().norm();
  const double rotation_deg = Eigen::AngleAxisd(T_last_current.linear()).angle() * 180.0 / M_PI;
  if (translation_m >= config_.min_translation_m || rotation_deg >= config_.min_rotation_deg) {
    last_keyframe_T_W_C_ = T_W_C;
    return true;
  }
  return false;
}

}  // namespace objmap
