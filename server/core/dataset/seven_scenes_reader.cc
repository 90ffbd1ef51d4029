#include "dataset/seven_scenes_reader.h"

#include <algorithm>
#include <filesystem>
#include <vector>

#include "dataset/image_io.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

constexpr char kDepthSuffix[] = ".depth.png";

class SevenScenesReader : public SequenceReader {
 public:
  SevenScenesReader(std::string folder, std::vector<std::string> stems, CameraIntrinsics K)
      : folder_(std::move(folder)), stems_(std::move(stems)), intrinsics_(K) {}

  std::size_t size() const override { return stems_.size(); }

  std::string Describe() const override {
    return "7-Scenes folder " + folder_ + ", " + std::to_string(stems_.size()) + " frames";
  }

  bool ReadFrame(std::size_t index, RgbdFrame* frame, std::string* why) const override {
    if (index >= stems_.size()) {
      *why = "frame index " + std::to_string(index) + " out of range";
      return false;
    }
    const std::string stem = folder_ + "/" + stems_[index];
    frame->frame_index = static_cast<std::int64_t>(index);
    frame->name = stems_[index];
    frame->stamp_s = 0.0;
    frame->intrinsics = intrinsics_;
    if (!ReadDepthImage(stem + kDepthSuffix, 1000.0, &frame->depth, why)) return false;
    const std::string color_path =
        fs::exists(stem + ".color.jpg") ? stem + ".color.jpg" : stem + ".color.png";
    if (!ReadColorImage(color_path, &frame->color, why)) return false;
    Eigen::Matrix<double, 4, 4, Eigen::RowMajor> pose;
    if (!ReadMatrixText(stem + ".pose.txt", 4, 4, pose.data(), why)) return false;
    std::string reason;
    if (!IsValidRigidTransform(pose, &reason)) {
      *why = stem + ".pose.txt: " + reason;
      return false;
    }
    frame->T_W_C.matrix() = pose;
    if (!ValidateFrame(*frame, why)) return false;
    return true;
  }

 private:
  std::string folder_;
  std::vector<std::string> stems_;  // "frame-000123"
  CameraIntrinsics intrinsics_;
};

// Image size is not in camera-intrinsics.txt: it comes from the first depth image, and every
// later depth image must match it.
bool ReadIntrinsics(const std::string& folder, const std::string& first_stem, CameraIntrinsics* K,
                    std::string* why) {
  const std::string path = folder + "/camera-intrinsics.txt";
  if (fs::exists(path)) {
    double k[9];
    if (!ReadMatrixText(path, 3, 3, k, why)) return false;
    K->fx = k[0];
    K->cx = k[2];
    K->fy = k[4];
    K->cy = k[5];
  }
  DepthImage first;
  if (!ReadDepthImage(folder + "/" + first_stem + kDepthSuffix, 1000.0, &first, why)) return false;
  K->width = first.width;
  K->height = first.height;
  if (!K->IsValid(why)) {
    *why = path + ": " + *why;
    return false;
  }
  return true;
}

}  // namespace

std::unique_ptr<SequenceReader> OpenSevenScenes(const std::string& folder, std::string* why) {
  std::vector<std::string> stems;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    const size_t suffix_length = sizeof(kDepthSuffix) - 1;
    if (name.rfind("frame-", 0) == 0 && name.size() > suffix_length &&
        name.compare(name.size() - suffix_length, suffix_length, kDepthSuffix) == 0) {
      stems.push_back(name.substr(0, name.size() - suffix_length));
    }
  }
  if (error) {
    *why = folder + ": " + error.message();
    return nullptr;
  }
  if (stems.empty()) {
    *why = folder + ": no frame-NNNNNN.depth.png files (empty sequence)";
    return nullptr;
  }
  std::sort(stems.begin(), stems.end());
  CameraIntrinsics K;
  if (!ReadIntrinsics(folder, stems.front(), &K, why)) return nullptr;
  return std::make_unique<SevenScenesReader>(folder, std::move(stems), K);
}

}  // namespace objmap
