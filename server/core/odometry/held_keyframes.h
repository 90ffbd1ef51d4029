#pragma once
// Keyframes tracked in a provisional fragment of a session (TrackingStatus::kProvisional), held
// until the fragment is placed in the map: each remembered as (its payload, the odometry
// keyframe it was tracked against, its pose relative to that one). Placing the fragment moves
// its odometry keyframes into the map's frame, and with them every keyframe held on them. The
// map server holds its mapping jobs so, the ROS node its frames.

#include <Eigen/Geometry>
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include "odometry/rgbd_odometry.h"
#include "odometry/tracked_keyframes.h"

namespace objmap {

template <typename Payload>
class HeldKeyframes {
 public:
  struct Held {
    Payload payload;
    int odometry_keyframe = -1;
    Eigen::Isometry3d T_K_C = Eigen::Isometry3d::Identity();

    /// Its pose as the odometry's keyframes now stand (in the map's frame once placed).
    [[nodiscard]] Eigen::Isometry3d T_W_C(const RgbdOdometry& odometry) const {
      return odometry.KeyframePose(odometry_keyframe) * T_K_C;
    }
  };

  /// Holds `payload` of the frame `tracked` reports (kProvisional) in its fragment. Beyond
  /// `limit` held in all, the oldest fragment's oldest keyframes go, returned: memory stays
  /// bounded on a session that never overlaps the map.
  std::vector<Held> Hold(Payload payload, const TrackingReport& tracked,
                         const RgbdOdometry& odometry, std::size_t limit) {
    Held held;
    held.payload = std::move(payload);
    held.odometry_keyframe = tracked.reference_keyframe;
    held.T_K_C = PoseOnReferenceKeyframe(tracked, odometry);
    by_fragment_[tracked.fragment].push_back(std::move(held));
    ++count_;
    std::vector<Held> dropped;
    while (count_ > limit && !by_fragment_.empty()) {
      auto oldest = by_fragment_.begin();
      dropped.push_back(std::move(oldest->second.front()));
      oldest->second.erase(oldest->second.begin());
      --count_;
      if (oldest->second.empty()) by_fragment_.erase(oldest);
    }
    return dropped;
  }

  /// The keyframes `fragment` holds, in order, no longer held.
  std::vector<Held> Take(int fragment) {
    const auto found = by_fragment_.find(fragment);
    if (found == by_fragment_.end()) return {};
    std::vector<Held> taken = std::move(found->second);
    by_fragment_.erase(found);
    count_ -= taken.size();
    return taken;
  }

  /// How many `fragment` holds.
  [[nodiscard]] std::size_t In(int fragment) const {
    const auto found = by_fragment_.find(fragment);
    return found == by_fragment_.end() ? 0 : found->second.size();
  }
  /// How many are held in all.
  [[nodiscard]] std::size_t size() const { return count_; }
  void Clear() {
    by_fragment_.clear();
    count_ = 0;
  }

 private:
  std::map<int, std::vector<Held>> by_fragment_;  // in order
  std::size_t count_ = 0;
};

}  // namespace objmap
