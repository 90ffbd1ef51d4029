#include "sim/sequence_writer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "detection/detections_file.h"
#include "evaluation/voxel_set.h"
#include "pointcloud_io/pointcloud_io.h"
#include "sim/sim_random.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

namespace fs = std::filesystem;

// Classes a detector takes for one another.
int LookAlike(int class_id) {
  static const std::map<std::string, std::string> kPairs = {
      {"tv", "laptop"},   {"laptop", "tv"},         {"cup", "bowl"},
      {"chair", "couch"}, {"keyboard", "remote"},   {"mouse", "remote"},
      {"book", "laptop"}, {"potted plant", "vase"}, {"dining table", "bench"}};
  const auto it = kPairs.find(std::string(CocoClassName(class_id)));
  return it == kPairs.end() ? class_id : CocoClassId(it->second);
}

float Score(double mean, double sigma, Random* random) {
  return static_cast<float>(std::clamp(mean + sigma * random->Normal(), 0.2, 0.99));
}

std::string FrameStem(int index) {
  char stem[32];
  std::snprintf(stem, sizeof(stem), "frame-%06d", index);
  return stem;
}

bool WriteMatrix(const std::string& path, const Eigen::Matrix4d& T, int rows, std::string* why) {
  std::ofstream out(path);
  char line[128];
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < (rows == 3 ? 3 : 4); ++c) {
      std::snprintf(line, sizeof(line), "%s%.18e", c == 0 ? "" : " ", T(r, c));
      out << line;
    }
    out << "\n";
  }
  if (!out) *why = path + ": write failed";
  return static_cast<bool>(out);
}

bool WritePng(const std::string& path, const cv::Mat& image, std::string* why) {
  if (cv::imwrite(path, image)) return true;
  *why = path + ": write failed";
  return false;
}

// The box of an object: centre and extents of its mesh in its own frame.
void ObjectBox(const SceneObject& object, Eigen::Isometry3d* T_W_B, Eigen::Vector3d* size) {
  Eigen::Vector3f min, max;
  object.mesh.Bounds(&min, &max);
  *T_W_B = object.T_W_O * Eigen::Translation3d((0.5f * (min + max)).cast<double>());
  *size = (max - min).cast<double>();
}

}  // namespace

bool DetectorNoiseConfig::IsValid(std::string* why) const {
  auto probability = [](double p) { return p >= 0.0 && p <= 1.0; };
  if (min_visible_px < 1 || small_object_px < min_visible_px || !(far_m > 0.0) ||
      !probability(miss_probability) || !probability(confusion_probability) ||
      !(false_positives_per_frame >= 0.0) || !(box_jitter >= 0.0) || !probability(score_mean) ||
      !(score_sigma >= 0.0)) {
    *why =
        "DetectorNoiseConfig: min_visible_px >= 1, small_object_px >= min_visible_px, "
        "far_m > 0, probabilities in [0, 1], rates and sigmas >= 0 are required";
    return false;
  }
  return true;
}

bool DriftConfig::IsValid(std::string* why) const {
  if (!std::isfinite(yaw_bias_deg_per_m) || !(yaw_noise_deg_per_m >= 0.0) ||
      !(scale_error > -0.5 && scale_error < 0.5)) {
    *why = "DriftConfig: finite yaw bias, yaw noise >= 0 and |scale_error| < 0.5 are required";
    return false;
  }
  return true;
}

std::vector<Eigen::Isometry3d> DriftedTrajectory(const std::vector<Eigen::Isometry3d>& trajectory,
                                                 const DriftConfig& drift, std::uint64_t seed) {
  std::vector<Eigen::Isometry3d> drifted;
  if (trajectory.empty()) return drifted;
  drifted.push_back(trajectory.front());
  Random random(seed, 0xD81F7ull);
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    // The motion between frames as odometry measures it: longer by the scale error, and turned
    // about the vertical by an error that grows with the distance.
    const Eigen::Isometry3d step = trajectory[k - 1].inverse() * trajectory[k];
    const Eigen::Vector3d move_W = trajectory[k - 1].linear() * step.translation();
    const double metres = move_W.norm();
    const double yaw_deg =
        drift.yaw_bias_deg_per_m * metres + drift.yaw_noise_deg_per_m * metres * random.Normal();
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::Isometry3d next = Eigen::Isometry3d::Identity();
    // World-frame increments applied to the drifted pose: heading error accumulates, so later
    // moves go in a turned direction.
    const Eigen::Matrix3d heading =
        drifted.back().linear() * trajectory[k - 1].linear().transpose();
    next.linear() = turn * heading * trajectory[k].linear();
    next.translation() =
        drifted.back().translation() + turn * heading * move_W * (1.0 + drift.scale_error);
    drifted.push_back(next);
  }
  return drifted;
}

std::vector<Detection> DetectFromInstances(const Scene& scene, const RenderedFrame& frame,
                                           const Eigen::Isometry3d& T_W_C,
                                           const DetectorNoiseConfig& config, std::uint64_t seed,
                                           int frame_index) {
  const int width = frame.depth.width, height = frame.depth.height;
  struct Extent {
    int pixels = 0;
    int u_min = 1 << 30, v_min = 1 << 30, u_max = -1, v_max = -1;
  };
  std::map<int, Extent> extents;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int id = frame.instance[static_cast<std::size_t>(v) * width + u];
      if (id == 0) continue;
      Extent& e = extents[id];
      ++e.pixels;
      e.u_min = std::min(e.u_min, u), e.u_max = std::max(e.u_max, u);
      e.v_min = std::min(e.v_min, v), e.v_max = std::max(e.v_max, v);
    }
  }
  Random random(seed, 0xDE7EC7ull, static_cast<std::uint64_t>(frame_index));
  std::vector<Detection> detections;
  for (const SceneObject& object : scene.objects) {
    const auto it = extents.find(object.id);
    if (it == extents.end() || it->second.pixels < config.min_visible_px) continue;
    const Extent& e = it->second;
    const double distance = (object.T_W_O.translation() - T_W_C.translation()).norm();
    double miss = config.miss_probability;
    if (e.pixels < config.small_object_px) {
      miss += (1.0 - miss) * (1.0 - static_cast<double>(e.pixels) / config.small_object_px);
    }
    if (distance > config.far_m)
      miss += (1.0 - miss) * std::min(1.0, (distance - config.far_m) / config.far_m);
    if (random.Uniform() < miss) continue;
    const double w = e.u_max - e.u_min + 1, h = e.v_max - e.v_min + 1;
    Detection d;
    d.box.x_min = static_cast<float>(
        std::clamp(e.u_min + config.box_jitter * w * random.Normal(), 0.0, width - 2.0));
    d.box.y_min = static_cast<float>(
        std::clamp(e.v_min + config.box_jitter * h * random.Normal(), 0.0, height - 2.0));
    d.box.x_max = static_cast<float>(std::clamp(e.u_max + config.box_jitter * w * random.Normal(),
                                                d.box.x_min + 1.0, width - 1.0));
    d.box.y_max = static_cast<float>(std::clamp(e.v_max + config.box_jitter * h * random.Normal(),
                                                d.box.y_min + 1.0, height - 1.0));
    d.class_id = random.Uniform() < config.confusion_probability ? LookAlike(object.class_id)
                                                                 : object.class_id;
    d.score = Score(config.score_mean, config.score_sigma, &random);
    detections.push_back(d);
  }
  // Spurious detections: a Poisson-like count from one uniform draw per expected tenth.
  static const char* const kIndoor[] = {"cup", "book", "chair", "tv", "bottle", "laptop"};
  for (double left = config.false_positives_per_frame; left > 0.0; left -= 1.0) {
    if (random.Uniform() >= std::min(1.0, left)) continue;
    Detection d;
    const double bw = random.Uniform(30.0, 150.0), bh = random.Uniform(30.0, 150.0);
    d.box.x_min = static_cast<float>(random.Uniform(0.0, width - bw - 1.0));
    d.box.y_min = static_cast<float>(random.Uniform(0.0, height - bh - 1.0));
    d.box.x_max = d.box.x_min + static_cast<float>(bw);
    d.box.y_max = d.box.y_min + static_cast<float>(bh);
    d.class_id = CocoClassId(kIndoor[random.Next() % 6]);
    d.score = Score(config.score_mean - 0.3, config.score_sigma, &random);
    detections.push_back(d);
  }
  return detections;
}

// The real surface the sensor saw: one exact (noise-free) point per voxel, first come, with its
// rendered colour, apart for the structure and the objects.
class SeenSurface {
 public:
  explicit SeenSurface(double voxel_m) : structure_(voxel_m), objects_(voxel_m) {}

  void Add(const RenderedFrame& frame, const Eigen::Isometry3d& T_W_C, const CameraIntrinsics& K,
           double max_range_m) {
    const Eigen::Isometry3f T = T_W_C.cast<float>();
    for (int v = 0; v < K.height; ++v) {
      for (int u = 0; u < K.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * K.width + u;
        const float z = frame.true_depth_m[i];
        // Seen: the sensor returned depth there (not dropped as grazing, at an edge or out of
        // range), and near enough for the map to mark it.
        if (frame.depth.depth_m[i] <= 0.f || z <= 0.f || z > max_range_m) continue;
        const Eigen::Vector3f p_W =
            T * Eigen::Vector3f(static_cast<float>((u - K.cx) / K.fx * z),
                                static_cast<float>((v - K.cy) / K.fy * z), z);
        Part& part = frame.instance[i] == 0 ? structure_ : objects_;
        if (!part.voxels.Insert(p_W.cast<double>())) continue;
        part.points.push_back(p_W);
        part.colors.push_back(
            {frame.color.rgb[3 * i], frame.color.rgb[3 * i + 1], frame.color.rgb[3 * i + 2]});
      }
    }
  }

  bool Write(const std::string& structure_path, const std::string& objects_path,
             std::string* why) const {
    return WritePly(structure_path, structure_.points, structure_.colors, why) &&
           WritePly(objects_path, objects_.points, objects_.colors, why);
  }

 private:
  struct Part {
    explicit Part(double voxel_m) : voxels(voxel_m) {}
    VoxelSet voxels;  // those that have their point
    std::vector<Eigen::Vector3f> points;
    std::vector<std::array<std::uint8_t, 3>> colors;
  };
  Part structure_, objects_;
};

std::string GroundTruthJson(const Scene& scene, int surface_points, double seen_voxel_m,
                            const std::map<int, int>& visible_frames) {
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (const SceneObject& object : scene.objects) {
    Eigen::Isometry3d T_W_B;
    Eigen::Vector3d size;
    ObjectBox(object, &T_W_B, &size);
    std::vector<double> pose;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) pose.push_back(T_W_B.matrix()(r, c));
    }
    nlohmann::ordered_json samples = nlohmann::ordered_json::array();
    const Eigen::Isometry3f T_W_O = object.T_W_O.cast<float>();
    for (const Eigen::Vector3f& p : object.mesh.SampleSurface(
             static_cast<std::size_t>(surface_points), scene.seed * 7919 + object.id)) {
      const Eigen::Vector3f q = T_W_O * p;
      samples.push_back({q.x(), q.y(), q.z()});
    }
    // The surface itself, so that model accuracy is a distance to it, not to the nearest of the
    // samples (spaced a few centimetres apart on large objects).
    nlohmann::ordered_json vertices = nlohmann::ordered_json::array();
    for (const Eigen::Vector3f& p : object.mesh.vertices) {
      const Eigen::Vector3f q = T_W_O * p;
      vertices.push_back({q.x(), q.y(), q.z()});
    }
    nlohmann::ordered_json triangles = nlohmann::ordered_json::array();
    for (const Eigen::Vector3i& t : object.mesh.triangles) triangles.push_back({t[0], t[1], t[2]});
    const auto visible = visible_frames.find(object.id);
    objects.push_back({{"id", object.id},
                       {"class", std::string(CocoClassName(object.class_id))},
                       {"name", object.name},
                       {"pose", pose},
                       {"size", {size.x(), size.y(), size.z()}},
                       {"visible_frames", visible == visible_frames.end() ? 0 : visible->second},
                       {"surface_sample", samples},
                       {"surface_mesh", {{"vertices", vertices}, {"triangles", triangles}}}});
  }
  return nlohmann::ordered_json{{"kind", scene.kind},
                                {"seed", scene.seed},
                                {"objects", objects},
                                {"seen_surface",
                                 {{"voxel_size_m", seen_voxel_m},
                                  {"structure", "seen_structure.ply"},
                                  {"objects", "seen_objects.ply"}}}}
      .dump(1);
}

bool WriteSequence(const Scene& scene, const SequenceOptions& options, const std::string& dir,
                   std::string* why) {
  if (!options.depth_noise.IsValid(why) || !options.detector.IsValid(why) ||
      !options.drift.IsValid(why)) {
    return false;
  }
  if (!(options.seen_voxel_m > 0.0) || !(options.seen_max_range_m > 0.0)) {
    *why = "SequenceOptions: seen_voxel_m and seen_max_range_m must be > 0";
    return false;
  }
  // What the tracker reports; the frames are rendered from the true poses.
  const std::vector<Eigen::Isometry3d> reported =
      options.drift.enabled ? DriftedTrajectory(scene.trajectory, options.drift, scene.seed)
                            : scene.trajectory;
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) {
    *why = dir + ": " + error.message();
    return false;
  }
  const CameraIntrinsics& K = scene.intrinsics;
  Eigen::Matrix4d intrinsics = Eigen::Matrix4d::Zero();
  intrinsics(0, 0) = K.fx, intrinsics(0, 2) = K.cx, intrinsics(1, 1) = K.fy,
                intrinsics(1, 2) = K.cy, intrinsics(2, 2) = 1.0;
  if (!WriteMatrix((fs::path(dir) / "camera-intrinsics.txt").string(), intrinsics, 3, why)) {
    return false;
  }
  DetectionsByFrame detections;
  SeenSurface seen(options.seen_voxel_m);
  std::map<int, int> visible_frames;  // object id -> frames showing >= min_visible_px of it
  for (std::size_t f = 0; f < scene.trajectory.size(); ++f) {
    const int index = static_cast<int>(f);
    const Eigen::Isometry3d& T_W_C = scene.trajectory[f];
    const RenderedFrame frame = Render(scene, T_W_C, options.depth_noise, scene.seed, index);
    const std::string stem = (fs::path(dir) / FrameStem(index)).string();
    cv::Mat color(K.height, K.width, CV_8UC3), depth(K.height, K.width, CV_16UC1),
        instance(K.height, K.width, CV_16UC1);
    for (int i = 0; i < K.width * K.height; ++i) {
      // OpenCV writes BGR.
      color.data[3 * i + 0] = frame.color.rgb[3 * i + 2];
      color.data[3 * i + 1] = frame.color.rgb[3 * i + 1];
      color.data[3 * i + 2] = frame.color.rgb[3 * i + 0];
      const double mm = std::round(frame.depth.depth_m[i] * 1000.0);
      depth.at<std::uint16_t>(i / K.width, i % K.width) =
          static_cast<std::uint16_t>(std::clamp(mm, 0.0, 65535.0));
      instance.at<std::uint16_t>(i / K.width, i % K.width) = frame.instance[i];
    }
    if (!WritePng(stem + ".color.png", color, why) || !WritePng(stem + ".depth.png", depth, why) ||
        !WritePng(stem + ".instance.png", instance, why) ||
        !WriteMatrix(stem + ".pose.txt", reported[f].matrix(), 4, why)) {
      return false;
    }
    detections[std::to_string(index)] =
        DetectFromInstances(scene, frame, T_W_C, options.detector, scene.seed, index);
    seen.Add(frame, T_W_C, K, options.seen_max_range_m);
    std::map<int, int> pixels;
    for (std::uint16_t id : frame.instance) {
      if (id != 0) ++pixels[id];
    }
    for (const auto& [id, count] : pixels) {
      if (count >= options.detector.min_visible_px) ++visible_frames[id];
    }
  }
  if (!seen.Write((fs::path(dir) / "seen_structure.ply").string(),
                  (fs::path(dir) / "seen_objects.ply").string(), why)) {
    return false;
  }
  if (!WriteDetectionsFile((fs::path(dir) / "detections.json").string(), detections, why)) {
    return false;
  }
  if (options.drift.enabled) {
    const std::string path = (fs::path(dir) / "corrected_poses.txt").string();
    std::ofstream corrected(path);
    corrected << "# frame_index tx ty tz qx qy qz qw: the true T_W_C of each frame\n";
    char line[256];
    for (std::size_t f = 0; f < scene.trajectory.size(); ++f) {
      const Eigen::Quaterniond q(scene.trajectory[f].linear());
      const Eigen::Vector3d t = scene.trajectory[f].translation();
      std::snprintf(line, sizeof(line), "%zu %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", f, t.x(), t.y(),
                    t.z(), q.x(), q.y(), q.z(), q.w());
      corrected << line;
    }
    if (!corrected) {
      *why = path + ": write failed";
      return false;
    }
  }
  const std::string gt_path = (fs::path(dir) / "ground_truth.json").string();
  std::ofstream gt(gt_path);
  gt << GroundTruthJson(scene, options.surface_points, options.seen_voxel_m, visible_frames)
     << "\n";
  if (!gt) {
    *why = gt_path + ": write failed";
    return false;
  }
  return true;
}

}  // namespace objmap::sim
