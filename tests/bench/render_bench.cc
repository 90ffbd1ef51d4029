// objmap render's stages on a map folder: reading the scene (map.bt expanded to voxels, objects),
// rendering a picture per view, writing the PNG; next to stock OctoMap reading the same map.bt
// and visiting its occupied leaves, the least any picture of it costs.
//   render_bench <map-dir> [runs=5] [width=1280] [height=960]
#include <octomap/octomap.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "render/map_picture.h"
#include "render/map_scene_io.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::bench::Median;

}  // namespace

int main(int argc, char** argv) {
  using namespace objmap;
  if (argc < 2) {
    std::fprintf(stderr, "usage: render_bench <map-dir> [runs] [width] [height]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  PictureConfig config;
  if (argc > 4) {
    config.width = std::atoi(argv[3]);
    config.height = std::atoi(argv[4]);
  }
  std::string why;
  std::vector<double> stock_ms, read_ms, png_ms;
  std::vector<std::vector<double>> view_ms(2);
  std::size_t leaves = 0;
  PictureScene scene;
  const std::string png =
      (std::filesystem::temp_directory_path() / "objmap_render_bench.png").string();
  for (int run = 0; run < runs; ++run) {
    auto start = Clock::now();
    octomap::OcTree tree((dir + "/map.bt").c_str());
    leaves = 0;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) leaves += tree.isNodeOccupied(*it);
    stock_ms.push_back(Ms(start));
    start = Clock::now();
    if (!ReadMapScene(dir, &scene, &why)) {
      std::fprintf(stderr, "render_bench: %s\n", why.c_str());
      return 1;
    }
    read_ms.push_back(Ms(start));
    MapPicture picture;
    for (const PictureView view : {PictureView::kPerspective, PictureView::kTop}) {
      config.view = view;
      start = Clock::now();
      if (!RenderMapPicture(scene, config, &picture, &why)) {
        std::fprintf(stderr, "render_bench: %s\n", why.c_str());
        return 1;
      }
      view_ms[view == PictureView::kTop].push_back(Ms(start));
    }
    start = Clock::now();
    if (!WritePicturePng(picture, png, &why)) {
      std::fprintf(stderr, "render_bench: %s\n", why.c_str());
      return 1;
    }
    png_ms.push_back(Ms(start));
  }
  std::filesystem::remove(png);
  std::printf("render_bench: %s, %zu structure voxels (%zu occupied leaves), %zu objects, "
              "%dx%d, median of %d runs\n",
              dir.c_str(), scene.structure_W.size(), leaves, scene.objects.size(), config.width,
              config.height, runs);
  std::printf("  stock OctoMap: read map.bt and visit the occupied leaves  %8.1f ms\n", Median(stock_ms));
  std::printf("  read the scene (map.bt to voxels, objects.json, models)  %8.1f ms\n", Median(read_ms));
  std::printf("  render, perspective view                                 %8.1f ms\n", Median(view_ms[0]));
  std::printf("  render, top view                                         %8.1f ms\n", Median(view_ms[1]));
  std::printf("  write the PNG                                            %8.1f ms\n", Median(png_ms));
  std::printf("  total (read, one view, PNG)                              %8.1f ms, %.2f x stock reading\n",
              Median(read_ms) + Median(view_ms[0]) + Median(png_ms),
              (Median(read_ms) + Median(view_ms[0]) + Median(png_ms)) / std::max(1e-9, Median(stock_ms)));
  return 0;
}
