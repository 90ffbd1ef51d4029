// OccupancyMap's integration of whole keyframe sequences: rays cast on several threads, the
// OcTree updated in order; and the rebuild of chosen regions only.

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <thread>

#include "occupancy/occupancy_map.h"
#include "occupancy/occupancy_map_impl.h"

namespace objmap {
namespace {

using occupancy_internal::FreeSpaceGrid;
using occupancy_internal::ScanPreparer;
using occupancy_internal::VoxelKey;

// The space a keyframe's correction can change is kept in blocks of 16 voxels: coarse enough to
// be marked quickly from the image, fine enough to leave most of a room alone.
constexpr int kRegionBlockLog2 = 4;

}  // namespace

Eigen::AlignedBox3d ReachInCameraFrame(const DepthScanW& scan, double margin_m) {
  Eigen::AlignedBox3d box(Eigen::Vector3d::Zero());  // the camera centre
  for (const Eigen::Vector3f& p : scan.points_C) {
    if (p.allFinite() && p.z() > 0.f) box.extend(p.cast<double>());
  }
  return Eigen::AlignedBox3d(box.min() - Eigen::Vector3d::Constant(margin_m),
                             box.max() + Eigen::Vector3d::Constant(margin_m));
}

Eigen::AlignedBox3d ReachInWorld(const Eigen::AlignedBox3d& reach_C,
                                 const Eigen::Isometry3d& T_W_C) {
  Eigen::AlignedBox3d box_W;
  for (int k = 0; k < 8; ++k) {
    box_W.extend(T_W_C * reach_C.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
  }
  return box_W;
}

// Workers prepare scans w, w + threads, ... each into its own preparer and wait until this
// thread has applied it; this thread applies them in order.
void OccupancyMap::Impl::IntegrateInOrder(std::size_t count,
                                          const std::function<DepthScanW(std::size_t)>& scan_at,
                                          int threads, const FreeSpaceGrid* region) {
  const auto workers = static_cast<std::size_t>(std::max(1, threads));
  if (workers == 1 || count < 2) {
    for (std::size_t i = 0; i < count; ++i) {
      preparer.Prepare(scan_at(i), region);
      Apply(&preparer);
    }
    return;
  }
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::unique_ptr<ScanPreparer>> slots;
  // The threads go to scans, one each.
  for (std::size_t w = 0; w < workers; ++w) {
    slots.push_back(std::make_unique<ScanPreparer>(config, /*threads=*/1));
  }
  std::vector<std::size_t> ready_index(workers, kNone);  // scan waiting in each slot
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<std::thread> pool;
  for (std::size_t w = 0; w < workers; ++w) {
    pool.emplace_back([&, w] {
      for (std::size_t i = w; i < count; i += workers) {
        {
          std::unique_lock<std::mutex> lock(mutex);
          changed.wait(lock, [&] { return ready_index[w] == kNone; });
        }
        slots[w]->Prepare(scan_at(i), region);
        std::lock_guard<std::mutex> lock(mutex);
        ready_index[w] = i;
        changed.notify_all();
      }
    });
  }
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t w = i % workers;
    {
      std::unique_lock<std::mutex> lock(mutex);
      changed.wait(lock, [&] { return ready_index[w] == i; });
    }
    Apply(slots[w].get());
    std::lock_guard<std::mutex> lock(mutex);
    ready_index[w] = kNone;
    changed.notify_all();
  }
  for (std::thread& worker : pool) worker.join();
}

void OccupancyMap::IntegrateSequence(std::size_t count,
                                     const std::function<DepthScanW(std::size_t)>& scan_at,
                                     int threads) {
  impl_->IntegrateInOrder(count, scan_at, threads, nullptr);
}

std::size_t OccupancyMap::RegenerateWhereReached(
    const std::vector<DepthScanW>& changed, std::size_t count,
    const std::function<DepthScanW(std::size_t)>& scan_at, int threads) {
  const double resolution_m = impl_->config.resolution_m;
  Eigen::AlignedBox3d bounds_W;
  for (const DepthScanW& scan : changed) {
    bounds_W.extend(
        ReachInWorld(ReachInCameraFrame(scan, 2.0 * resolution_m), scan.T_W_C.cast<double>()));
  }
  VoxelKey lo{}, hi{};
  // (An empty box has min > max: no keys.)
  if (!occupancy_internal::KeysOfBox(bounds_W.min(), bounds_W.max(), resolution_m, &lo, &hi)) {
    return 0;
  }
  FreeSpaceGrid region(resolution_m);
  region.Reset(lo, hi);
  ScanPreparer marker(impl_->config);
  for (const DepthScanW& scan : changed) marker.MarkReach(scan, kRegionBlockLog2, &region);
  region.BuildPyramid();
  impl_->tree.ClearRegion(region);
  impl_->IntegrateInOrder(count, scan_at, threads, &region);
  return region.CountSet();
}

OccupancyMap OccupancyMap::Clone() const {
  OccupancyMap copy(impl_->config);
  // OcTree's copy constructor copies every node; the sensor model is the configuration's.
  occupancy_internal::BatchOcTree nodes(impl_->tree);
  copy.impl_->tree.swapContent(nodes);
  return copy;
}

}  // namespace objmap
