#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace objmap {

/// When a frame becomes a keyframe: after enough camera motion since the last keyframe.
struct KeyframeSelectorConfig {
  /// Translation since the last keyframe that makes a new one, metres.
  double min_translation_m = 0.10;
  /// Rotation since the last keyframe that makes a new one, degrees.
  double min_rotation_deg = 10.0;
  /// Take every frame as a keyframe (motion thresholds ignored).
  bool every_frame = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Decides keyframes in sequence order. Thread-safety: none (keeps the last keyframe pose).
class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeSelectorConfig& config) : config_(config) {}

  /// True when the frame at pose T_W_C is a keyframe; the first frame always is.
  [[nodiscard]] bool IsKeyframe(const Eigen::Isometry3d& T_W_C);

 private:
  KeyframeSelectorConfig config_;
  std::optional<Eigen::Isometry3d> last_keyframe_T_W_C_;
};

}  // namespace objmap
