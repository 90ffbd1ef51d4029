// The web viewer's answers on a map folder, through HTTP on 127.0.0.1 as a page loads them:
// opening the folder, /api/map, /api/structure (the default 600k points), every inventory
// object's model, one keyframe crop, and the whole first load (map, structure, models); next to
// stock OctoMap reading the same map.bt and visiting its occupied leaves, the least any view of
// the structure costs.
//   viewer_bench <map-dir> [runs=5] [viewer-folder]
#include <octomap/octomap.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "http_viewer/http_viewer.h"
#include "http_viewer/viewer_map.h"

// Last: it includes <resolv.h>, whose _res macro breaks Eigen headers included after it.
#include <httplib.h>

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::bench::Median;

// GET `path`; its size in bytes, or -1 (with a message) when it failed.
long long Fetch(httplib::Client& client, const std::string& path, std::string* body = nullptr) {
  auto result = client.Get(path.c_str());
  if (!result || result->status != 200) {
    std::fprintf(stderr, "viewer_bench: %s failed\n", path.c_str());
    return -1;
  }
  if (body != nullptr) *body = result->body;
  return static_cast<long long>(result->body.size());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace objmap;
  if (argc < 2) {
    std::fprintf(stderr, "usage: viewer_bench <map-dir> [runs] [viewer-folder]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  std::string why;
  http_viewer::HttpViewerConfig config;
  config.listen_address = "127.0.0.1:0";
  if (!http_viewer::FindViewerFolder(argc > 3 ? argv[3] : "", &config.viewer_folder, &why)) {
    std::fprintf(stderr, "viewer_bench: %s\n", why.c_str());
    return 1;
  }
  std::vector<double> stock_ms, open_ms, map_ms, structure_ms, models_ms, crop_ms, load_ms;
  long long structure_bytes = 0, model_bytes = 0;
  std::size_t leaves = 0, models = 0;
  for (int run = 0; run < runs; ++run) {
    auto start = Clock::now();
    octomap::OcTree tree((dir + "/map.bt").c_str());
    leaves = 0;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) leaves += tree.isNodeOccupied(*it);
    stock_ms.push_back(Ms(start));

    start = Clock::now();
    auto map = http_viewer::FolderViewerMap::Open(dir, &why);
    if (!map) {
      std::fprintf(stderr, "viewer_bench: %s\n", why.c_str());
      return 1;
    }
    open_ms.push_back(Ms(start));
    auto viewer = http_viewer::HttpViewer::Start(config, *map, &why);
    if (!viewer) {
      std::fprintf(stderr, "viewer_bench: %s\n", why.c_str());
      return 1;
    }
    httplib::Client client("127.0.0.1", viewer->port());
    const auto load_start = Clock::now();
    std::string body;
    start = Clock::now();
    if (Fetch(client, "/api/map", &body) < 0) return 1;
    map_ms.push_back(Ms(start));
    start = Clock::now();
    structure_bytes = Fetch(client, "/api/structure");
    if (structure_bytes < 0) return 1;
    structure_ms.push_back(Ms(start));
    const nlohmann::json answer = nlohmann::json::parse(body);
    start = Clock::now();
    model_bytes = 0;
    models = 0;
    std::string first_crop;
    for (const nlohmann::json& object : answer["objects"]) {
      if (!object["in_inventory"].get<bool>()) continue;
      const long long bytes = Fetch(client, "/api/objects/" + object["id"].dump() + "/model");
      if (bytes < 0) return 1;
      model_bytes += bytes;
      ++models;
      if (first_crop.empty()) {
        std::string detail;
        if (Fetch(client, "/api/objects/" + object["id"].dump(), &detail) < 0) return 1;
        const auto sightings = nlohmann::json::parse(detail)["sightings"];
        if (!sightings.empty()) first_crop = sightings[0]["image"].get<std::string>();
      }
    }
    models_ms.push_back(Ms(start));
    load_ms.push_back(Ms(load_start));
    if (!first_crop.empty()) {
      start = Clock::now();
      if (Fetch(client, first_crop) < 0) return 1;
      crop_ms.push_back(Ms(start));
    }
  }
  std::printf("map folder %s, %d runs (medians)\n", dir.c_str(), runs);
  std::printf("  stock OctoMap: read map.bt + visit %zu occupied leaves   %8.1f ms\n", leaves,
              Median(stock_ms));
  std::printf("  open the folder (map.bt, objects.json, models)          %8.1f ms\n",
              Median(open_ms));
  std::printf("  GET /api/map                                             %8.1f ms\n",
              Median(map_ms));
  std::printf("  GET /api/structure (%lld points)                     %8.1f ms  (%.1f MB)\n",
              structure_bytes / 12, Median(structure_ms), structure_bytes / 1e6);
  std::printf("  GET %zu inventory models                                  %8.1f ms  (%.2f MB)\n",
              models, Median(models_ms), model_bytes / 1e6);
  std::printf("  GET one keyframe crop                                    %8.1f ms\n",
              Median(crop_ms));
  std::printf("  a page's first load (map + structure + details + models) %8.1f ms\n",
              Median(load_ms));
  return 0;
}
