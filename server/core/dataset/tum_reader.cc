#include "dataset/tum_reader.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "dataset/image_io.h"

namespace objmap {
namespace {

struct StampedFile {
  double stamp_s = 0.0;
  std::string path;
};

struct StampedPose {
  double stamp_s = 0.0;
  Eigen::Vector3d t_W = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_W_C = Eigen::Quaterniond::Identity();
};

struct TumFrame {
  double stamp_s = 0.0;
  std::string color_path;
  std::string depth_path;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
};

// Reads "stamp value..." lines, skipping '#' comments; `parse` consumes the rest of the line.
template <typename Parse>
bool ReadStampedLines(const std::string& path, Parse parse, std::string* why) {
  std::ifstream in(path);
  if (!in) {
    *why = path + ": missing or unreadable";
    return false;
  }
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    if (!parse(fields)) {
      *why = path + ":" + std::to_string(line_number) + ": malformed line";
      return false;
    }
  }
  return true;
}

bool ReadFileList(const std::string& folder, const std::string& name,
                  std::vector<StampedFile>* files, std::string* why) {
  return ReadStampedLines(
      folder + "/" + name,
      [&](std::istringstream& fields) {
        StampedFile file;
        if (!(fields >> file.stamp_s >> file.path)) return false;
        file.path = folder + "/" + file.path;
        files->push_back(file);
        return true;
      },
      why);
}

bool ReadGroundTruth(const std::string& path, std::vector<StampedPose>* poses, std::string* why) {
  return ReadStampedLines(
      path,
      [&](std::istringstream& fields) {
        StampedPose pose;
        double qx, qy, qz, qw;
        if (!(fields >> pose.stamp_s >> pose.t_W.x() >> pose.t_W.y() >> pose.t_W.z() >> qx >> qy >>
              qz >> qw)) {
          return false;
        }
        pose.q_W_C = Eigen::Quaterniond(qw, qx, qy, qz).normalized();
        poses->push_back(pose);
        return true;
      },
      why);
}

// Index of the entry of `sorted` whose stamp is nearest to `stamp_s`.
template <typename T>
size_t Nearest(const std::vector<T>& sorted, double stamp_s) {
  auto it = std::lower_bound(sorted.begin(), sorted.end(), stamp_s,
                             [](const T& a, double s) { return a.stamp_s < s; });
  if (it == sorted.end()) return sorted.size() - 1;
  if (it != sorted.begin() && stamp_s - std::prev(it)->stamp_s < it->stamp_s - stamp_s) --it;
  return static_cast<size_t>(it - sorted.begin());
}

bool InterpolatePose(const std::vector<StampedPose>& poses, double stamp_s, double max_gap_s,
                     Eigen::Isometry3d* T_W_C) {
  auto after = std::lower_bound(poses.begin(), poses.end(), stamp_s,
                                [](const StampedPose& a, double s) { return a.stamp_s < s; });
  if (after == poses.end() || after == poses.begin()) return false;
  const auto before = std::prev(after);
  const double gap = after->stamp_s - before->stamp_s;
  if (gap > max_gap_s) return false;
  const double a = gap > 0 ? (stamp_s - before->stamp_s) / gap : 0.0;
  T_W_C->setIdentity();
  T_W_C->linear() = before->q_W_C.slerp(a, after->q_W_C).toRotationMatrix();
  T_W_C->translation() = (1 - a) * before->t_W + a * after->t_W;
  return true;
}

class TumReader : public SequenceReader {
 public:
  TumReader(std::string folder, std::vector<TumFrame> frames, CameraIntrinsics K,
            double depth_units)
      : folder_(std::move(folder)),
        frames_(std::move(frames)),
        intrinsics_(K),
        depth_units_(depth_units) {}

  std::size_t size() const override { return frames_.size(); }
  std::string Describe() const override {
    return "TUM RGB-D folder " + folder_ + ", " + std::to_string(frames_.size()) + " frames";
  }

  bool ReadFrame(std::size_t index, RgbdFrame* frame, std::string* why) const override {
    if (index >= frames_.size()) {
      *why = "frame index " + std::to_string(index) + " out of range";
      return false;
    }
    const TumFrame& source = frames_[index];
    frame->frame_index = static_cast<std::int64_t>(index);
    frame->stamp_s = source.stamp_s;
    frame->name = std::filesystem::path(source.depth_path).filename().string();
    frame->intrinsics = intrinsics_;
    frame->T_W_C = source.T_W_C;
    if (!ReadDepthImage(source.depth_path, depth_units_, &frame->depth, why)) return false;
    if (!ReadColorImage(source.color_path, &frame->color, why)) return false;
    return ValidateFrame(*frame, why);
  }

 private:
  std::string folder_;
  std::vector<TumFrame> frames_;
  CameraIntrinsics intrinsics_;
  double depth_units_;
};

std::vector<TumFrame> Associate(const std::vector<StampedFile>& colors,
                                const std::vector<StampedFile>& depths,
                                const std::vector<StampedPose>& poses,
                                const TumReaderConfig& config) {
  std::vector<TumFrame> frames;
  for (const StampedFile& depth : depths) {
    const StampedFile& color = colors[Nearest(colors, depth.stamp_s)];
    if (std::abs(color.stamp_s - depth.stamp_s) > config.max_color_depth_dt_s) continue;
    TumFrame frame;
    frame.stamp_s = depth.stamp_s;
    frame.depth_path = depth.path;
    frame.color_path = color.path;
    if (!InterpolatePose(poses, depth.stamp_s, config.max_pose_gap_s, &frame.T_W_C)) continue;
    frames.push_back(frame);
  }
  return frames;
}

}  // namespace

bool TumReaderConfig::IsValid(std::string* why) const {
  if (!(max_color_depth_dt_s > 0) || !(max_pose_gap_s > 0) || !(depth_units_per_metre > 0)) {
    *why =
        "TumReaderConfig: max_color_depth_dt_s, max_pose_gap_s and depth_units_per_metre "
        "must be positive";
    return false;
  }
  return true;
}

std::unique_ptr<SequenceReader> OpenTum(const std::string& folder, const TumReaderConfig& config,
                                        std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  std::vector<StampedFile> colors, depths;
  std::vector<StampedPose> poses;
  if (!ReadFileList(folder, "rgb.txt", &colors, why) ||
      !ReadFileList(folder, "depth.txt", &depths, why) ||
      !ReadGroundTruth(folder + "/groundtruth.txt", &poses, why)) {
    return nullptr;
  }
  auto by_stamp = [](const auto& a, const auto& b) { return a.stamp_s < b.stamp_s; };
  std::sort(colors.begin(), colors.end(), by_stamp);
  std::sort(poses.begin(), poses.end(), by_stamp);
  std::vector<TumFrame> frames = colors.empty() || poses.empty()
                                     ? std::vector<TumFrame>{}
                                     : Associate(colors, depths, poses, config);
  if (frames.empty()) {
    *why = folder + ": no depth image has a colour image and a ground-truth pose (empty sequence)";
    return nullptr;
  }
  CameraIntrinsics K;
  K.fx = K.fy = 525.0;
  K.cx = 319.5;
  K.cy = 239.5;
  const std::string intrinsics_path = folder + "/camera-intrinsics.txt";
  if (std::filesystem::exists(intrinsics_path)) {
    double k[9];
    if (!ReadMatrixText(intrinsics_path, 3, 3, k, why)) return nullptr;
    K.fx = k[0];
    K.cx = k[2];
    K.fy = k[4];
    K.cy = k[5];
  }
  DepthImage first;
  if (!ReadDepthImage(frames.front().depth_path, config.depth_units_per_metre, &first, why)) {
    return nullptr;
  }
  K.width = first.width;
  K.height = first.height;
  return std::make_unique<TumReader>(folder, std::move(frames), K, config.depth_units_per_metre);
}

}  // namespace objmap
