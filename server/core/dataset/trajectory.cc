#include "dataset/trajectory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace objmap {
namespace {

// Parses `stamp tx ty tz qx qy qz qw`; false with the reason when the line is not that.
bool ParsePoseLine(const std::string& line, TrajectoryPose* pose, std::string* why) {
  std::istringstream fields(line);
  double t[3], q[4];
  if (!(fields >> pose->stamp_s >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3])) {
    *why = "expected `stamp tx ty tz qx qy qz qw`";
    return false;
  }
  std::string extra;
  if (fields >> extra) {
    *why = "more than 8 numbers";
    return false;
  }
  const Eigen::Quaterniond q_W_C(q[3], q[0], q[1], q[2]);
  const double norm = q_W_C.norm();
  if (!std::isfinite(pose->stamp_s) || !std::isfinite(norm) ||
      !Eigen::Vector3d(t[0], t[1], t[2]).allFinite() || std::abs(norm - 1.0) > 0.01) {
    *why = "not a finite pose with a unit quaternion";
    return false;
  }
  pose->T_W_C = Eigen::Isometry3d::Identity();
  pose->T_W_C.linear() = q_W_C.normalized().toRotationMatrix();
  pose->T_W_C.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  return true;
}

class TrajectoryStream : public FrameStream {
 public:
  TrajectoryStream(std::unique_ptr<FrameStream> inner, std::vector<TrajectoryPose> poses,
                   const TrajectoryMatchConfig& config, const std::string& origin)
      : inner_(std::move(inner)), poses_(std::move(poses)), config_(config), origin_(origin) {}

  FrameStatus Next(RgbdFrame* frame, std::string* why) override {
    const FrameStatus status = inner_->Next(frame, why);
    if (status != FrameStatus::kFrame) return status;
    const TrajectoryPose* nearest = Nearest(frame->stamp_s);
    if (nearest == nullptr ||
        std::abs(nearest->stamp_s - frame->stamp_s) > config_.max_stamp_difference_s) {
      std::ostringstream reason;
      reason.precision(6);
      reason << std::fixed << frame->name << ": no pose in " << origin_ << " within "
             << config_.max_stamp_difference_s << " s of stamp " << frame->stamp_s;
      *why = reason.str();
      return FrameStatus::kBadFrame;
    }
    frame->T_W_C = nearest->T_W_C;
    return FrameStatus::kFrame;
  }

  std::size_t size() const override { return inner_->size(); }
  std::string Describe() const override { return inner_->Describe() + ", poses from " + origin_; }

 private:
  // The pose whose stamp is nearest `stamp_s` (poses_ is sorted and not empty).
  const TrajectoryPose* Nearest(double stamp_s) const {
    if (poses_.empty()) return nullptr;
    const auto after = std::lower_bound(
        poses_.begin(), poses_.end(), stamp_s,
        [](const TrajectoryPose& pose, double stamp) { return pose.stamp_s < stamp; });
    if (after == poses_.begin()) return &*after;
    if (after == poses_.end()) return &poses_.back();
    const auto before = std::prev(after);
    return stamp_s - before->stamp_s <= after->stamp_s - stamp_s ? &*before : &*after;
  }

  std::unique_ptr<FrameStream> inner_;
  const std::vector<TrajectoryPose> poses_;
  const TrajectoryMatchConfig config_;
  const std::string origin_;
};

}  // namespace

bool WriteTumTrajectory(const std::string& path, const std::vector<TrajectoryPose>& poses,
                        const std::string& comment, std::string* why) {
  std::ofstream out(path);
  out << "# " << comment << "\n";
  char line[256];
  for (const TrajectoryPose& pose : poses) {
    const Eigen::Quaterniond q(pose.T_W_C.linear());
    const Eigen::Vector3d t = pose.T_W_C.translation();
    std::snprintf(line, sizeof(line), "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", pose.stamp_s,
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    out << line;
  }
  if (!out) *why = "cannot write " + path;
  return static_cast<bool>(out);
}

bool ReadTumTrajectory(const std::string& path, std::vector<TrajectoryPose>* poses,
                       std::string* why) {
  std::ifstream in(path);
  if (!in) {
    *why = path + ": missing or unreadable";
    return false;
  }
  poses->clear();
  std::string line, reason;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    TrajectoryPose pose;
    if (!ParsePoseLine(line, &pose, &reason)) {
      *why = path + ":" + std::to_string(line_number) + ": " + reason;
      return false;
    }
    poses->push_back(pose);
  }
  if (poses->empty()) {
    *why = path + ": no poses";
    return false;
  }
  std::stable_sort(
      poses->begin(), poses->end(),
      [](const TrajectoryPose& a, const TrajectoryPose& b) { return a.stamp_s < b.stamp_s; });
  return true;
}

bool TrajectoryMatchConfig::IsValid(std::string* why) const {
  if (!(max_stamp_difference_s >= 0.0) || !std::isfinite(max_stamp_difference_s)) {
    *why = "max_stamp_difference_s must be finite and >= 0";
    return false;
  }
  return true;
}

std::unique_ptr<FrameStream> WithTrajectory(std::unique_ptr<FrameStream> inner,
                                            std::vector<TrajectoryPose> poses,
                                            const TrajectoryMatchConfig& config,
                                            const std::string& origin) {
  return std::make_unique<TrajectoryStream>(std::move(inner), std::move(poses), config, origin);
}

}  // namespace objmap
