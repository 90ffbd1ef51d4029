// What publishing object models costs per keyframe, with and without resolving the voxels that
// touching objects of one class share (objects.resolve_shared_voxels). A sequence with its
// detections file (a synthetic scene from objmap_sim) is mapped twice, every `step`-th frame a
// keyframe; after each keyframe the objects are published as the server's snapshot does it
// (ObjectMap::ModelKey of every object, ModelPoints of those whose key changed). The keyframe
// itself (segmentation, association, OctoMap) is timed alongside as the baseline.
//   published_model_bench SCENE [step=9]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "detection/detections_file.h"
#include "mapper/mapper.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::bench::Median;

struct Timings {
  std::vector<double> keyframe_ms, publish_ms, points_ms;
  std::size_t published_points = 0;
};

bool Run(const objmap::SequenceReader& reader, objmap::Detector* detector, int step, bool resolve,
         Timings* timings) {
  objmap::MapperConfig config;
  config.objects.resolve_shared_voxels = resolve;
  objmap::Mapper mapper(config);
  std::map<objmap::ObjectId, std::vector<std::pair<objmap::ObjectId, std::uint64_t>>> keys;
  for (std::size_t i = 0; i < reader.size(); i += static_cast<std::size_t>(step)) {
    objmap::RgbdFrame frame;
    std::vector<objmap::Detection> detections;
    std::string why;
    if (!reader.ReadFrame(i, &frame, &why) || !detector->Detect(frame, &detections, &why)) {
      std::fprintf(stderr, "published_model_bench: %s\n", why.c_str());
      return false;
    }
    objmap::KeyframeResult result;
    Clock::time_point start = Clock::now();
    if (!mapper.AddKeyframe(frame, detections, &result, &why)) {
      std::fprintf(stderr, "published_model_bench: %s\n", why.c_str());
      return false;
    }
    timings->keyframe_ms.push_back(Ms(start));
    start = Clock::now();
    std::size_t points = 0;
    double points_ms = 0.0;
    for (const auto& [id, object] : mapper.objects().objects()) {
      auto key = mapper.objects().ModelKey(object);
      if (keys[id] == key) continue;
      const Clock::time_point model_start = Clock::now();
      points += mapper.objects().ModelPoints(object).size();
      points_ms += Ms(model_start);
      keys[id] = std::move(key);
    }
    timings->points_ms.push_back(points_ms);
    timings->publish_ms.push_back(Ms(start));
    timings->published_points += points;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: published_model_bench SCENE [step=9]\n");
    return 2;
  }
  const std::string scene = argv[1];
  const int step = argc > 2 ? std::max(1, std::atoi(argv[2])) : 9;
  std::string why;
  const auto reader = objmap::OpenSequence(scene, &why);
  objmap::DetectionsFileConfig file;
  file.path = scene + "/detections.json";
  auto detector = reader ? objmap::MakeDetectionsFileDetector(file, &why) : nullptr;
  if (!reader || !detector) {
    std::fprintf(stderr, "published_model_bench: %s\n", why.c_str());
    return 1;
  }
  std::printf("%s, every %d-th of %zu frames a keyframe\n\n", scene.c_str(), step, reader->size());
  std::printf(
      "| resolve_shared_voxels | keyframes | keyframe median ms | publish median ms | "
      "of which model points median ms | publish mean ms | publish max ms | points published |\n"
      "|---|---|---|---|---|---|---|---|\n");
  for (const bool resolve : {false, true, false, true}) {
    Timings timings;
    if (!Run(*reader, detector.get(), step, resolve, &timings)) return 1;
    double sum = 0.0;
    for (double ms : timings.publish_ms) sum += ms;
    std::printf("| %s | %zu | %.1f | %.2f | %.2f | %.2f | %.2f | %zu |\n", resolve ? "on" : "off",
                timings.keyframe_ms.size(), Median(timings.keyframe_ms), Median(timings.publish_ms),
                Median(timings.points_ms), sum / static_cast<double>(timings.publish_ms.size()),
                *std::max_element(timings.publish_ms.begin(), timings.publish_ms.end()),
                timings.published_points);
  }
  return 0;
}
