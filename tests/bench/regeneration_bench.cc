// Regeneration of the 1 cm OctoMap after a pose-graph update, on redkitchen with every frame a
// keyframe: the full rebuild (Mapper::Restore, as at a restart or after a correction moving most
// keyframes) with the rays of `threads` keyframes cast at once, and incremental rebuilds after
// corrections that move a few keyframes. Baselines in the same run: stock
// OcTree::insertPointCloud and objmap's ray-by-ray integration on the first keyframes (their
// per-keyframe time times the keyframes gives their rebuild), and the full rebuild on one
// thread over the first keyframes.
//   regeneration_bench [sequence=../shared/data/redkitchen] [keyframes=1000] [threads=2]
//                      [baseline_keyframes=3]
#include <octomap/OcTree.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "mapper/mapper.h"
#include "occupancy/occupancy_map.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::KeyframeId;
using objmap::KeyframeRecord;

double PeakResidentMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

struct Args {
  std::string data_dir = "../shared/data/redkitchen";
  int keyframes = 1000;
  int threads = 2;
  int baseline_keyframes = 3;
};

// Every frame as a keyframe record (depth in millimetres, no objects), as the store keeps them.
bool ReadKeyframes(const objmap::SequenceReader& reader, int count,
                   std::map<KeyframeId, KeyframeRecord>* records) {
  for (int i = 0; i < count && static_cast<std::size_t>(i) < reader.size(); ++i) {
    objmap::RgbdFrame frame;
    std::string why;
    if (!reader.ReadFrame(static_cast<std::size_t>(i), &frame, &why)) {
      std::fprintf(stderr, "regeneration_bench: %s\n", why.c_str());
      return false;
    }
    KeyframeRecord record = objmap::RecordOf(frame);
    records->emplace(static_cast<KeyframeId>(i + 1), std::move(record));
  }
  return !records->empty();
}

// Per-keyframe time of stock insertPointCloud and of objmap's ray-by-ray and projective
// integration on the first keyframes (one thread, one map each).
void Baselines(const std::map<KeyframeId, KeyframeRecord>& records, int count,
               const objmap::OccupancyConfig& config, double* stock_ms, double* ray_by_ray_ms,
               double* projective_ms) {
  octomap::OcTree stock(config.resolution_m);
  objmap::OccupancyConfig one_thread = config;
  one_thread.threads_per_scan = 1;
  objmap::OccupancyMap ray_by_ray(one_thread), projective(one_thread);
  *stock_ms = *ray_by_ray_ms = *projective_ms = 0.0;
  int done = 0;
  for (const auto& [id, record] : records) {
    if (done == count) break;
    const objmap::DepthScanW scan = objmap::DepthScanOf(record);
    const objmap::ScanW points = objmap::ToScanW(scan);
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : points.structure_points_W) cloud.push_back(p.x(), p.y(), p.z());
    Clock::time_point start = Clock::now();
    stock.insertPointCloud(
        cloud, octomap::point3d(points.origin_W.x(), points.origin_W.y(), points.origin_W.z()),
        config.max_range_m);
    *stock_ms += Ms(start);
    start = Clock::now();
    ray_by_ray.Integrate(points);
    *ray_by_ray_ms += Ms(start);
    start = Clock::now();
    projective.Integrate(scan);
    *projective_ms += Ms(start);
    ++done;
  }
  *stock_ms /= done;
  *ray_by_ray_ms /= done;
  *projective_ms /= done;
}

// Moves `ids` by a small correction (1.5 cm, 0.6 degrees about z), as a loop closure that
// touches a few keyframes does; returns the time of UpdatePoses.
double Correct(objmap::Mapper* mapper, const std::vector<KeyframeId>& ids,
               objmap::PoseUpdateReport* report) {
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  correction.translation() = Eigen::Vector3d(0.015, -0.01, 0.005);
  correction.linear() = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (KeyframeId id : ids) poses[id] = correction * mapper->FindKeyframe(id)->T_W_C;
  std::string why;
  const Clock::time_point start = Clock::now();
  if (!mapper->UpdatePoses(poses, &why, report)) {
    std::fprintf(stderr, "regeneration_bench: %s\n", why.c_str());
  }
  return Ms(start);
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (argc > 1) args.data_dir = argv[1];
  if (argc > 2) args.keyframes = std::atoi(argv[2]);
  if (argc > 3) args.threads = std::atoi(argv[3]);
  if (argc > 4) args.baseline_keyframes = std::atoi(argv[4]);
  std::string why;
  const auto reader = objmap::OpenSequence(args.data_dir, &why);
  if (!reader) {
    std::fprintf(stderr, "regeneration_bench: %s\n", why.c_str());
    return 1;
  }
  std::map<KeyframeId, KeyframeRecord> records;
  Clock::time_point start = Clock::now();
  if (!ReadKeyframes(*reader, args.keyframes, &records)) return 1;
  const int n = static_cast<int>(records.size());
  std::printf("read %d keyframes in %.1f s (not counted below)\n", n, Ms(start) / 1000.0);
  const std::size_t bytes_per_keyframe =
      records.begin()->second.depth_mm.size() * sizeof(std::uint16_t) +
      records.begin()->second.object_mask.size();
  std::printf("kept per keyframe in memory: %zu bytes (depth mm + object mask)\n",
              bytes_per_keyframe);

  objmap::MapperConfig config;
  config.regeneration.threads = args.threads;
  double stock_ms = 0.0, ray_by_ray_ms = 0.0, projective_ms = 0.0;
  Baselines(records, args.baseline_keyframes, config.occupancy, &stock_ms, &ray_by_ray_ms,
            &projective_ms);
  std::printf(
      "first %d keyframes, one thread, ms per keyframe: stock insertPointCloud %.1f, objmap ray "
      "by ray %.1f, objmap projective %.1f\n",
      args.baseline_keyframes, stock_ms, ray_by_ray_ms, projective_ms);

  objmap::Mapper mapper{config};
  start = Clock::now();
  mapper.Restore(records, {}, 1, nullptr);
  const double full_ms = Ms(start);
  const objmap::OccupancyCounts counts = mapper.occupancy().Counts();
  std::printf("map: %zu occupied, %zu free voxels\n", counts.occupied, counts.free);

  // A correction of 10 keyframes in the middle, then of the last 5 %.
  std::vector<KeyframeId> middle, tail;
  for (int i = 0; i < 10; ++i) middle.push_back(static_cast<KeyframeId>(n / 2 + i + 1));
  for (int i = n - std::max(1, n / 20); i < n; ++i) tail.push_back(static_cast<KeyframeId>(i + 1));
  objmap::PoseUpdateReport middle_report, tail_report;
  const double middle_ms = Correct(&mapper, middle, &middle_report);
  const double tail_ms = Correct(&mapper, tail, &tail_report);

  std::printf("\n| regeneration of %d keyframes | s | ms per keyframe | vs stock |\n", n);
  std::printf("|---|---|---|---|\n");
  std::printf(
      "| stock insertPointCloud, one thread (%d keyframes x %.1f ms) | %.1f | %.1f | 1.0x |\n", n,
      stock_ms, n * stock_ms / 1000.0, stock_ms);
  std::printf("| objmap ray by ray, one thread (%d x %.1f ms) | %.1f | %.1f | %.1fx |\n", n,
              ray_by_ray_ms, n * ray_by_ray_ms / 1000.0, ray_by_ray_ms, stock_ms / ray_by_ray_ms);
  std::printf("| objmap projective, one thread (%d x %.1f ms) | %.1f | %.1f | %.1fx |\n", n,
              projective_ms, n * projective_ms / 1000.0, projective_ms, stock_ms / projective_ms);
  std::printf("| **objmap full rebuild, %d threads (measured)** | **%.1f** | %.1f | %.1fx |\n",
              args.threads, full_ms / 1000.0, full_ms / n, stock_ms * n / full_ms);
  std::printf(
      "| objmap after moving 10 keyframes (incremental: %s, %d keyframes redone) | %.1f | "
      "| %.1fx |\n",
      middle_report.occupancy_incremental ? "yes" : "no", middle_report.keyframes_reintegrated,
      middle_ms / 1000.0, stock_ms * n / middle_ms);
  std::printf(
      "| objmap after moving the last %zu keyframes (incremental: %s, %d redone) | %.1f | "
      "| %.1fx |\n",
      tail.size(), tail_report.occupancy_incremental ? "yes" : "no",
      tail_report.keyframes_reintegrated, tail_ms / 1000.0, stock_ms * n / tail_ms);
  std::printf("\npeak resident memory: %.0f MB\n", PeakResidentMb());
  return 0;
}
