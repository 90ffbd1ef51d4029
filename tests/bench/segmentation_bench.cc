// objmap's segmentation against PCL SupervoxelClustering + LCCPSegmentation, in one run:
//  - mOSD learn clouds: ms per cloud (median, p90) and quality against the ground truth (rates of
//    segmentation/mosd_ground_truth.h: over-segmentation, under-segmentation, object recall);
//  - redkitchen 640x480 frames: ms per frame for Segmenter::Segment, for the mapper's whole
//    segmentation step (Mapper::AddKeyframe's timings.segmentation_ms: back-projection,
//    segmentation, detection-to-segment for every CenterNet detection, keyframe record) and its
//    parts, and for PCL on the first frames.
//   segmentation_bench [mosd=../shared/data/mosd-learn] [sequence=../shared/data/redkitchen]
//                      [frames=10] [stride=50] [pcl_frames=3] [model=models/centernet_coco.pb]
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
#include <filesystem>
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
#include "segmentation/segmenter.h"

namespace {

using Clock = std::chrono::steady_clock;
using PclPoint = pcl::PointXYZRGBA;

double Ms(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double Percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto rank =
      static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(rank, values.size() - 1)];
}

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
std::vector<int> PclLccpSegment(const objmap::OrganizedCloud& cloud, double* ms) {
  constexpr float kVoxelM = 0.0075f;
  constexpr float kSeedM = 0.03f;
  const pcl::PointCloud<PclPoint>::Ptr input = ToPcl(cloud);
  const auto start = Clock::now();
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
  *ms = Ms(start);
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
  std::vector<double> ms;
  objmap::testing::SegmentationRates rates;
};

void PrintMethod(const char* name, const MethodRun& run) {
  std::printf("| %-28s | %7.1f | %7.1f | %6.3f | %6.3f | %5.2f (%d/%d) |\n", name,
              objmap::Median(run.ms), Percentile(run.ms, 0.9), run.rates.OverSegmentation(),
              run.rates.UnderSegmentation(), run.rates.Recall(), run.rates.objects_found,
              run.rates.objects);
}

// Returns false when no mOSD cloud could be read.
bool RunMosd(const std::string& folder, const objmap::Segmenter& segmenter) {
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
    auto start = Clock::now();
    result = segmenter.Segment(cloud);
    objmap_run.ms.push_back(Ms(start));
    objmap_run.rates.Add(ToSegmentIds(result), labels);
    double pcl_ms = 0.0;
    const std::vector<int> pcl_segments = PclLccpSegment(cloud, &pcl_ms);
    pcl_run.ms.push_back(pcl_ms);
    pcl_run.rates.Add(pcl_segments, labels);
    std::printf("%-12s objmap %6.1f ms  PCL %7.1f ms\n",
                std::filesystem::path(path).filename().c_str(), objmap_run.ms.back(), pcl_ms);
  }
  if (objmap_run.ms.empty()) return false;
  std::printf("\nmOSD learn, %zu clouds (640x480):\n", objmap_run.ms.size());
  std::printf("| method                       | ms med  | ms p90  | over   | under  | recall |\n");
  PrintMethod("objmap Segmenter", objmap_run);
  PrintMethod("PCL supervoxels + LCCP", pcl_run);
  std::printf("ratio PCL / objmap (median ms): %.1fx\n\n",
              objmap::Median(pcl_run.ms) / objmap::Median(objmap_run.ms));
  return true;
}

struct FrameTimes {
  std::vector<double> back_projection, segment, detection_to_segment, mapper_step, pcl;
  std::vector<double> segment_on_pcl_frames;
};

void RunKitchen(const std::string& sequence, int frames, int stride, int pcl_frames,
                const std::string& model_path) {
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
  objmap::Mapper mapper(mapper_config);
  const objmap::Segmenter segmenter{mapper_config.segmenter};
  FrameTimes times;
  int detections_total = 0;
  for (int k = 0; k < frames; ++k) {
    objmap::RgbdFrame frame;
    if (!reader->ReadFrame(static_cast<std::size_t>(k * stride), &frame, &why)) continue;
    std::vector<objmap::Detection> detections;
    if (detector && !detector->Detect(frame, &detections, &why)) detections.clear();
    detections_total += static_cast<int>(detections.size());
    auto start = Clock::now();
    const objmap::OrganizedCloud cloud =
        objmap::BackProject(frame.depth, frame.color, frame.intrinsics);
    times.back_projection.push_back(Ms(start));
    start = Clock::now();
    const objmap::SegmentationResult result = segmenter.Segment(cloud);
    times.segment.push_back(Ms(start));
    start = Clock::now();
    const auto segmented =
        objmap::SegmentDetections(frame, cloud, result, detections, 0, mapper_config);
    times.detection_to_segment.push_back(Ms(start));
    objmap::KeyframeResult keyframe;
    if (mapper.AddKeyframe(frame, detections, &keyframe, &why)) {
      times.mapper_step.push_back(keyframe.timings.segmentation_ms);
    }
    std::printf("frame %4d: %2zu detections, Segment %5.1f ms, mapper step %5.1f ms", k * stride,
                detections.size(), times.segment.back(),
                times.mapper_step.empty() ? 0.0 : times.mapper_step.back());
    if (k < pcl_frames) {
      double pcl_ms = 0.0;
      const std::vector<int> pcl_segments = PclLccpSegment(cloud, &pcl_ms);
      times.pcl.push_back(pcl_ms);
      times.segment_on_pcl_frames.push_back(times.segment.back());
      std::printf(", PCL supervoxels + LCCP %7.1f ms", pcl_ms);
    }
    std::printf("\n");
  }
  if (times.segment.empty()) return;
  std::printf("\nredkitchen, %zu frames 640x480 (every %d-th), %.1f detections per frame:\n",
              times.segment.size(), stride,
              static_cast<double>(detections_total) / static_cast<double>(times.segment.size()));
  std::printf("| stage                                   | ms med  | ms p90  |\n");
  auto row = [](const char* name, const std::vector<double>& ms) {
    std::printf("| %-39s | %7.1f | %7.1f |\n", name, objmap::Median(ms), Percentile(ms, 0.9));
  };
  row("back-projection", times.back_projection);
  row("Segmenter::Segment", times.segment);
  row("SegmentDetections (detection-to-segment)", times.detection_to_segment);
  row("mapper segmentation step (whole)", times.mapper_step);
  row("PCL supervoxels + LCCP", times.pcl);
  if (!times.pcl.empty()) {
    std::printf(
        "ratio PCL / objmap Segment on the same %zu frames: %.1fx; PCL / mapper step: %.1fx\n",
        times.pcl.size(), objmap::Median(times.pcl) / objmap::Median(times.segment_on_pcl_frames),
        objmap::Median(times.pcl) / objmap::Median(times.mapper_step));
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
  const objmap::Segmenter segmenter{objmap::SegmenterConfig{}};
  if (!RunMosd(mosd, segmenter)) std::fprintf(stderr, "segmentation_bench: no mOSD clouds\n");
  RunKitchen(sequence, frames, stride, pcl_frames, model);
  return 0;
}
