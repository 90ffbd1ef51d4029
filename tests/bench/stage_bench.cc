// Per-frame cost of the detector and of the segmentation, with PCL's SupervoxelClustering (only
// the supervoxel step of the paper's segmentation) as the baseline on the same frames.
//   stage_bench [sequence=../shared/data/redkitchen] [frames=10] [stride=50] [pcl_frames=3]
#include <pcl/point_types.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "detection/centernet_detector.h"
#include "pipeline/sequence_runner.h"
#include "segmentation/segmenter.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;

// PCL's supervoxels with the parameters of its tutorial scaled to a Kinect frame.
double PclSupervoxelMs(const objmap::OrganizedCloud& cloud, std::size_t* clusters) {
  auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZRGBA>>();
  pcl_cloud->width = cloud.width;
  pcl_cloud->height = cloud.height;
  pcl_cloud->is_dense = false;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    pcl::PointXYZRGBA p;
    p.x = cloud.points_C[i].x();
    p.y = cloud.points_C[i].y();
    p.z = cloud.points_C[i].z();
    pcl_cloud->push_back(p);
  }
  const auto start = Clock::now();
  pcl::SupervoxelClustering<pcl::PointXYZRGBA> supervoxels(0.008f, 0.1f);
  supervoxels.setUseSingleCameraTransform(false);
  supervoxels.setInputCloud(pcl_cloud);
  supervoxels.setColorImportance(0.2f);
  supervoxels.setSpatialImportance(0.4f);
  supervoxels.setNormalImportance(1.0f);
  std::map<std::uint32_t, pcl::Supervoxel<pcl::PointXYZRGBA>::Ptr> clusters_out;
  supervoxels.extract(clusters_out);
  *clusters = clusters_out.size();
  return Ms(start);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const int frames = argc > 2 ? std::atoi(argv[2]) : 10;
  const int stride = argc > 3 ? std::atoi(argv[3]) : 50;
  const int pcl_frames = argc > 4 ? std::atoi(argv[4]) : 3;
  std::string why;
  auto reader = objmap::OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "stage_bench: %s\n", why.c_str());
    return 1;
  }
  objmap::CenterNetConfig detector_config;
  detector_config.model_path = OBJMAP_DEFAULT_MODEL_PATH;
  auto detector = objmap::MakeCenterNetDetector(detector_config, &why);
  if (!detector) std::fprintf(stderr, "stage_bench: detector skipped: %s\n", why.c_str());
  const objmap::Segmenter segmenter{objmap::SegmenterConfig{}};
  std::vector<double> detection_ms, segmentation_ms, pcl_ms, segmentation_on_pcl_frames_ms;
  for (int k = 0; k < frames; ++k) {
    objmap::RgbdFrame frame;
    if (!reader->ReadFrame(static_cast<std::size_t>(k * stride), &frame, &why)) continue;
    if (detector) {
      std::vector<objmap::Detection> detections;
      const auto start = Clock::now();
      if (detector->Detect(frame, &detections, &why)) detection_ms.push_back(Ms(start));
    }
    const objmap::OrganizedCloud cloud =
        objmap::BackProject(frame.depth, frame.color, frame.intrinsics);
    auto start = Clock::now();
    const objmap::SegmentationResult result = segmenter.Segment(cloud);
    segmentation_ms.push_back(Ms(start));
    std::printf("frame %4d: objmap segmentation %6.1f ms, %3d segments", k * stride,
                segmentation_ms.back(), result.num_segments);
    if (k < pcl_frames) {
      std::size_t clusters = 0;
      pcl_ms.push_back(PclSupervoxelMs(cloud, &clusters));
      segmentation_on_pcl_frames_ms.push_back(segmentation_ms.back());
      std::printf("; PCL supervoxels alone %7.1f ms, %zu supervoxels", pcl_ms.back(), clusters);
    }
    std::printf("\n");
  }
  std::printf("\nmedian over %zu frames: detection %.1f ms, objmap segmentation %.1f ms\n",
              segmentation_ms.size(), objmap::Median(detection_ms),
              objmap::Median(segmentation_ms));
  if (!pcl_ms.empty()) {
    std::printf(
        "PCL SupervoxelClustering alone %.1f ms vs objmap whole segmentation %.1f ms on "
        "the same %zu frames: %.1fx\n",
        objmap::Median(pcl_ms), objmap::Median(segmentation_on_pcl_frames_ms), pcl_ms.size(),
        objmap::Median(pcl_ms) / objmap::Median(segmentation_on_pcl_frames_ms));
  }
  return 0;
}
