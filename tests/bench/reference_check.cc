// How far a sequence's own poses (its "ground truth") agree with its images where the camera
// comes back to a place. Real-data references are reconstructions too: 7-Scenes' come from
// KinectFusion, which has no loop closure, so its poses can drift between visits. A trajectory
// scored against them inherits that error, and a trajectory that closes loops correctly is
// charged for it.
//
// Revisits are the frame pairs at least `min_gap` frames apart that the reference itself puts
// within 0.4 m and 25 degrees of each other (for each frame, its nearest such partner; frames
// every `stride`). For each pair, the depth of the later frame is aligned to the earlier one
// starting from the reference's relative pose (AlignDepth, as the odometry does), and the two
// relative poses are compared by two independent witnesses:
//   depth:   cells of the later frame that lie within 1 cm of the earlier frame's surface;
//   colour:  ORB matches (ratio test) whose two keypoints' 3D points (from the depth) come
//            within 2 cm of each other.
// A pair where the depth moves the pose by more than 3 cm and both witnesses prefer the moved
// pose is one where the reference disagrees with its own images by that much.
// With an estimated trajectory (TUM, one pose per frame in order, as odometry_bench writes), its
// relative poses are scored on the same revisits by the depth witness, next to the reference's:
// which of the two explains the images better where the camera came back.
//   reference_check [sequence=../shared/data/redkitchen] [min_gap=150] [stride=5]
//                   [estimated.txt]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"
#include "odometry/depth_alignment.h"

namespace {

using objmap::DepthAlignmentReport;
using objmap::DepthGrid;
using objmap::RgbdFrame;

constexpr double kMaxPairDistanceM = 0.4;
constexpr double kMaxPairAngleDeg = 25.0;
constexpr double kSurfaceToleranceM = 0.01;
constexpr double kFeatureToleranceM = 0.02;
constexpr double kMovedM = 0.03;

double AngleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

struct FrameData {
  Eigen::Isometry3d T_W_C;
  objmap::CameraIntrinsics intrinsics;
  DepthGrid coarse, fine;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<Eigen::Vector3d> points;  // per keypoint, camera frame; NaN without depth
};

FrameData Prepare(const RgbdFrame& frame, cv::ORB& orb) {
  FrameData data;
  data.T_W_C = frame.T_W_C;
  data.intrinsics = frame.intrinsics;
  data.coarse = objmap::MakeDepthGrid(frame.depth, frame.intrinsics, 8, 4.0);
  data.fine = objmap::MakeDepthGrid(frame.depth, frame.intrinsics, 4, 4.0);
  const cv::Mat rgb(frame.color.height, frame.color.width, CV_8UC3,
                    const_cast<std::uint8_t*>(frame.color.rgb.data()));
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  orb.detectAndCompute(grey, cv::noArray(), data.keypoints, data.descriptors);
  const objmap::CameraIntrinsics& K = frame.intrinsics;
  for (const cv::KeyPoint& keypoint : data.keypoints) {
    const int u = static_cast<int>(std::lround(keypoint.pt.x));
    const int v = static_cast<int>(std::lround(keypoint.pt.y));
    double z = 0.0;
    if (u >= 0 && v >= 0 && u < K.width && v < K.height) {
      z = frame.depth.depth_m[static_cast<std::size_t>(v) * K.width + u];
    }
    data.points.push_back(z > 0.2 && z < 4.0
                              ? Eigen::Vector3d((keypoint.pt.x - K.cx) * z / K.fx,
                                                (keypoint.pt.y - K.cy) * z / K.fy, z)
                              : Eigen::Vector3d::Constant(std::nan("")));
  }
  return data;
}

// Cells of `later` within the tolerance of `earlier`'s surface under T_earlier_later.
int DepthWitness(const FrameData& earlier, const FrameData& later,
                 const Eigen::Isometry3d& T_earlier_later) {
  Eigen::Isometry3d T = T_earlier_later;
  DepthAlignmentReport report;
  // One iteration counts the correspondences at the given pose (before its update).
  (void)objmap::AlignDepth({&earlier.fine}, {&later.fine},
                           {{1, kSurfaceToleranceM, kSurfaceToleranceM}}, 1, &T, &report);
  return report.correspondences;
}

// Matches whose two 3D points (each keypoint's depth) coincide within the tolerance under
// T_earlier_later. 3D against 3D rather than reprojection: where colour is not registered to
// depth (7-Scenes: 10-20 px), a keypoint's depth is read beside it, alike in both frames.
int ColourWitness(const std::vector<cv::DMatch>& matches, const FrameData& earlier,
                  const FrameData& later, const Eigen::Isometry3d& T_earlier_later) {
  int agreeing = 0;
  for (const cv::DMatch& match : matches) {
    const Eigen::Vector3d& p = earlier.points[static_cast<std::size_t>(match.trainIdx)];
    const Eigen::Vector3d& q = later.points[static_cast<std::size_t>(match.queryIdx)];
    if (!p.allFinite() || !q.allFinite()) continue;
    agreeing += (T_earlier_later * q - p).norm() <= kFeatureToleranceM;
  }
  return agreeing;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const int min_gap = argc > 2 ? std::atoi(argv[2]) : 150;
  const int stride = argc > 3 ? std::max(1, std::atoi(argv[3])) : 5;
  std::string why;
  std::unique_ptr<objmap::SequenceReader> reader = objmap::OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "reference_check: %s\n", why.c_str());
    return 1;
  }
  std::vector<objmap::TrajectoryPose> estimated;
  if (argc > 4 && !objmap::ReadTumTrajectory(argv[4], &estimated, &why)) {
    std::fprintf(stderr, "reference_check: %s\n", why.c_str());
    return 1;
  }
  if (!estimated.empty() && estimated.size() != reader->size()) {
    std::fprintf(stderr, "reference_check: %zu estimated poses for %zu frames\n", estimated.size(),
                 reader->size());
    return 1;
  }
  std::vector<int> indices;
  std::vector<Eigen::Isometry3d> reference;
  for (std::size_t i = 0; i < reader->size(); i += static_cast<std::size_t>(stride)) {
    RgbdFrame frame;
    if (!reader->ReadFrame(i, &frame, &why)) {
      std::fprintf(stderr, "reference_check: %s\n", why.c_str());
      return 1;
    }
    indices.push_back(static_cast<int>(i));
    reference.push_back(frame.T_W_C);
  }
  // Each frame's nearest revisit by the reference's own poses.
  std::vector<std::pair<int, int>> pairs;  // positions in `indices`
  for (std::size_t b = 0; b < indices.size(); ++b) {
    int best = -1;
    double best_distance = kMaxPairDistanceM;
    for (std::size_t a = 0; a < b; ++a) {
      if (indices[b] - indices[a] < min_gap) break;
      const Eigen::Isometry3d offset = reference[a].inverse() * reference[b];
      const double distance = offset.translation().norm();
      if (distance <= best_distance && AngleDeg(offset.linear()) <= kMaxPairAngleDeg) {
        best_distance = distance;
        best = static_cast<int>(a);
      }
    }
    if (best >= 0) pairs.emplace_back(best, static_cast<int>(b));
  }
  std::printf("reference_check: %s, %zu revisits (frames >= %d apart, <= %.1f m and %.0f deg "
              "by the reference)\n",
              reader->Describe().c_str(), pairs.size(), min_gap, kMaxPairDistanceM,
              kMaxPairAngleDeg);
  std::printf("%6s %6s %8s %8s %12s %12s %12s %12s %12s\n", "frame", "frame", "moved_cm", "deg",
              "depth@ref", "depth@moved", "colour@ref", "colour@moved", "depth@est");
  cv::Ptr<cv::ORB> orb = cv::ORB::create(1000);
  const cv::BFMatcher matcher(cv::NORM_HAMMING);
  std::vector<double> moved_cm;
  int disagreeing = 0, aligned = 0;
  long total_ref = 0, total_moved = 0, total_estimated = 0;
  int estimated_better = 0;
  for (const auto& [a, b] : pairs) {
    RgbdFrame earlier_frame, later_frame;
    if (!reader->ReadFrame(static_cast<std::size_t>(indices[a]), &earlier_frame, &why) ||
        !reader->ReadFrame(static_cast<std::size_t>(indices[b]), &later_frame, &why)) {
      std::fprintf(stderr, "reference_check: %s\n", why.c_str());
      return 1;
    }
    const FrameData earlier = Prepare(earlier_frame, *orb);
    const FrameData later = Prepare(later_frame, *orb);
    const Eigen::Isometry3d T_ref = earlier.T_W_C.inverse() * later.T_W_C;
    Eigen::Isometry3d T_depth = T_ref;
    DepthAlignmentReport report;
    if (!objmap::AlignDepth({&earlier.coarse, &earlier.fine}, {&later.coarse, &later.fine},
                            {{10, 0.08, 0.03}, {20, 0.03, 0.01}}, 100, &T_depth, &report)) {
      continue;
    }
    ++aligned;
    std::vector<std::vector<cv::DMatch>> knn;
    std::vector<cv::DMatch> matches;
    if (!earlier.descriptors.empty() && !later.descriptors.empty()) {
      matcher.knnMatch(later.descriptors, earlier.descriptors, knn, 2);
    }
    for (const auto& pair : knn) {
      if (pair.size() == 2 && pair[0].distance < 0.8f * pair[1].distance) matches.push_back(pair[0]);
    }
    const Eigen::Isometry3d moved = T_ref.inverse() * T_depth;
    const double cm = 100.0 * moved.translation().norm();
    moved_cm.push_back(cm);
    const int depth_ref = DepthWitness(earlier, later, T_ref);
    const int depth_moved = DepthWitness(earlier, later, T_depth);
    const int colour_ref = ColourWitness(matches, earlier, later, T_ref);
    const int colour_moved = ColourWitness(matches, earlier, later, T_depth);
    const bool disagrees = cm > 100.0 * kMovedM && depth_moved > depth_ref && colour_moved > colour_ref;
    disagreeing += disagrees;
    int depth_estimated = -1;
    if (!estimated.empty()) {
      depth_estimated = DepthWitness(
          earlier, later,
          estimated[static_cast<std::size_t>(indices[a])].T_W_C.inverse() *
              estimated[static_cast<std::size_t>(indices[b])].T_W_C);
      total_estimated += depth_estimated;
      estimated_better += depth_estimated > depth_ref;
    }
    total_ref += depth_ref;
    total_moved += depth_moved;
    std::printf("%6d %6d %8.2f %8.2f %12d %12d %12d %12d %12d%s\n", indices[a], indices[b], cm,
                AngleDeg(moved.linear()), depth_ref, depth_moved, colour_ref, colour_moved,
                depth_estimated, disagrees ? "  reference off" : "");
  }
  if (moved_cm.empty()) {
    std::printf("no revisit could be aligned\n");
    return 0;
  }
  std::sort(moved_cm.begin(), moved_cm.end());
  std::printf("%d of %d aligned revisits: the reference is off by more than %.0f cm, both the "
              "depth and the colour agreeing; depth moved the reference's pose by median %.2f cm, "
              "90th percentile %.2f, max %.2f\n",
              disagreeing, aligned, 100.0 * kMovedM, moved_cm[moved_cm.size() / 2],
              moved_cm[std::min(moved_cm.size() - 1, moved_cm.size() * 9 / 10)], moved_cm.back());
  std::printf("depth cells within %.0f cm, summed over the revisits: reference %ld, each pair "
              "aligned on its own %ld",
              100.0 * kSurfaceToleranceM, total_ref, total_moved);
  if (!estimated.empty()) {
    std::printf(", estimated trajectory %ld (more than the reference's on %d of %d revisits)",
                total_estimated, estimated_better, aligned);
  }
  std::printf("\n");
  return 0;
}
