// Occupancy integration speed: objmap's OccupancyMap against stock OcTree::insertPointCloud on
// 7-Scenes redkitchen keyframes, plus voxel-by-voxel agreement of the two maps.
//
// Usage: occupancy_bench [data_dir] [keyframes=10] [stride=10] [stock_keyframes=2] [max_range_m=4]
//                        [ray_by_ray_keyframes=all] [threads_per_scan=1]

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "dataset/sequence_reader.h"
#include "occupancy/occupancy_map.h"
#include "occupancy/octree_compare.h"
#include "types/organized_cloud.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string data_dir = "../shared/data/redkitchen";
  int keyframes = 10;
  int stride = 10;
  int stock_keyframes = 2;
  double max_range_m = 4.0;
  int ray_by_ray_keyframes = 1 << 30;  ///< how many keyframes also go ray by ray (all by default)
  int threads_per_scan = 1;            ///< one core by default, as the stock baseline
};

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Frame `index` as a depth scan, read through the dataset reader.
bool LoadScan(const objmap::SequenceReader& reader, int index, objmap::DepthScanW* scan) {
  objmap::RgbdFrame frame;
  std::string why;
  if (!reader.ReadFrame(static_cast<std::size_t>(index), &frame, &why)) {
    std::fprintf(stderr, "occupancy_bench: %s\n", why.c_str());
    return false;
  }
  const objmap::OrganizedCloud cloud_C =
      objmap::BackProject(frame.depth, objmap::ColorImage{}, frame.intrinsics);
  scan->T_W_C = frame.T_W_C.cast<float>();
  scan->width = cloud_C.width;
  scan->height = cloud_C.height;
  scan->fx = static_cast<float>(frame.intrinsics.fx);
  scan->fy = static_cast<float>(frame.intrinsics.fy);
  scan->cx = static_cast<float>(frame.intrinsics.cx);
  scan->cy = static_cast<float>(frame.intrinsics.cy);
  scan->points_C = cloud_C.points_C;
  return true;
}

// Voxel-by-voxel agreement of one of our maps with a reference tree (stock or ours).
void PrintAgreement(const char* what, const objmap::OccupancyMap& map,
                    const octomap::OcTree& reference) {
  const std::string path = "/tmp/objmap_occupancy_bench.bt";
  std::string why;
  if (!map.WriteBinary(path, &why)) {
    std::printf("agreement: cannot write %s: %s\n", path.c_str(), why.c_str());
    return;
  }
  octomap::OcTree ours(path);
  std::remove(path.c_str());
  const objmap::testing::LeafComparison cmp = objmap::testing::CompareTrees(ours, reference);
  std::printf(
      "agreement %s: %zu of %zu voxels known in either agree (%.4f%%); only objmap %zu, only "
      "reference %zu, free vs occupied %zu\n",
      what, cmp.agree, cmp.known_in_either, 100.0 * cmp.Agreement(), cmp.only_a, cmp.only_b,
      cmp.state_differs);
}

std::string BinaryTreeBytes(const objmap::OccupancyMap& map) {
  return map.BinaryBytes(false, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), nullptr);
}

Args ParseArgs(int argc, char** argv) {
  Args args;
  if (argc > 1) args.data_dir = argv[1];
  if (argc > 2) args.keyframes = std::atoi(argv[2]);
  if (argc > 3) args.stride = std::atoi(argv[3]);
  if (argc > 4) args.stock_keyframes = std::atoi(argv[4]);
  if (argc > 5) args.max_range_m = std::atof(argv[5]);
  if (argc > 6) args.ray_by_ray_keyframes = std::atoi(argv[6]);
  if (argc > 7) args.threads_per_scan = std::atoi(argv[7]);
  return args;
}

struct Totals {
  std::vector<double> projective_ms, cast_ms, tree_ms, ray_by_ray_ms;
  double projective_on_stock_frames_ms = 0.0;
  double ray_by_ray_on_stock_frames_ms = 0.0;
  double stock_ms = 0.0;
  int done = 0;
};

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

double Mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

struct Maps {
  objmap::OccupancyMap projective;
  objmap::OccupancyMap ray_by_ray;
  octomap::OcTree stock;
};

// Integrates one keyframe projectively, ray by ray, and with stock OctoMap for the first ones.
bool RunKeyframe(const Args& args, const objmap::SequenceReader& reader, int k, Maps* maps,
                 Totals* totals) {
  objmap::DepthScanW scan;
  const int index = k * args.stride;
  if (!LoadScan(reader, index, &scan)) return false;
  const objmap::ScanW points = objmap::ToScanW(scan);
  Clock::time_point start = Clock::now();
  maps->projective.Integrate(scan);
  const double projective_ms = MsSince(start);
  const objmap::IntegrationStats s = maps->projective.last_stats();
  double ray_by_ray_ms = 0.0;
  if (k < args.ray_by_ray_keyframes) {
    start = Clock::now();
    maps->ray_by_ray.Integrate(points);
    ray_by_ray_ms = MsSince(start);
  }
  std::printf(
      "frame %4d: %6zu rays, projective %6.1f ms (carve %5.1f, tree %5.1f; %zu blocks decided, "
      "%zu voxels tested), ray by ray %6.1f ms, free %7zu, occupied %6zu",
      index, s.rays, projective_ms, s.cast_ms, s.tree_update_ms, s.blocks_decided, s.voxels_tested,
      ray_by_ray_ms, s.free_voxels, s.occupied_voxels);
  totals->projective_ms.push_back(projective_ms);
  totals->cast_ms.push_back(s.cast_ms);
  totals->tree_ms.push_back(s.tree_update_ms);
  totals->ray_by_ray_ms.push_back(ray_by_ray_ms);
  ++totals->done;
  if (k < args.stock_keyframes) {
    octomap::Pointcloud cloud;
    for (const Eigen::Vector3f& p : points.structure_points_W) cloud.push_back(p.x(), p.y(), p.z());
    start = Clock::now();
    maps->stock.insertPointCloud(
        cloud, octomap::point3d(points.origin_W.x(), points.origin_W.y(), points.origin_W.z()),
        args.max_range_m);
    const double stock_ms = MsSince(start);
    std::printf(", stock %7.1f ms", stock_ms);
    totals->stock_ms += stock_ms;
    totals->projective_on_stock_frames_ms += projective_ms;
    totals->ray_by_ray_on_stock_frames_ms += ray_by_ray_ms;
  }
  std::printf("\n");
  std::fflush(stdout);
  return true;
}

}  // namespace

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
  config.threads_per_scan = args.threads_per_scan;
  std::printf("projective carving on %d thread(s) per scan\n", config.threads_per_scan);
  Maps maps{objmap::OccupancyMap(config), objmap::OccupancyMap(config),
            octomap::OcTree(config.resolution_m)};
  Totals totals;
  for (int k = 0; k < args.keyframes; ++k) {
    if (!RunKeyframe(args, *reader, k, &maps, &totals)) break;
    if (k + 1 == args.stock_keyframes) {
      PrintAgreement("projective vs stock", maps.projective, maps.stock);
      PrintAgreement("ray by ray vs stock", maps.ray_by_ray, maps.stock);
    }
  }
  if (totals.done == 0) return 1;
  if (args.ray_by_ray_keyframes >= totals.done) {
    std::istringstream bytes(BinaryTreeBytes(maps.ray_by_ray));
    octomap::OcTree ray_by_ray_tree(config.resolution_m);
    ray_by_ray_tree.readBinary(bytes);
    PrintAgreement("projective vs ray by ray, all keyframes", maps.projective, ray_by_ray_tree);
  }
  std::printf(
      "objmap projective: median %.1f ms, mean %.1f ms per keyframe (carve median %.1f, tree "
      "update median %.1f) over %d keyframes\n",
      Median(totals.projective_ms), Mean(totals.projective_ms), Median(totals.cast_ms),
      Median(totals.tree_ms), totals.done);
  std::printf("objmap ray by ray: median %.1f ms, mean %.1f ms per keyframe; ratio %.1fx\n",
              Median(totals.ray_by_ray_ms), Mean(totals.ray_by_ray_ms),
              Mean(totals.ray_by_ray_ms) / Mean(totals.projective_ms));
  const int stock_done = std::min(totals.done, args.stock_keyframes);
  if (stock_done > 0) {
    std::printf(
        "stock insertPointCloud: %.1f ms per keyframe over %d keyframes; on the same keyframes "
        "objmap projective %.1f ms (%.1fx faster), ray by ray %.1f ms (%.1fx faster)\n",
        totals.stock_ms / stock_done, stock_done, totals.projective_on_stock_frames_ms / stock_done,
        totals.stock_ms / totals.projective_on_stock_frames_ms,
        totals.ray_by_ray_on_stock_frames_ms / stock_done,
        totals.stock_ms / totals.ray_by_ray_on_stock_frames_ms);
  }
  const objmap::OccupancyCounts counts = maps.projective.Counts();
  std::printf("map: %zu occupied, %zu free leaf voxels\n", counts.occupied, counts.free);
  return 0;
}
