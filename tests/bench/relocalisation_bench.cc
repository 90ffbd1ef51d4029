// Placing a camera in a saved map: RgbdOdometry seeded with a map's keyframes at the sequence's
// own poses (AddMapKeyframe, as MapServer does at a start on a stored map), then asked to track
// one frame from elsewhere, once per start frame. Per start: placed or refused, the time of the
// attempt and, when placed, the error against the sequence's pose (a placement farther than
// 5 cm or 3 degrees is wrong). objmap's relocalisation (the keyframes near the last pose, then
// those the appearance index finds alike) against the plain baseline in the same run: every map
// keyframe tried in turn (relocalisation_keyframes = all, no appearance candidates).
//   relocalisation_bench [sequence=../shared/data/redkitchen] [map_first=0] [map_last=449]
//                        [map_step=15] [start_first=550] [start_last=999] [start_step=25]
//                        [start_sequence=sequence]
// A start_sequence (another recording of the same place in the same world frame: objmap_sim
// --revisit's second session) gives the starts; the map is always made from `sequence`.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "odometry/rgbd_odometry.h"

namespace {

using namespace objmap;

struct Attempt {
  bool placed = false;
  bool wrong = false;
  double ms = 0.0;
  double error_cm = 0.0, error_deg = 0.0;  // placed: against the sequence's pose
};

struct Totals {
  int placed = 0, wrong = 0, refused = 0;
  std::vector<double> placed_ms, refused_ms;
};

double AngleDeg(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
}

// A fresh odometry seeded with the map keyframes, then one Track of `start`.
Attempt Place(const OdometryConfig& config, const std::vector<RgbdFrame>& map,
              const RgbdFrame& start, double* seed_ms) {
  RgbdOdometry odometry{config};
  const auto seed_start = bench::Clock::now();
  for (const RgbdFrame& keyframe : map) {
    std::string why;
    (void)odometry.AddMapKeyframe(keyframe, &why);  // a textureless one is left out, as in use
  }
  *seed_ms = bench::Ms(seed_start);
  const TrackingReport report = odometry.Track(start);
  Attempt attempt;
  attempt.ms = report.ms;
  // A start not placed is kLost or, with provisional fragments, tracked in a frame of its own.
  attempt.placed = report.status != TrackingStatus::kLost && report.fragment == 0;
  if (attempt.placed) {
    const Eigen::Isometry3d error = start.T_W_C.inverse() * report.T_W_C;
    attempt.error_cm = 100.0 * error.translation().norm();
    attempt.error_deg = AngleDeg(error.linear());
    attempt.wrong = attempt.error_cm > 5.0 || attempt.error_deg > 3.0;
  }
  return attempt;
}

void Add(const Attempt& attempt, Totals* totals) {
  if (!attempt.placed) {
    ++totals->refused;
    totals->refused_ms.push_back(attempt.ms);
    return;
  }
  ++totals->placed;
  if (attempt.wrong) ++totals->wrong;
  totals->placed_ms.push_back(attempt.ms);
}

}  // namespace

int main(int argc, char** argv) {
  auto arg = [&](int i, long fallback) { return argc > i ? std::atol(argv[i]) : fallback; };
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const long map_first = arg(2, 0), map_last = arg(3, 449), map_step = arg(4, 15);
  const long start_first = arg(5, 550), start_last = arg(6, 999), start_step = arg(7, 25);
  if (map_step <= 0 || start_step <= 0) {
    std::fprintf(stderr, "relocalisation_bench: steps must be > 0\n");
    return 1;
  }
  const std::string start_path = argc > 8 ? argv[8] : path;
  std::string why;
  auto open = [&](const std::string& sequence) {
    std::unique_ptr<SequenceReader> reader = OpenSequence(sequence, &why);
    if (!reader) {
      std::fprintf(stderr, "relocalisation_bench: %s\n", why.c_str());
      std::exit(1);
    }
    return reader;
  };
  const std::unique_ptr<SequenceReader> map_reader = open(path);
  const std::unique_ptr<SequenceReader> start_reader =
      start_path == path ? nullptr : open(start_path);
  auto read = [&](const SequenceReader& reader, long index, RgbdFrame* frame) {
    if (index < 0 || static_cast<std::size_t>(index) >= reader.size()) return false;
    if (reader.ReadFrame(static_cast<std::size_t>(index), frame, &why)) return true;
    std::fprintf(stderr, "relocalisation_bench: %s\n", why.c_str());
    std::exit(1);
  };
  std::vector<RgbdFrame> map;
  for (long i = map_first; i <= map_last; i += map_step) {
    RgbdFrame frame;
    if (read(*map_reader, i, &frame)) map.push_back(std::move(frame));
  }
  OdometryConfig objmap_config;
  OdometryConfig every_keyframe = objmap_config;
  every_keyframe.relocalisation_keyframes = static_cast<int>(map.size());
  every_keyframe.relocalisation_appearance_candidates = 0;

  Totals objmap_totals, baseline_totals;
  std::vector<double> seed_ms;
  std::printf("map: %zu keyframes (frames %ld..%ld every %ld); starts: frames %ld..%ld every %ld\n",
              map.size(), map_first, map_last, map_step, start_first, start_last, start_step);
  std::printf("%6s  %-38s  %-38s\n", "frame", "objmap", "every keyframe tried");
  for (long i = start_first; i <= start_last; i += start_step) {
    RgbdFrame start;
    if (!read(start_reader ? *start_reader : *map_reader, i, &start)) break;
    double ms = 0.0;
    const Attempt ours = Place(objmap_config, map, start, &ms);
    seed_ms.push_back(ms);
    const Attempt plain = Place(every_keyframe, map, start, &ms);
    Add(ours, &objmap_totals);
    Add(plain, &baseline_totals);
    auto describe = [](const Attempt& a) {
      char text[64];
      if (!a.placed) {
        std::snprintf(text, sizeof(text), "refused %7.1f ms", a.ms);
      } else {
        std::snprintf(text, sizeof(text), "%s %7.1f ms %5.1f cm %4.1f deg",
                      a.wrong ? "WRONG  " : "placed ", a.ms, a.error_cm, a.error_deg);
      }
      return std::string(text);
    };
    std::printf("%6ld  %-38s  %-38s\n", i, describe(ours).c_str(), describe(plain).c_str());
  }
  auto summary = [](const char* name, const Totals& t) {
    std::printf("%-22s placed %d (wrong %d), refused %d; median ms placed %.1f, refused %.1f\n",
                name, t.placed, t.wrong, t.refused, bench::Median(t.placed_ms),
                bench::Median(t.refused_ms));
  };
  summary("objmap", objmap_totals);
  summary("every keyframe tried", baseline_totals);
  std::printf("seeding the map's %zu keyframes: median %.1f ms (%.2f ms per keyframe)\n",
              map.size(), bench::Median(seed_ms),
              map.empty() ? 0.0 : bench::Median(seed_ms) / static_cast<double>(map.size()));
  const double ours_ms = bench::Median(objmap_totals.placed_ms);
  if (ours_ms > 0.0) {
    std::printf("placement: every keyframe tried / objmap = %.2fx (median ms of placed starts)\n",
                bench::Median(baseline_totals.placed_ms) / ours_ms);
  }
  return objmap_totals.wrong == 0 ? 0 : 2;
}
