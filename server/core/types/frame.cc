#include "types/frame.h"

#include <cmath>
#include <sstream>

namespace objmap {
namespace {

void SetWhy(std::string* why, const std::string& text) {
  if (why != nullptr) *why = text;
}

}  // namespace

bool CameraIntrinsics::IsValid(std::string* why) const {
  if (width <= 0 || height <= 0) {
    SetWhy(why, "intrinsics: width and height must be positive");
    return false;
  }
  const auto focal_ok = [](double f) { return f >= kMinFocalPx && f <= kMaxFocalPx; };
  if (!focal_ok(fx) || !focal_ok(fy)) {
    std::ostringstream text;
    text << "intrinsics: fx " << fx << " and fy " << fy << " must lie in [" << kMinFocalPx << ", "
         << kMaxFocalPx << "] pixels";
    SetWhy(why, text.str());
    return false;
  }
  // NaN fails both comparisons.
  if (!(cx >= -width && cx <= 2.0 * width) || !(cy >= -height && cy <= 2.0 * height)) {
    std::ostringstream text;
    text << "intrinsics: the principal point (cx " << cx << ", cy " << cy
         << ") must lie within one image size of the " << width << "x" << height << " image";
    SetWhy(why, text.str());
    return false;
  }
  return true;
}

bool IsValidRigidTransform(const Eigen::Matrix4d& T, std::string* why) {
  if (!T.allFinite()) {
    SetWhy(why, "pose has NaN or infinite entries");
    return false;
  }
  constexpr double kTolerance = 1e-3;
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const double orthonormal_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  if (orthonormal_error > kTolerance || std::abs(R.determinant() - 1.0) > kTolerance) {
    std::ostringstream text;
    text << "pose is not rigid: |R^T R - I| = " << orthonormal_error
         << ", det(R) = " << R.determinant();
    SetWhy(why, text.str());
    return false;
  }
  if (T.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > kMaxTranslationM) {
    std::ostringstream text;
    text << "pose translation (" << T(0, 3) << ", " << T(1, 3) << ", " << T(2, 3)
         << ") lies more than " << kMaxTranslationM << " m from the map origin";
    SetWhy(why, text.str());
    return false;
  }
  if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > kTolerance) {
    SetWhy(why, "pose last row is not (0 0 0 1)");
    return false;
  }
  return true;
}

bool ValidateFrame(const RgbdFrame& frame, std::string* why) {
  std::string reason;
  if (!frame.intrinsics.IsValid(&reason)) {
    SetWhy(why, frame.name + ": " + reason);
    return false;
  }
  const CameraIntrinsics& K = frame.intrinsics;
  if (frame.depth.empty() || frame.depth.width != K.width || frame.depth.height != K.height ||
      frame.depth.depth_m.size() != static_cast<size_t>(K.width) * K.height) {
    std::ostringstream text;
    text << frame.name << ": depth image is " << frame.depth.width << "x" << frame.depth.height
         << " but the intrinsics say " << K.width << "x" << K.height;
    SetWhy(why, text.str());
    return false;
  }
  if (!frame.color.empty() &&
      frame.color.rgb.size() != static_cast<size_t>(frame.color.width) * frame.color.height * 3) {
    SetWhy(why, frame.name + ": colour buffer size does not match its width and height");
    return false;
  }
  if (!IsValidRigidTransform(frame.T_W_C.matrix(), &reason)) {
    SetWhy(why, frame.name + ": " + reason);
    return false;
  }
  return true;
}

}  // namespace objmap
