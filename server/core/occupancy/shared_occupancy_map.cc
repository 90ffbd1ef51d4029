#include "occupancy/shared_occupancy_map.h"

#include <malloc.h>

#include <thread>

namespace objmap {

SharedOccupancyMap::SharedOccupancyMap(const OccupancyConfig& config, bool second_copy)
    : second_copy_(second_copy), copies_{OccupancyMap(config), OccupancyMap(config)} {}

SharedOccupancyMap::~SharedOccupancyMap() = default;

void SharedOccupancyMap::Read(const std::function<void(const OccupancyMap&)>& read) const {
  if (!second_copy_) {
    std::shared_lock<std::shared_mutex> lock(readers_[0]);
    read(copies_[0]);
    return;
  }
  for (;;) {
    const int index = published_.load(std::memory_order_acquire);
    // The writer locks only the unpublished copy, so a failed try means `index` was replaced
    // since it was read. Reading it again after locking catches a publication in between: the
    // copy locked would still be consistent, but a query that starts after a publication must
    // see it.
    std::shared_lock<std::shared_mutex> lock(readers_[index], std::try_to_lock);
    if (lock.owns_lock() && published_.load(std::memory_order_acquire) == index) {
      read(copies_[index]);
      return;
    }
    std::this_thread::yield();
  }
}

const OccupancyMap& SharedOccupancyMap::latest() const {
  return copies_[published_.load(std::memory_order_relaxed)];
}

int SharedOccupancyMap::Unpublished() const {
  // Without a second copy the one copy is both, and readers wait for its lock.
  return second_copy_ ? 1 - published_.load(std::memory_order_relaxed) : 0;
}

std::unique_lock<std::shared_mutex> SharedOccupancyMap::LockUnpublished() {
  return std::unique_lock<std::shared_mutex>(readers_[Unpublished()]);
}

void SharedOccupancyMap::CatchUp() {
  if (unpublished_behind_ == Behind::kNothing) return;
  const OccupancyMap& latest_map = latest();
  OccupancyMap& stale = copies_[Unpublished()];
  std::unique_lock<std::shared_mutex> lock = LockUnpublished();
  if (unpublished_behind_ == Behind::kOneScan) {
    // The scan is still held by the latest copy's preparer: the next PrepareScan is this one's.
    stale.ApplyScanPreparedBy(latest_map);
  } else {
    Release(&stale);  // first, so that three maps never exist at once
    stale = latest_map.Clone();
  }
  unpublished_behind_ = Behind::kNothing;
}

void SharedOccupancyMap::Release(OccupancyMap* map) {
  map->Clear();
  // The OcTree's millions of small nodes go back to glibc's bins for their size, which hand
  // them out again one by one in no useful order; merging them into large free blocks first
  // lets the next tree be allocated in the order it is built.
  malloc_trim(0);
}

void SharedOccupancyMap::Publish(int index, Behind behind) {
  if (!second_copy_) return;
  published_.store(index, std::memory_order_release);
  unpublished_behind_ = behind;
}

void SharedOccupancyMap::Integrate(const DepthScanW& scan) {
  CatchUp();
  const int index = Unpublished();
  OccupancyMap& next = copies_[index];
  // Casting touches no OcTree, so it needs no lock (a reader from before the last publication
  // may still be on this copy's tree).
  next.PrepareScan(scan);
  {
    std::unique_lock<std::shared_mutex> lock = LockUnpublished();
    next.ApplyPreparedScan();
  }
  Publish(index, Behind::kOneScan);
}

const IntegrationStats& SharedOccupancyMap::last_stats() const {
  return latest().last_stats();
}

bool SharedOccupancyMap::Rewrite(const std::function<bool(OccupancyMap*)>& rewrite) {
  CatchUp();
  const int index = Unpublished();
  {
    std::unique_lock<std::shared_mutex> lock = LockUnpublished();
    if (!rewrite(&copies_[index])) return false;
  }
  Publish(index, Behind::kRewritten);
  return true;
}

bool SharedOccupancyMap::Rebuild(const std::function<bool(OccupancyMap*)>& build) {
  CatchUp();
  const int index = Unpublished();
  {
    std::unique_lock<std::shared_mutex> lock = LockUnpublished();
    Release(&copies_[index]);
    if (!build(&copies_[index])) {
      // Nothing published, but the copy no longer equals the published one.
      if (second_copy_) unpublished_behind_ = Behind::kRewritten;
      return false;
    }
  }
  Publish(index, Behind::kRewritten);
  return true;
}

}  // namespace objmap
