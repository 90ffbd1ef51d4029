// Sessions that start anywhere, placed in a saved map: RgbdOdometry seeded with the map's
// keyframes (AddMapKeyframe, as MapServer does at a start on a stored map) tracks a short
// session of another recording of the same place, from each of several starting frames. Until a
// frame is placed the session is tracked in a provisional fragment; the frame that places it
// attaches the fragment. Per session: the frames until it was placed, the time spent, and the
// error of every keyframe in the map's frame against the recording's pose (a keyframe farther
// than 5 cm or 3 degrees: a wrong placement). Sessions of recordings of other places (`foreign`,
// a room the map does not hold) must never be placed.
//   session_placement_bench MAP_SEQUENCE SESSION_SEQUENCE [sessions=5] [frames=60] [step=2]
//                           [map_step=10] [FOREIGN_SEQUENCE ...]
// The map is every map_step-th frame of MAP_SEQUENCE at its poses; each session tracks `frames`
// frames, every step-th, from starts spread evenly over SESSION_SEQUENCE (which must share the
// map's world frame: objmap_sim --revisit's second session). Exit status 2 when a session is
// placed wrongly or a foreign one is placed at all.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "odometry/rgbd_odometry.h"

namespace {

using namespace objmap;

double AngleDeg(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
}

struct SessionResult {
  bool placed = false;
  bool wrong = false;
  int frames_to_place = 0;   // frames tracked before (and with) the one that placed it
  int fragments = 0;         // provisional fragments started
  double ms_to_place = 0.0;  // tracking time until placed
  double worst_cm = 0.0, worst_deg = 0.0;  // over the keyframes in the map's frame
  int keyframes_in_map = 0, keyframes_apart = 0;
};

std::unique_ptr<SequenceReader> Open(const std::string& path) {
  std::string why;
  std::unique_ptr<SequenceReader> reader = OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "session_placement_bench: %s\n", why.c_str());
    std::exit(1);
  }
  return reader;
}

RgbdFrame Read(const SequenceReader& reader, std::size_t index) {
  RgbdFrame frame;
  std::string why;
  if (!reader.ReadFrame(index, &frame, &why)) {
    std::fprintf(stderr, "session_placement_bench: %s\n", why.c_str());
    std::exit(1);
  }
  return frame;
}

SessionResult RunSession(const std::vector<RgbdFrame>& map, const SequenceReader& session,
                         std::size_t first, int frames, int step, bool foreign) {
  RgbdOdometry odometry{OdometryConfig{}};
  for (const RgbdFrame& keyframe : map) {
    std::string why;
    (void)odometry.AddMapKeyframe(keyframe, &why);
  }
  const int map_keyframes = odometry.num_keyframes();
  SessionResult result;
  // The recording's pose of each keyframe the session made, to score them once placed.
  std::vector<Eigen::Isometry3d> truth;
  for (int i = 0; i < frames; ++i) {
    const std::size_t index = first + static_cast<std::size_t>(i * step);
    if (index >= session.size()) break;
    const RgbdFrame frame = Read(session, index);
    const TrackingReport report = odometry.Track(frame);
    if (!result.placed) {
      ++result.frames_to_place;
      result.ms_to_place += report.ms;
    }
    if (report.new_keyframe) truth.push_back(frame.T_W_C);
    if (report.status != TrackingStatus::kLost && report.fragment == 0) result.placed = true;
  }
  result.fragments = odometry.fragments_started();
  for (int k = map_keyframes; k < odometry.num_keyframes(); ++k) {
    if (odometry.KeyframeFragment(k) != 0) {
      ++result.keyframes_apart;
      continue;
    }
    ++result.keyframes_in_map;
    const Eigen::Isometry3d error =
        truth[static_cast<std::size_t>(k - map_keyframes)].inverse() * odometry.KeyframePose(k);
    result.worst_cm = std::max(result.worst_cm, 100.0 * error.translation().norm());
    result.worst_deg = std::max(result.worst_deg, AngleDeg(error.linear()));
  }
  result.wrong = result.placed && (foreign || result.worst_cm > 5.0 || result.worst_deg > 3.0);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: session_placement_bench MAP_SEQUENCE SESSION_SEQUENCE [sessions=5] "
                 "[frames=60] [step=2] [map_step=10] [FOREIGN_SEQUENCE ...]\n");
    return 1;
  }
  auto arg = [&](int i, long fallback) { return argc > i ? std::atol(argv[i]) : fallback; };
  const long sessions = arg(3, 5), frames = arg(4, 60), step = arg(5, 2), map_step = arg(6, 10);
  if (sessions <= 0 || frames <= 0 || step <= 0 || map_step <= 0) {
    std::fprintf(stderr, "session_placement_bench: counts and steps must be > 0\n");
    return 1;
  }
  const std::unique_ptr<SequenceReader> map_reader = Open(argv[1]);
  std::vector<RgbdFrame> map;
  for (std::size_t i = 0; i < map_reader->size(); i += static_cast<std::size_t>(map_step)) {
    map.push_back(Read(*map_reader, i));
  }
  std::vector<std::pair<std::string, bool>> recordings{{argv[2], false}};
  for (int i = 7; i < argc; ++i) recordings.emplace_back(argv[i], true);

  int placed = 0, wrong = 0, total = 0, foreign_total = 0, foreign_placed = 0;
  std::vector<double> ms_to_place, frames_to_place;
  std::printf("map: %zu keyframes of %s\n", map.size(), argv[1]);
  std::printf("%-40s %6s  %-8s %7s %9s %5s %9s %9s\n", "session", "start", "result", "frames", "ms",
              "frags", "worst cm", "worst deg");
  for (const auto& [path, foreign] : recordings) {
    const std::unique_ptr<SequenceReader> reader = Open(path);
    const std::size_t span = static_cast<std::size_t>(frames * step);
    const std::size_t room = reader->size() > span ? reader->size() - span : 1;
    for (long s = 0; s < sessions; ++s) {
      const std::size_t first =
          room * static_cast<std::size_t>(s) / static_cast<std::size_t>(sessions);
      const SessionResult r = RunSession(map, *reader, first, static_cast<int>(frames),
                                         static_cast<int>(step), foreign);
      const char* verdict = r.wrong ? "WRONG" : r.placed ? "placed" : "apart";
      std::printf("%-40s %6zu  %-8s %7d %9.1f %5d %9.2f %9.2f\n",
                  (path.size() > 40 ? path.substr(path.size() - 40) : path).c_str(), first, verdict,
                  r.frames_to_place, r.ms_to_place, r.fragments, r.worst_cm, r.worst_deg);
      if (foreign) {
        ++foreign_total;
        foreign_placed += r.placed;
        wrong += r.wrong;
        continue;
      }
      ++total;
      placed += r.placed;
      wrong += r.wrong;
      if (r.placed) {
        ms_to_place.push_back(r.ms_to_place);
        frames_to_place.push_back(r.frames_to_place);
      }
    }
  }
  std::printf(
      "sessions of the mapped place: %d, placed %d (wrong %d); frames to place median %.0f, "
      "time to place median %.1f ms\n",
      total, placed, wrong - foreign_placed, bench::Median(frames_to_place),
      bench::Median(ms_to_place));
  std::printf("sessions of other places: %d, placed (wrongly) %d\n", foreign_total, foreign_placed);
  return wrong == 0 ? 0 : 2;
}
