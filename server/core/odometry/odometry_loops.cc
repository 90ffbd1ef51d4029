// RgbdOdometry's loop closure: for each new keyframe, the older keyframes near it and those that
// look like it are matched to it; each match is a loop edge, and the keyframes' pose graph is
// solved, on the tracking thread or on a worker of its own (background_loop_closure).
#include <exception>

#include "odometry/odometry_impl.h"

namespace objmap {

using namespace odometry_detail;

LoopJob RgbdOdometry::Impl::MakeLoopJob(std::shared_ptr<const FrameFeatures> features,
                                        const CameraIntrinsics& K) const {
  LoopJob job;
  job.newest = static_cast<int>(keyframes.size()) - 1;
  job.features = std::move(features);
  job.intrinsics = K;
  job.keyframes = keyframes;
  job.poses = poses;
  job.fragments = fragment_of;
  job.edges = edges;
  return job;
}

std::vector<int> RgbdOdometry::Impl::AppearanceCandidates(const LoopJob& job,
                                                          const std::vector<int>& already) {
  if (config.loop_appearance_candidates <= 0) return {};
  // Keyframes made since the last search join the index first.
  IndexKeyframes(job.keyframes, job.newest, &appearance_index, &indexed_keyframes);
  const cv::Mat& mine = job.keyframes[static_cast<std::size_t>(job.newest)]->strongest_descriptors;
  if (mine.rows < 2) return {};
  const int last_old = job.newest - config.loop_min_keyframe_gap;
  std::vector<int> shortlist;
  if (config.appearance_shortlist > 0 && mine.isContinuous()) {
    for (const auto& [votes, k] : appearance_index.MostAlike(
             mine.ptr<std::uint8_t>(), mine.rows, last_old, config.appearance_shortlist)) {
      shortlist.push_back(k);
    }
  } else {
    for (int k = 0; k <= last_old; ++k) shortlist.push_back(k);
  }
  // Keyframes of a provisional fragment have poses in another frame: no loop to them.
  auto eligible = [&](int k) {
    return job.fragments[static_cast<std::size_t>(k)] == 0 &&
           std::find(already.begin(), already.end(), k) == already.end();
  };
  return MostMatched(mine, shortlist, eligible, job.keyframes, config.match_ratio,
                     config.loop_min_inliers, config.loop_appearance_candidates);
}

LoopClosure RgbdOdometry::Impl::CloseLoops(const LoopJob& job) {
  const auto start = Clock::now();
  LoopClosure closure;
  closure.newest = job.newest;
  closure.job_edges = job.edges.size();
  closure.fragments = job.fragments;
  auto finish = [&]() -> LoopClosure {
    closure.ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return closure;
  };
  if (config.loop_candidates <= 0) return finish();
  const int newest = job.newest;
  const Eigen::Isometry3d& T_W_new = job.poses[static_cast<std::size_t>(newest)];
  auto in_map_frame = [&](int k) { return job.fragments[static_cast<std::size_t>(k)] == 0; };
  if (!in_map_frame(newest)) return finish();
  std::vector<std::pair<double, int>> near;
  for (int k = 0; k + config.loop_min_keyframe_gap <= newest; ++k) {
    if (!in_map_frame(k)) continue;
    const Eigen::Isometry3d offset = job.poses[static_cast<std::size_t>(k)].inverse() * T_W_new;
    if (offset.translation().norm() <= config.loop_search_radius_m &&
        AngleDeg(offset.linear()) <= config.loop_search_angle_deg) {
      near.emplace_back(offset.translation().norm(), k);
    }
  }
  std::sort(near.begin(), near.end());
  std::vector<int> candidates;
  for (std::size_t c = 0; c < near.size() && static_cast<int>(c) < config.loop_candidates; ++c) {
    candidates.push_back(near[c].second);
  }
  for (int k : AppearanceCandidates(job, candidates)) candidates.push_back(k);
  std::vector<PoseGraphEdge> edges = job.edges;
  std::vector<std::pair<int, PoseFit>> loops;
  for (const int k : candidates) {
    PoseFit fit = Fit(*job.features, *job.keyframes[static_cast<std::size_t>(k)], job.intrinsics);
    if (fit.ok && fit.inliers >= config.loop_min_inliers) loops.emplace_back(k, std::move(fit));
  }
  // Loops to the saved map's keyframes must agree on where the newest keyframe is (within the
  // relocalisation consensus limits), the tracked pose voting too: a repeated pattern fits
  // strongly at a wrong place, and a wrong loop to keyframes held fixed would pull the whole
  // session there (the graph's robust loss sorts out the session's own loops). The loops that
  // agree with the largest group are kept; without one group larger than the others, none.
  const bool to_map = std::any_of(loops.begin(), loops.end(),
                                  [&](const auto& loop) { return loop.first < map_keyframes; });
  std::vector<Eigen::Isometry3d> voters;  // the loops' poses of the newest keyframe, then its own
  for (const auto& [k, fit] : loops)
    voters.push_back(job.poses[static_cast<std::size_t>(k)] * fit.T_K_C);
  voters.push_back(T_W_new);
  auto agree = [&](const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
    return WithinConsensus(a.inverse() * b);
  };
  std::vector<int> support(voters.size(), 0);
  for (std::size_t v = 0; v < voters.size(); ++v) {
    for (const Eigen::Isometry3d& other : voters) support[v] += agree(voters[v], other);
  }
  const auto best =
      static_cast<std::size_t>(std::max_element(support.begin(), support.end()) - support.begin());
  const bool one_group = std::count(support.begin(), support.end(), support[best]) == support[best];
  int added = 0;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (to_map && !(one_group && agree(voters[best], voters[l]))) continue;
    PoseGraphEdge loop;
    loop.from = loops[l].first;
    loop.to = newest;
    loop.T_from_to = loops[l].second.T_K_C;
    loop.information = EdgeInformationOf(loops[l].second);
    loop.loop = true;
    edges.push_back(loop);
    ++added;
  }
  if (added == 0) return finish();
  // The graph of the keyframes in the map's frame: a provisional fragment's are tied to it by
  // no edge until it is attached.
  PoseGraph graph;
  for (int k = 0; k <= newest; ++k) {
    if (in_map_frame(k)) graph.AddNode(k, job.poses[static_cast<std::size_t>(k)]);
  }
  for (int k = 0; k < map_keyframes && k <= newest; ++k) graph.SetFixed(k);
  std::string why;
  std::vector<std::size_t> in_graph;  // graph edge -> index in `edges`
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].from > newest || edges[e].to > newest || !in_map_frame(edges[e].from) ||
        !in_map_frame(edges[e].to)) {
      continue;
    }
    if (!graph.AddEdge(edges[e], &why)) return finish();
    in_graph.push_back(e);
  }
  PoseGraphReport report;
  if (!graph.Optimize(&report, &why)) return finish();
  // Wrong loops stay out of later solves.
  std::vector<bool> dropped(edges.size(), false);
  for (int e : report.rejected_loops) dropped[in_graph[static_cast<std::size_t>(e)]] = true;
  int kept_loops = added;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (!dropped[e]) {
      closure.edges.push_back(edges[e]);
    } else if (edges[e].to == newest && e >= job.edges.size()) {
      --kept_loops;
    }
  }
  closure.loops = kept_loops;
  closure.poses.assign(job.poses.begin(), job.poses.begin() + newest + 1);
  for (const auto& [k, pose] : graph.poses()) closure.poses[static_cast<std::size_t>(k)] = pose;
  return finish();
}

int RgbdOdometry::Impl::Apply(LoopClosure closure) {
  if (closure.poses.empty()) return 0;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto newest = static_cast<std::size_t>(closure.newest);
  const Eigen::Isometry3d correction = closure.poses[newest] * poses[newest].inverse();
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (fragment_of[k] != 0) continue;  // a provisional fragment's frame is its own
    // Solved, or made or attached since the job: these follow the newest's correction.
    poses[k] = k <= newest && closure.fragments[k] == 0 ? closure.poses[k] : correction * poses[k];
  }
  // Edges added since the job (odometry edges of newer keyframes) follow the solved ones.
  closure.edges.insert(closure.edges.end(),
                       edges.begin() + static_cast<std::ptrdiff_t>(closure.job_edges), edges.end());
  edges = std::move(closure.edges);
  if (has_last && current_fragment == 0) last_T_W_C = correction * last_T_W_C;
  loops_closed += closure.loops;
  return closure.loops;
}

int RgbdOdometry::Impl::ApplyFinished(double* ms) {
  std::vector<LoopClosure> finished;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    finished.swap(results);
  }
  int loops = 0;
  for (LoopClosure& closure : finished) {
    *ms += closure.ms;
    loops += Apply(std::move(closure));
  }
  if (!finished.empty()) wake.notify_all();  // the worker waits for its result to be applied
  return loops;
}

void RgbdOdometry::Impl::WorkerLoop() {
  for (;;) {
    LoopJob job;
    {
      std::unique_lock<std::mutex> lock(mutex);
      wake.wait(lock, [&] { return stop || (!jobs.empty() && results.empty()); });
      if (stop) return;
      job = std::move(jobs.front());
      jobs.pop_front();
      // The job was queued before the loops applied since: it starts from the current state.
      job.poses.assign(poses.begin(), poses.begin() + job.newest + 1);
      job.fragments.assign(fragment_of.begin(), fragment_of.begin() + job.newest + 1);
      job.edges = edges;
      busy = true;
    }
    LoopClosure closure;
    try {
      closure = CloseLoops(job);
    } catch (const std::exception&) {
      // A search that fails (OpenCV or Ceres on a degenerate case, memory) closes no loop;
      // tracking goes on without it rather than the process ending on this thread.
      closure = LoopClosure{};
    }
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (!closure.poses.empty()) results.push_back(std::move(closure));
      busy = false;
    }
    settled.notify_all();
  }
}

void RgbdOdometry::Impl::StopWorker() {
  if (!worker.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    stop = true;
  }
  wake.notify_all();
  worker.join();
}

}  // namespace objmap
