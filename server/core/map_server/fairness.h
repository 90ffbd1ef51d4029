#pragma once
// How the server shares its CPU between writes and queries. Queries whose work grows with the
// map or the region asked (QueryOccupancy, GetOctomap) run on a few threads of their own at a
// lower priority, after the ones before them; the short planner queries (IsFree, RayCast,
// object queries) run at once on the request threads, at the writes' priority, since their
// latency is what a planner waits for. Without this, a crowd of clients asking for occupancy
// grids slows keyframe ingest roughly by their number.

#include <string>

namespace objmap {

struct FairnessConfig {
  /// Threads that answer heavy queries (QueryOccupancy, GetOctomap); more such queries wait.
  int heavy_query_threads = 1;
  /// Niceness those threads add to the server's (lower priority): under a flood of heavy
  /// queries the mapping and detector threads keep most of the CPU. 0: the same priority.
  int heavy_query_nice = 10;
  /// Heavy queries that may wait for a thread; one more is answered RESOURCE_EXHAUSTED at once.
  int max_waiting_heavy_queries = 64;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Lowers the calling thread's priority by `nice` (on Linux, niceness is per thread). A thread
/// cannot take it back: use it for threads made for lower-priority work. False with the reason
/// when the system refused.
bool LowerThisThreadPriority(int nice, std::string* why);

}  // namespace objmap
