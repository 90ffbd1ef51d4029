#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace objmap {

/// When a frame becomes a keyframe: after enough camera motion since the last keyframe, or every
/// Nth frame (a fixed choice, the same whatever the poses say: runs of one sequence with other
/// poses, drifting and corrected, then map the same frames).
struct KeyframeSelectorConfig {
  /// Translation since the last keyframe that makes a new one, metres.
  double min_translation_m = 0.10;
  /// Rotation since the last keyframe that makes a new one, degrees.
  double min_rotation_deg = 10.0;
  /// 0: by motion. N > 0: frames 0, N, 2N, ... of those offered are keyframes (1: every frame),
  /// motion ignored.
  int every_nth_frame = 0;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Decides keyframes in sequence order. Thread-safety: none (keeps the last keyframe pose).
class KeyframeSelector {
 public:
  explicit KeyframeSelector(const KeyframeSelectorConfig& config) : config_(config) {}

  /// True when the frame at pose T_W_C (the next one in sequence order) is a keyframe; the first
  /// frame always is.
  [[nodiscard]] bool IsKeyframe(const Eigen::Isometry3d& T_W_C);

 private:
  KeyframeSelectorConfig config_;
  std::optional<Eigen::Isometry3d> last_keyframe_T_W_C_;
  long long frames_offered_ = 0;
};

}  // namespace objmap
