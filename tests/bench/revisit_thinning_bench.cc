// What the revisit test costs (CoverageOf: is a later session's keyframe new, repeated in part
// or whole, or does it show a change?) against what it saves: mapping the keyframe (segmentation,
// association, OctoMap integration; Mapper::AddKeyframe without detections), on real frames.
// Each frame `i` of the list is compared with the frames i-2s, i-s, i+s, i+2s as stored views
// (a revisit passing a few centimetres from where the first session passed); the verdicts show
// what real depth noise leaves of the test's margins.
//
// Usage: revisit_thinning_bench [data_dir] [first=100] [count=10] [frame_step=50] [view_step=5]
//                               [repeats=5]

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "map_server/revisit_thinning.h"
#include "mapper/mapper.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Median;
using objmap::bench::Ms;

}  // namespace

int main(int argc, char** argv) {
  const std::string data_dir = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const int first = argc > 2 ? std::atoi(argv[2]) : 100;
  const int count = argc > 3 ? std::atoi(argv[3]) : 10;
  const int frame_step = argc > 4 ? std::atoi(argv[4]) : 50;
  const int view_step = argc > 5 ? std::atoi(argv[5]) : 5;
  const int repeats = argc > 6 ? std::atoi(argv[6]) : 5;
  std::string why;
  auto reader = objmap::OpenSequence(data_dir, &why);
  if (!reader) {
    std::fprintf(stderr, "revisit_thinning_bench: %s\n", why.c_str());
    return 1;
  }
  const objmap::RevisitThinningConfig config;
  const objmap::MapperConfig mapper_config;
  std::vector<double> test_ms, map_ms;
  std::printf("%6s %10s %10s %12s %10s %10s\n", "frame", "explained", "changed px", "verdict",
              "test ms", "map ms");
  for (int k = 0; k < count; ++k) {
    const int index = first + k * frame_step;
    objmap::RgbdFrame frame;
    std::vector<objmap::RgbdFrame> stored_frames;
    bool ok = reader->ReadFrame(static_cast<std::size_t>(index), &frame, &why);
    for (int offset : {-2 * view_step, -view_step, view_step, 2 * view_step}) {
      stored_frames.emplace_back();
      ok = ok && index + offset >= 0 &&
           reader->ReadFrame(static_cast<std::size_t>(index + offset), &stored_frames.back(), &why);
    }
    if (!ok) {
      std::fprintf(stderr, "revisit_thinning_bench: frame %d: %s\n", index, why.c_str());
      return 1;
    }
    std::vector<objmap::KeyframeRecord> records;
    for (const objmap::RgbdFrame& stored : stored_frames) records.push_back(objmap::RecordOf(stored));
    std::vector<objmap::StoredView> views;
    for (std::size_t i = 0; i < records.size(); ++i) {
      views.push_back({static_cast<std::int64_t>(i + 1), records[i].T_W_C, &records[i].intrinsics,
                       &records[i].depth_mm});
    }
    objmap::ViewCoverage coverage;
    std::vector<double> tests;
    for (int r = 0; r < repeats; ++r) {
      const auto start = Clock::now();
      coverage = objmap::CoverageOf(frame.depth, frame.intrinsics, frame.T_W_C, views, config);
      tests.push_back(Ms(start));
    }
    // The baseline: mapping the frame into a map that holds the stored views.
    std::vector<double> maps;
    for (int r = 0; r < std::max(1, repeats / 2); ++r) {
      objmap::Mapper mapper(mapper_config);
      objmap::KeyframeResult result;
      for (const objmap::RgbdFrame& stored : stored_frames) {
        if (!mapper.AddKeyframe(stored, {}, &result, &why)) return 1;
      }
      const auto start = Clock::now();
      if (!mapper.AddKeyframe(frame, {}, &result, &why)) return 1;
      maps.push_back(Ms(start));
    }
    test_ms.push_back(Median(tests));
    map_ms.push_back(Median(maps));
    const char* verdict = coverage.repeated           ? "repeated"
                          : coverage.repeated_in_part ? "in part"
                                                      : "mapped";
    std::printf("%6d %10.3f %10.0f %12s %10.2f %10.1f\n", index, coverage.explained_fraction,
                coverage.largest_changed_patch_px, verdict, test_ms.back(), map_ms.back());
  }
  const double test = Median(test_ms), map = Median(map_ms);
  std::printf("median: revisit test %.2f ms, mapping the keyframe %.1f ms (%.1fx the test)\n", test,
              map, test > 0 ? map / test : 0.0);
  return 0;
}
