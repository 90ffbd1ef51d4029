#pragma once
// A z-buffer rasterizer for synthetic scenes: colour with simple shading, depth with a
// Kinect-like noise model, and per-pixel instance ids. Deterministic: the same scene, pose,
// seed and frame index give the same images on every machine.

#include <cstdint>
#include <string>
#include <vector>

#include "sim/scene.h"

namespace objmap::sim {

/// Kinect-like depth errors (after Nguyen, Izadi and Lovell, 3DIMPVT 2012, and Khoshelham and
/// Elberink, Sensors 2012).
struct DepthNoiseConfig {
  bool enabled = true;
  /// Axial noise sigma(z) = a + b (z - z0)^2, metres.
  double axial_a_m = 0.0012;
  double axial_b_per_m = 0.0019;
  double axial_z0_m = 0.4;
  /// Disparity quantization: the sensor measures disparity fx * baseline / z in steps of
  /// 1 / disparity_subpixels pixel, so depth comes in steps of about z^2 / (subpixels fx baseline)
  /// (11 mm at 2 m for the Kinect's 7.5 cm baseline and 1/8 pixel). 0 subpixels: no quantization.
  double baseline_m = 0.075;
  int disparity_subpixels = 8;
  /// Valid range; nearer or farther pixels read 0.
  double min_depth_m = 0.5;
  double max_depth_m = 4.5;
  /// Surfaces seen more obliquely than this (angle between the view ray and the normal) read 0.
  double max_incidence_deg = 78.0;
  /// A pixel next to a depth jump of more than this fraction of its depth reads 0 with this
  /// probability (the flying and missing pixels at object edges).
  double edge_jump_fraction = 0.04;
  double edge_dropout_probability = 0.6;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

struct RenderedFrame {
  ColorImage color;
  DepthImage depth;                     ///< metres, noisy, 0 where invalid
  std::vector<float> true_depth_m;      ///< before noise, 0 where nothing is hit
  std::vector<std::uint16_t> instance;  ///< SceneObject::id per pixel, 0 for the structure
};

/// Renders the scene from T_W_C with the scene's intrinsics. `frame_index` and `seed` pick the
/// noise, so every frame's noise differs and a run can be repeated exactly.
[[nodiscard]] RenderedFrame Render(const Scene& scene, const Eigen::Isometry3d& T_W_C,
                                   const DepthNoiseConfig& noise, std::uint64_t seed,
                                   int frame_index);

}  // namespace objmap::sim
