#pragma once
// A synthetic scene written as a recorded sequence in the 7-Scenes layout the readers take
// (frame-NNNNNN.color.png, .depth.png in mm, .pose.txt, camera-intrinsics.txt) plus
// frame-NNNNNN.instance.png (16-bit instance ids), detections.json (the ground-truth detector's
// output, in the format of `objmap map --detections`), ground_truth.json (the format of
// `objmap eval --gt`) and, with drift, corrected_poses.txt (`objmap map --corrected-poses`).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "sim/renderer.h"
#include "sim/scene.h"
#include "types/detection.h"

namespace objmap::sim {

/// The ground-truth detector: boxes from the instance image, with the errors of a real one.
struct DetectorNoiseConfig {
  /// Objects showing fewer pixels are never detected.
  int min_visible_px = 150;
  /// Chance to miss a detectable object; grows towards 1 for small (below small_object_px
  /// visible pixels) and far (beyond far_m) objects.
  double miss_probability = 0.1;
  int small_object_px = 1500;
  double far_m = 3.0;
  /// Chance to report a look-alike class instead (tv/laptop, cup/bowl, chair/couch, ...).
  double confusion_probability = 0.05;
  /// Expected spurious detections per frame (a random box, a random indoor class).
  double false_positives_per_frame = 0.05;
  /// Sigma of each box edge, as a fraction of the box's width or height.
  double box_jitter = 0.05;
  /// Scores of real detections ~ N(mean, sigma) clamped to [0.2, 0.99]; spurious ones are lower.
  double score_mean = 0.65;
  double score_sigma = 0.15;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Detections of one rendered frame; deterministic for (seed, frame_index).
[[nodiscard]] std::vector<Detection> DetectFromInstances(const Scene& scene,
                                                         const RenderedFrame& frame,
                                                         const Eigen::Isometry3d& T_W_C,
                                                         const DetectorNoiseConfig& config,
                                                         std::uint64_t seed, int frame_index);

/// ground_truth.json of the scene: per object id, class, name, box pose (4x4 row by row) and
/// size (metres) from its mesh, the frames that showed it (`visible_frames`: at least the
/// detector's min_visible_px pixels of it), `surface_points` samples of its surface and the
/// surface mesh itself (vertices and triangles, world frame); the seen surface's files.
[[nodiscard]] std::string GroundTruthJson(const Scene& scene, int surface_points,
                                          double seen_voxel_m,
                                          const std::map<int, int>& visible_frames);

/// Odometry drift: the poses written with the frames are what a drifting tracker reports; the
/// true ones go to corrected_poses.txt, as a loop closure would give them back.
struct DriftConfig {
  bool enabled = false;
  /// Heading error per metre travelled (a bias), and its frame-to-frame noise, degrees.
  double yaw_bias_deg_per_m = 2.0;
  double yaw_noise_deg_per_m = 0.5;
  /// Odometry scale error: travelled distances come out this fraction too long.
  double scale_error = 0.02;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The poses a drifting tracker reports along `trajectory` (the first pose is exact).
[[nodiscard]] std::vector<Eigen::Isometry3d> DriftedTrajectory(
    const std::vector<Eigen::Isometry3d>& trajectory, const DriftConfig& drift, std::uint64_t seed);

struct SequenceOptions {
  DepthNoiseConfig depth_noise;
  DetectorNoiseConfig detector;
  DriftConfig drift;
  int surface_points = 2000;  ///< per object in ground_truth.json
  /// The seen surface (seen_structure.ply, seen_objects.ply) keeps one exact surface point per
  /// voxel of this size that the sensor returned depth for within seen_max_range_m: what the
  /// OctoMap (1 cm, 4 m range by default) is scored against.
  double seen_voxel_m = 0.01;
  double seen_max_range_m = 4.0;
};

/// Renders every pose of the scene's trajectory into `dir` (created when missing). False with
/// a reason naming the file that could not be written.
[[nodiscard]] bool WriteSequence(const Scene& scene, const SequenceOptions& options,
                                 const std::string& dir, std::string* why);

}  // namespace objmap::sim
