// objmap's segmentation against PCL SupervoxelClustering + LCCPSegmentation, in one run:
//  - mOSD learn clouds: ms per cloud (median, p90) and quality against the ground truth, as
//    defined in segmentation/mosd_ground_truth.h and applied identically to both methods:
//    over-segmentation rate = share of the ground-truth objects' points outside each object's
//    best-overlapping segment; under-segmentation rate = share of the segments' labelled points
//    that belong to another region (object or table) than the segment's dominant one; object
//    recall = objects whose best segment has IoU >= 0.5 (both rates point-weighted, 0 is best);
//  - redkitchen 640x480 frames: ms per frame for Segmenter::Segment, for the mapper's whole
//    segmentation step (Mapper::AddKeyframe's timings.segmentation_ms: back-projection,
//    segmentation, detection-to-segment for every CenterNet detection, keyframe record) and its
//    parts, and for PCL on the first frames.
//   segmentation_bench [mosd=../shared/data/mosd-learn] [sequence=../shared/data/redkitchen]
//                      [frames=10] [stride=50] [pcl_frames=3] [model=models/centernet_coco.pb]
//                      [repetitions=3]
// Each cloud and frame runs `repetitions` times (the mapper step on as many Mappers); the tables
// give over clouds / frames the median and p90 of each one's median run, as wall-clock and as
// CPU time of the benchmark's thread (the machine may be shared).
// PCL runs with the parameters of its LCCP tutorial (voxel 7.5 mm, seed 3 cm, colour off,
// spatial 1, normal 4, concavity tolerance 10 deg, smoothness check 0.1, no sanity criterion, no
// extended convexity, no minimum segment size); conversion to PCL types is not timed.
#include <pcl/point_types.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "dataset/sequence_reader.h"
#include "detection/centernet_detector.h"
#include "mapper/keyframe_segments.h"
#include "mapper/mapper.h"
#include "pipeline/sequence_runner.h"
#include "pointcloud_io/pointcloud_io.h"
#include "segmentation/mosd_ground_truth.h"
#include "segmentation/segment_index.h"
#include "segmentation/segmenter.h"

namespace {

using Clock = std::chrono::steady_clock;
using PclPoint = pcl::PointXYZRGBA;

// Wall-clock and CPU time (of this thread) of one run; on a shared machine the CPU time is what
// the work itself costs, the wall time adds waiting for the core.
struct Timing {
  double wall_ms = 0.0;
  double cpu_ms = 0.0;
};

double ThreadCpuMs() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

class Stopwatch {
 public:
  Stopwatch() : wall_(Clock::now()), cpu_ms_(ThreadCpuMs()) {}
  [[nodiscard]] Timing Elapsed() const {
    return {std::chrono::duration<double, std::milli>(Clock::now() - wall_).count(),
            ThreadCpuMs() - cpu_ms_};
  }

 private:
  Clock::time_point wall_;
  double cpu_ms_;
};

double Percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto rank =
      static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(rank, values.size() - 1)];
}

// Per item (cloud or frame) the median of its repetitions.
struct Timings {
  std::vector<double> wall_ms, cpu_ms;
  void Add(const std::vector<Timing>& repetitions) {
    std::vector<double> wall, cpu;
    for (const Timing& t : repetitions) {
      wall.push_back(t.wall_ms);
      cpu.push_back(t.cpu_ms);
    }
    wall_ms.push_back(objmap::Median(wall));
    cpu_ms.push_back(objmap::Median(cpu));
  }
};

pcl::PointCloud<PclPoint>::Ptr ToPcl(const objmap::OrganizedCloud& cloud) {
  auto pcl_cloud = std::make_shared<pcl::PointCloud<PclPoint>>();
  pcl_cloud->width = static_cast<std::uint32_t>(cloud.width);
  pcl_cloud->height = static_cast<std::uint32_t>(cloud.height);
  pcl_cloud->is_dense = false;
  pcl_cloud->resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    PclPoint& p = (*pcl_cloud)[i];
    p.x = cloud.points_C[i].x();
    p.y = cloud.points_C[i].y();
    p.z = cloud.points_C[i].z();
    if (!cloud.rgb.empty()) {
      p.r = cloud.rgb[i][0];
      p.g = cloud.rgb[i][1];
      p.b = cloud.rgb[i][2];
    }
  }
  return pcl_cloud;
}

// Supervoxels + LCCP as in PCL's LCCP tutorial; returns a compact segment id per point (-1 where
// PCL labels nothing) and the time from the PCL cloud to per-point labels.
std::vector<int> PclLccpSegment(const objmap::OrganizedCloud& cloud, Timing* timing) {
  constexpr float kVoxelM = 0.0075f;
  constexpr float kSeedM = 0.03f;
  const pcl::PointCloud<PclPoint>::Ptr input = ToPcl(cloud);
  const Stopwatch stopwatch;
  pcl::SupervoxelClustering<PclPoint> supervoxels(kVoxelM, kSeedM);
  supervoxels.setUseSingleCameraTransform(false);
  supervoxels.setInputCloud(input);
  supervoxels.setColorImportance(0.f);
  supervoxels.setSpatialImportance(1.f);
  supervoxels.setNormalImportance(4.f);
  std::map<std::uint32_t, pcl::Supervoxel<PclPoint>::Ptr> clusters;
  supervoxels.extract(clusters);
  std::multimap<std::uint32_t, std::uint32_t> adjacency;
  supervoxels.getSupervoxelAdjacency(adjacency);
  pcl::LCCPSegmentation<PclPoint> lccp;
  lccp.setConcavityToleranceThreshold(10.f);
  lccp.setSanityCheck(false);
  lccp.setSmoothnessCheck(true, kVoxelM, kSeedM, 0.1f);
  lccp.setKFactor(0);
  lccp.setMinSegmentSize(0);
  lccp.setInputSupervoxels(clusters, adjacency);
  lccp.segment();
  const pcl::PointCloud<pcl::PointXYZL>::Ptr labelled = supervoxels.getLabeledCloud();
  lccp.relabelCloud(*labelled);
  *timing = stopwatch.Elapsed();
  std::vector<int> segment(cloud.size(), -1);
  std::unordered_map<std::uint32_t, int> compact;
  for (std::size_t i = 0; i < labelled->size() && i < cloud.size(); ++i) {
    const std::uint32_t label = (*labelled)[i].label;
    if (label == 0) continue;  // PCL's "no supervoxel"
    segment[i] = compact.emplace(label, static_cast<int>(compact.size())).first->second;
  }
  return segment;
}

std::vector<int> ToSegmentIds(const objmap::SegmentationResult& result) {
  return std::vector<int>(result.labels.begin(), result.labels.end());
}

struct MethodRun {
  Timings timings;
  objmap::testing::SegmentationRates rates;
};

void PrintMethod(const char* name, const MethodRun& run) {
  const Timings& t = run.timings;
  std::printf("| %-24s | %6.1f | %6.1f | %6.1f | %6.1f | %6.3f | %6.3f | %4.2f (%d/%d) |\n", name,
              objmap::Median(t.wall_ms), Percentile(t.wall_ms, 0.9), objmap::Median(t.cpu_ms),
              Percentile(t.cpu_ms, 0.9), run.rates.OverSegmentation(),
              run.rates.UnderSegmentation(), run.rates.Recall(), run.rates.objects_found,
              run.rates.objects);
}

// Returns false when no mOSD cloud could be read.
bool RunMosd(const std::string& folder, const objmap::Segmenter& segmenter, int repetitions) {
  MethodRun objmap_run, pcl_run;
  for (const std::string& path : objmap::testing::MosdCloudPaths(folder)) {
    objmap::OrganizedCloud cloud;
    std::vector<std::uint32_t> labels;
    std::string why;
    if (!objmap::LoadOrganizedPcd(path, &cloud, &labels, &why)) {
      std::fprintf(stderr, "segmentation_bench: %s\n", why.c_str());
      continue;
    }
    objmap::SegmentationResult result = segmenter.Segment(cloud);  // warm caches
    std::vector<Timing> ours(repetitions), theirs(repetitions);
    std::vector<int> pcl_segments;
    for (int r = 0; r < repetitions; ++r) {
      const Stopwatch stopwatch;
      result = segmenter.Segment(cloud);
      ours[r] = stopwatch.Elapsed();
      pcl_segments = PclLccpSegment(cloud, &theirs[r]);
    }
    objmap_run.timings.Add(ours);
    pcl_run.timings.Add(theirs);
    objmap_run.rates.Add(ToSegmentIds(result), labels);
    pcl_run.rates.Add(pcl_segments, labels);
    std::printf("%-12s objmap %6.1f ms  PCL %7.1f ms (wall, median of %d)\n",
                std::filesystem::path(path).filename().c_str(), objmap_run.timings.wall_ms.back(),
                pcl_run.timings.wall_ms.back(), repetitions);
  }
  if (objmap_run.timings.wall_ms.empty()) return false;
  std::printf("\nmOSD learn, %zu clouds (640x480), ms per cloud:\n",
              objmap_run.timings.wall_ms.size());
  std::printf(
      "| method                   | wall   | p90    | CPU    | p90    | over   | under  | recall "
      "     |\n");
  PrintMethod("objmap Segmenter", objmap_run);
  PrintMethod("PCL supervoxels + LCCP", pcl_run);
  std::printf("ratio PCL / objmap (median wall ms): %.1fx\n\n",
              objmap::Median(pcl_run.timings.wall_ms) / objmap::Median(objmap_run.timings.wall_ms));
  return true;
}

struct KitchenTimings {
  Timings back_projection, segment, detection_to_segment, parts, pcl, segment_on_pcl_frames;
  std::vector<double> mapper_step_ms;  // wall, as Mapper::AddKeyframe reports it
};

void RunKitchen(const std::string& sequence, int frames, int stride, int pcl_frames,
                const std::string& model_path, int repetitions) {
  std::string why;
  auto reader = objmap::OpenSequence(sequence, &why);
  if (!reader) {
    std::fprintf(stderr, "segmentation_bench: %s\n", why.c_str());
    return;
  }
  objmap::CenterNetConfig detector_config;
  detector_config.model_path = model_path;
  auto detector = objmap::MakeCenterNetDetector(detector_config, &why);
  if (!detector) std::fprintf(stderr, "segmentation_bench: no detections: %s\n", why.c_str());
  const objmap::MapperConfig mapper_config;
  // One mapper per repetition: each sees every frame once, as in a run.
  std::vector<std::unique_ptr<objmap::Mapper>> mappers;
  for (int r = 0; r < repetitions; ++r) {
    mappers.push_back(std::make_unique<objmap::Mapper>(mapper_config));
  }
  const objmap::Segmenter segmenter{mapper_config.segmenter};
  KitchenTimings times;
  int detections_total = 0;
  for (int k = 0; k < frames; ++k) {
    objmap::RgbdFrame frame;
    if (!reader->ReadFrame(static_cast<std::size_t>(k * stride), &frame, &why)) continue;
    std::vector<objmap::Detection> detections;
    if (detector && !detector->Detect(frame, &detections, &why)) detections.clear();
    detections_total += static_cast<int>(detections.size());
    std::vector<Timing> back_projection(repetitions), segment(repetitions),
        detection_to_segment(repetitions), parts(repetitions);
    std::vector<double> mapper_step;
    objmap::OrganizedCloud cloud;
    for (int r = 0; r < repetitions; ++r) {
      const Stopwatch whole;
      Stopwatch stopwatch;
      cloud = objmap::BackProject(frame.depth, frame.color, frame.intrinsics);
      back_projection[r] = stopwatch.Elapsed();
      stopwatch = Stopwatch();
      const objmap::SegmentationResult result = segmenter.Segment(cloud);
      segment[r] = stopwatch.Elapsed();
      stopwatch = Stopwatch();
      const objmap::SegmentIndex index = objmap::IndexSegments(result, cloud);
      const auto segmented =
          objmap::SegmentDetections(frame, cloud, objmap::DepthMillimetres(frame.depth), result,
                                    index, detections, 0, mapper_config);
      detection_to_segment[r] = stopwatch.Elapsed();
      parts[r] = whole.Elapsed();
      objmap::KeyframeResult keyframe;
      if (mappers[r]->AddKeyframe(frame, detections, &keyframe, &why)) {
        mapper_step.push_back(keyframe.timings.segmentation_ms);
      }
    }
    times.back_projection.Add(back_projection);
    times.segment.Add(segment);
    times.detection_to_segment.Add(detection_to_segment);
    times.parts.Add(parts);
    times.mapper_step_ms.push_back(objmap::Median(mapper_step));
    std::printf("frame %4d: %2zu detections, Segment %5.1f ms, mapper step %5.1f ms", k * stride,
                detections.size(), times.segment.wall_ms.back(), times.mapper_step_ms.back());
    if (k < pcl_frames) {
      Timing pcl;
      const std::vector<int> pcl_segments = PclLccpSegment(cloud, &pcl);
      times.pcl.Add({pcl});
      times.segment_on_pcl_frames.Add(segment);
      std::printf(", PCL supervoxels + LCCP %7.1f ms", pcl.wall_ms);
    }
    std::printf("\n");
  }
  if (times.segment.wall_ms.empty()) return;
  std::printf(
      "\nredkitchen, %zu frames 640x480 (every %d-th), %.1f detections per frame, median of %d "
      "runs per frame, ms per frame:\n",
      times.segment.wall_ms.size(), stride,
      static_cast<double>(detections_total) / static_cast<double>(times.segment.wall_ms.size()),
      repetitions);
  std::printf("| stage                                    | wall   | p90    | CPU    | p90    |\n");
  auto row = [](const char* name, const Timings& t) {
    std::printf("| %-40s | %6.1f | %6.1f | %6.1f | %6.1f |\n", name, objmap::Median(t.wall_ms),
                Percentile(t.wall_ms, 0.9), objmap::Median(t.cpu_ms), Percentile(t.cpu_ms, 0.9));
  };
  row("back-projection", times.back_projection);
  row("Segmenter::Segment", times.segment);
  row("SegmentDetections (detection-to-segment)", times.detection_to_segment);
  row("the three together", times.parts);
  std::printf("| %-40s | %6.1f | %6.1f |      - |      - |\n", "mapper segmentation step (whole)",
              objmap::Median(times.mapper_step_ms), Percentile(times.mapper_step_ms, 0.9));
  row("PCL supervoxels + LCCP", times.pcl);
  if (!times.pcl.wall_ms.empty()) {
    std::printf(
        "ratio PCL / objmap Segment on the same %zu frames: %.1fx; PCL / mapper step: %.1fx\n",
        times.pcl.wall_ms.size(),
        objmap::Median(times.pcl.wall_ms) / objmap::Median(times.segment_on_pcl_frames.wall_ms),
        objmap::Median(times.pcl.wall_ms) / objmap::Median(times.mapper_step_ms));
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mosd = argc > 1 ? argv[1] : "../shared/data/mosd-learn";
  const std::string sequence = argc > 2 ? argv[2] : "../shared/data/redkitchen";
  const int frames = argc > 3 ? std::atoi(argv[3]) : 10;
  const int stride = argc > 4 ? std::atoi(argv[4]) : 50;
  const int pcl_frames = argc > 5 ? std::atoi(argv[5]) : 3;
  const std::string model = argc > 6 ? argv[6] : OBJMAP_DEFAULT_MODEL_PATH;
  const int repetitions = std::max(1, argc > 7 ? std::atoi(argv[7]) : 3);
  const objmap::Segmenter segmenter{objmap::SegmenterConfig{}};
  if (!RunMosd(mosd, segmenter, repetitions)) {
    std::fprintf(stderr, "segmentation_bench: no mOSD clouds\n");
  }
  RunKitchen(sequence, frames, stride, pcl_frames, model, repetitions);
  return 0;
}
