// `objmap segment`: the unsupervised segmentation alone on one organized cloud.
#include <chrono>
#include <iostream>

#include "arguments.h"
#include "commands.h"
#include "pointcloud_io/pointcloud_io.h"
#include "segmentation/segmenter.h"

namespace objmap::cli {

int RunSegmentCommand(int argc, char** argv) {
  Arguments args(argc, argv, {"--out"}, {"--help"});
  constexpr char kUsage[] =
      "objmap segment: segments one organized point cloud without supervision (labels per point).\n"
      "usage: objmap segment <organized.pcd> --out <labelled.pcd>\n"
      "  reads an organized cloud (fields x y z rgb/rgba) and writes it with a `label` field:\n"
      "  0 for invalid points, segment s as s + 1\n";
  if (args.Has("--help")) {
    std::cout << kUsage;
    return 0;
  }
  if (!args.error().empty() || args.positional().size() != 1 || !args.Has("--out")) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << kUsage;
    return 2;
  }
  std::string why;
  OrganizedCloud cloud;
  if (!LoadOrganizedPcd(args.positional()[0], &cloud, nullptr, &why)) {
    std::cerr << "objmap segment: " << why << "\n";
    return 1;
  }
  if (cloud.height <= 1) {
    std::cerr << "objmap segment: " << args.positional()[0]
              << " is not organized (height 1); the segmentation needs the image grid\n";
    return 1;
  }
  const Segmenter segmenter{SegmenterConfig{}};
  const auto start = std::chrono::steady_clock::now();
  const SegmentationResult result = segmenter.Segment(cloud);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  int planes = 0;
  for (bool is_plane : result.segment_is_plane) planes += is_plane ? 1 : 0;
  std::cout << cloud.width << "x" << cloud.height << ": " << result.num_segments << " segments ("
            << planes << " supporting planes) in " << ms << " ms\n";
  if (!SaveLabelledPcd(args.Get("--out", ""), cloud, result.labels, &why)) {
    std::cerr << "objmap segment: " << why << "\n";
    return 1;
  }
  std::cout << "wrote " << args.Get("--out", "") << "\n";
  return 0;
}

}  // namespace objmap::cli
