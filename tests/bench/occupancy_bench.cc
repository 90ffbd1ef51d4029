// Occupancy integration speed: objmap's OccupancyMap against stock OcTree::insertPointCloud on
// 7-Scenes redkitchen keyframes, plus voxel-by-voxel agreement of the two maps.
//
// Usage: occupancy_bench [data_dir] [keyframes=10] [stride=10] [stock_keyframes=2] [max_range_m=4]
//                        [one_ray_per_end_voxel=0]

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "dataset/sequence_reader.h"
#include "types/organized_cloud.h"
#include "occupancy/occupancy_map.h"
#include "occupancy/octree_compare.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string data_dir = "../shared/data/redkitchen";
  int keyframes = 10;
  int stride = 10;
  int stock_keyframes = 2;
  double max_range_m = 4.0;
  bool one_ray_per_end_voxel = false;
};

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Every valid depth pixel of frame `index`, in the world frame, read through the dataset reader.
bool LoadScan(const objmap::SequenceReader& reader, int index, objmap::ScanW* scan) {
  objmap::RgbdFrame frame;
  std::string why;
  if (!reader.ReadFrame(static_cast<std::size_t>(index), &frame, &why)) {
    std::fprintf(stderr, "occupancy_bench: %s\n", why.c_str());
    return false;
  }
  const objmap::OrganizedCloud cloud_C =
      objmap::BackProject(frame.depth, objmap::ColorImage{}, frame.intrinsics);
  const Eigen::Isometry3f T_W_C = frame.T_W_C.cast<float>();
  scan->origin_W = T_W_C.translation();
  scan->structure_points_W.clear();
  for (std::size_t i = 0; i < cloud_C.size(); ++i) {
    if (cloud_C.IsValid(static_cast<int>(i))) {
      scan->structure_points_W.push_back(T_W_C * cloud_C.points_C[i]);
    }
  }
  return true;
}

double InsertStock(const objmap::ScanW& scan, double max_range_m, octomap::OcTree* tree) {
  octomap::Pointcloud cloud;
  cloud.reserve(scan.structure_points_W.size());
  for (const Eigen::Vector3f& p : scan.structure_points_W) cloud.push_back(p.x(), p.y(), p.z());
  const Clock::time_point start = Clock::now();
  tree->insertPointCloud(cloud,
                         octomap::point3d(scan.origin_W.x(), scan.origin_W.y(), scan.origin_W.z()),
                         max_range_m);
  return MsSince(start);
}

void PrintAgreement(const objmap::OccupancyMap& map, const octomap::OcTree& stock) {
  const std::string path = "/tmp/objmap_occupancy_bench.bt";
  std::string why;
  if (!map.WriteBinary(path, &why)) {
    std::printf("agreement: cannot write %s: %s\n", path.c_str(), why.c_str());
    return;
  }
  octomap::OcTree ours(path);
  const objmap::testing::LeafComparison cmp = objmap::testing::CompareTrees(ours, stock);
  std::printf(
      "agreement after the stock keyframes: %zu of %zu known voxels agree (%.6f%%); "
      "only objmap %zu, only stock %zu, state differs %zu\n",
      cmp.agree, cmp.known_in_either, 100.0 * cmp.Agreement(), cmp.only_a, cmp.only_b,
      cmp.state_differs);
  std::remove(path.c_str());
}

Args ParseArgs(int argc, char** argv) {
  Args args;
  if (argc > 1) args.data_dir = argv[1];
  if (argc > 2) args.keyframes = std::atoi(argv[2]);
  if (argc > 3) args.stride = std::atoi(argv[3]);
  if (argc > 4) args.stock_keyframes = std::atoi(argv[4]);
  if (argc > 5) args.max_range_m = std::atof(argv[5]);
  if (argc > 6) args.one_ray_per_end_voxel = std::atoi(argv[6]) != 0;
  return args;
}

}  // namespace

struct Totals {
  double ours_ms = 0.0;
  double ours_on_stock_frames_ms = 0.0;
  double stock_ms = 0.0;
  int done = 0;
};

// Integrates one keyframe with objmap (and with stock OctoMap for the first ones).
bool RunKeyframe(const Args& args, const objmap::SequenceReader& reader, int k,
                 objmap::OccupancyMap* map, octomap::OcTree* stock, Totals* totals) {
  objmap::ScanW scan;
  const int index = k * args.stride;
  if (!LoadScan(reader, index, &scan)) return false;
  const Clock::time_point start = Clock::now();
  map->Integrate(scan);
  const double ms = MsSince(start);
  const objmap::IntegrationStats& s = map->last_stats();
  std::printf(
      "frame %4d: %6zu rays, objmap %6.1f ms (cast %6.1f, tree %6.1f), free %7zu, "
      "occupied %6zu",
      index, s.rays, ms, s.cast_ms, s.tree_update_ms, s.free_voxels, s.occupied_voxels);
  totals->ours_ms += ms;
  ++totals->done;
  if (k < args.stock_keyframes) {
    const double stock_ms = InsertStock(scan, args.max_range_m, stock);
    std::printf(", stock %8.1f ms", stock_ms);
    totals->stock_ms += stock_ms;
    totals->ours_on_stock_frames_ms += ms;
  }
  std::printf("\n");
  std::fflush(stdout);
  return true;
}

int main(int argc, char** argv) {
  const Args args = ParseArgs(argc, argv);
  std::string why;
  const auto reader = objmap::OpenSequence(args.data_dir, &why);
  if (!reader) {
    std::fprintf(stderr, "occupancy_bench: %s\n", why.c_str());
    return 1;
  }
  objmap::OccupancyConfig config;
  config.max_range_m = args.max_range_m;
  // Stock carving, so that the map is comparable voxel for voxel with insertPointCloud.
  config.structure_margin_m = 0.0;
  config.structure_margin_per_m2 = 0.0;
  config.one_ray_per_end_voxel = args.one_ray_per_end_voxel;
  objmap::OccupancyMap map(config);
  octomap::OcTree stock(config.resolution_m);
  Totals totals;
  for (int k = 0; k < args.keyframes; ++k) {
    if (!RunKeyframe(args, *reader, k, &map, &stock, &totals)) break;
    if (k + 1 == args.stock_keyframes) PrintAgreement(map, stock);
  }
  if (totals.done == 0) return 1;
  const int stock_done = std::min(totals.done, args.stock_keyframes);
  std::printf("objmap: %.1f ms per keyframe over %d keyframes\n", totals.ours_ms / totals.done,
              totals.done);
  if (stock_done > 0) {
    std::printf(
        "stock insertPointCloud: %.1f ms per keyframe over %d keyframes; objmap on the "
        "same keyframes %.1f ms; speed-up %.1fx\n",
        totals.stock_ms / stock_done, stock_done, totals.ours_on_stock_frames_ms / stock_done,
        totals.stock_ms / totals.ours_on_stock_frames_ms);
  }
  const objmap::OccupancyCounts counts = map.Counts();
  std::printf("map: %zu occupied, %zu free leaf voxels\n", counts.occupied, counts.free);
  return 0;
}
