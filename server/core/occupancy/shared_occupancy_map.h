#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <mutex>
#include <shared_mutex>

#include "occupancy/occupancy_map.h"

namespace objmap {

/// An OccupancyMap shared by one writer and any number of readers. With a second copy (the
/// default), a reader never waits for the writer: readers read the published copy while the writer
/// updates the other one and then publishes it. The copy it replaced is brought up to date at
/// the start of the next write, once the readers that were on it have finished, so the writer
/// only ever waits for queries that started before its previous publication (and a long query
/// delays only the write after it, never another query). A scan's rays are cast once and its
/// voxel updates written into both copies; a rewrite (rebuild, restore) is made in one copy and
/// cloned into the other.
///
/// The price: a second copy of the OcTree in memory, and a second OcTree update per scan (not
/// the ray casting, which is most of a scan's time). Without the second copy (a map nobody
/// queries while it is written), readers share a lock with the OcTree writes instead.
///
/// Thread-safety: Read() from any thread at any time; everything else from one writer thread.
class SharedOccupancyMap {
 public:
  explicit SharedOccupancyMap(const OccupancyConfig& config, bool second_copy = true);
  ~SharedOccupancyMap();
  SharedOccupancyMap(const SharedOccupancyMap&) = delete;
  SharedOccupancyMap& operator=(const SharedOccupancyMap&) = delete;

  /// Runs `read` on the published copy, which does not change while `read` runs.
  void Read(const std::function<void(const OccupancyMap&)>& read) const;

  /// The published copy, the latest map; for the writer's thread, where it needs no lock
  /// because only the writer changes the copies, and never the published one.
  [[nodiscard]] const OccupancyMap& latest() const;

  /// OccupancyMap::Integrate into the map, without blocking readers. last_stats(): this scan's.
  void Integrate(const DepthScanW& scan);
  [[nodiscard]] const IntegrationStats& last_stats() const;

  /// Runs `rewrite` on a copy equal to the latest map that no reader sees. When it returns
  /// true, that copy is published (and cloned into the other one later); when it returns false
  /// it must have left the copy unchanged, and nothing is published.
  bool Rewrite(const std::function<bool(OccupancyMap*)>& rewrite);

  /// Runs `build` on an empty copy that no reader sees and publishes it when `build` returns
  /// true (cloned into the other copy later); false publishes nothing (without a second copy,
  /// the one copy is then left empty: rebuild it). The copy is emptied and
  /// its memory given back to the allocator first, so a rebuild needs no third copy and its
  /// nodes are not scattered over the old ones' freed places (which makes queries and updates
  /// on the rebuilt tree about twice as slow).
  bool Rebuild(const std::function<bool(OccupancyMap*)>& build);

  /// Brings the unpublished copy up to date now (waiting for its last readers), instead of at
  /// the start of the next write; for benchmarks and tests that compare the copies.
  void CatchUp();

 private:
  enum class Behind { kNothing, kOneScan, kRewritten };

  [[nodiscard]] int Unpublished() const;
  // The unpublished copy, once the readers still on it (from before the last publication)
  // are done.
  [[nodiscard]] std::unique_lock<std::shared_mutex> LockUnpublished();
  void Publish(int index, Behind behind);
  // Empties `map` and returns its nodes' memory to the allocator in one piece.
  static void Release(OccupancyMap* map);

  bool second_copy_;
  std::array<OccupancyMap, 2> copies_;  // [1] stays empty without a second copy
  mutable std::array<std::shared_mutex, 2> readers_;
  std::atomic<int> published_{0};
  Behind unpublished_behind_ = Behind::kNothing;  // what the unpublished copy lacks
};

}  // namespace objmap
