// Data association on real redkitchen object models and segments, with the paper's test (a k-d
// tree over the object's points built for the pair, every segment point queried at 2 cm) as the
// baseline on the same pairs.
//   association_bench [sequence=../shared/data/redkitchen] [frames=700] [repeats=3]
// First the real pipeline (CenterNet, segmentation, Mapper) maps `frames` frames; its per-keyframe
// association stage time is the pipeline figure. Then the observations the Mapper stored are
// replayed keyframe by keyframe, as Mapper::UpdatePoses re-associates them, `repeats` times; for
// every class-compatible candidate pair of every keyframe both tests run, before the keyframe
// joins the replayed map. Decisions (>= 50 % of the points within 2 cm) must agree.
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "association/associator.h"
#include "dataset/sequence_reader.h"
#include "detection/centernet_detector.h"
#include "pipeline/sequence_runner.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::ObjectId;

double Percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1));
  return values[index];
}

struct KeyframeInput {
  Eigen::Isometry3d T_W_C;
  std::vector<objmap::ObjectObservation> observations;
};

std::vector<Eigen::Vector3f> ToWorld(const std::vector<Eigen::Vector3f>& points_C,
                                     const Eigen::Isometry3d& T_W_C) {
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  std::vector<Eigen::Vector3f> points_W;
  points_W.reserve(points_C.size());
  for (const Eigen::Vector3f& p : points_C) points_W.push_back(T * p);
  return points_W;
}

// The stored observations grouped by keyframe with the keyframe's pose, in keyframe order.
std::vector<KeyframeInput> KeyframesOf(const objmap::Mapper& mapper) {
  std::map<objmap::KeyframeId, KeyframeInput> by_keyframe;
  for (const auto& [id, object] : mapper.objects().objects()) {
    for (const objmap::ObjectObservation& observation : object.observations) {
      const objmap::KeyframeRecord* record = mapper.FindKeyframe(observation.keyframe_id);
      if (record == nullptr) continue;
      KeyframeInput& input = by_keyframe[observation.keyframe_id];
      input.T_W_C = record->T_W_C;
      input.observations.push_back(observation);
    }
  }
  std::vector<KeyframeInput> keyframes;
  for (auto& [id, input] : by_keyframe) keyframes.push_back(std::move(input));
  return keyframes;
}

// The paper's test for one pair: a k-d tree over the object's points, every segment point
// queried for its nearest neighbour. Returns the number of segment points within `distance_m`.
std::size_t KdTreeMatches(const std::vector<Eigen::Vector3f>& object_points,
                          const std::vector<Eigen::Vector3f>& segment_points, float distance_m) {
  if (object_points.empty()) return 0;
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->reserve(object_points.size());
  for (const Eigen::Vector3f& p : object_points) cloud->push_back({p.x(), p.y(), p.z()});
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  std::vector<int> index(1);
  std::vector<float> distance_sq(1);
  std::size_t matched = 0;
  for (const Eigen::Vector3f& p : segment_points) {
    if (tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, distance_sq) > 0 &&
        distance_sq[0] <= distance_m * distance_m) {
      ++matched;
    }
  }
  return matched;
}

struct PairFigures {
  std::vector<double> objmap_ms, objmap_cached_ms, objmap_sampled_ms, baseline_ms;
  std::size_t unstable = 0;  ///< pairs whose second test gave another fraction (must be 0)
  std::size_t disagreements = 0, sampled_disagreements = 0, count_mismatches = 0, joins = 0;
};

// Both tests on every class-compatible candidate pair of one keyframe's segments.
void MeasurePairs(const objmap::ObjectMap& map,
                  const std::vector<objmap::SegmentToAssociate>& segments,
                  objmap::Associator* every_point, objmap::Associator* sampled,
                  PairFigures* figures) {
  const float distance_m = every_point->config().match_distance_m;
  const float min_fraction = every_point->config().min_match_fraction;
  for (const objmap::SegmentToAssociate& segment : segments) {
    for (ObjectId id : every_point->Candidates(map, segment.points_W)) {
      const objmap::MapObject& object = *map.Find(id);
      if (!every_point->ClassCompatible(object, segment.class_id)) continue;
      auto start = Clock::now();
      const float fraction = every_point->MatchFraction(object, segment.points_W);
      figures->objmap_ms.push_back(Ms(start));
      // Again, now that the object's search structure is certainly cached: the query alone.
      start = Clock::now();
      if (every_point->MatchFraction(object, segment.points_W) != fraction) ++figures->unstable;
      figures->objmap_cached_ms.push_back(Ms(start));
      start = Clock::now();
      const float sampled_fraction = sampled->MatchFraction(object, segment.points_W);
      figures->objmap_sampled_ms.push_back(Ms(start));
      const std::vector<Eigen::Vector3f> object_points = object.model_W.Points().points;
      start = Clock::now();
      const std::size_t matched = KdTreeMatches(object_points, segment.points_W, distance_m);
      figures->baseline_ms.push_back(Ms(start));
      const float baseline_fraction =
          static_cast<float>(matched) / static_cast<float>(segment.points_W.size());
      const bool baseline_joins = baseline_fraction >= min_fraction;
      figures->joins += baseline_joins ? 1 : 0;
      if (fraction != baseline_fraction) ++figures->count_mismatches;
      if ((fraction >= min_fraction) != baseline_joins) {
        ++figures->disagreements;
        std::printf(
            "  disagreement: object %llu (%zu points), segment of %zu: objmap %.4f, "
            "k-d tree %.4f\n",
            static_cast<unsigned long long>(id), object_points.size(), segment.points_W.size(),
            fraction, baseline_fraction);
      }
      if ((sampled_fraction >= min_fraction) != baseline_joins) ++figures->sampled_disagreements;
    }
  }
}

// Per keyframe: the whole association stage and its three parts.
struct StageFigures {
  std::vector<double> total_ms, assign_ms, update_ms, duplicates_ms;
};

// The Mapper's association stage for one keyframe: assignment, model update, duplicate merging.
void AssociateAndMerge(objmap::ObjectMap* map, objmap::Associator* associator,
                       const std::vector<objmap::SegmentToAssociate>& segments,
                       std::vector<objmap::ObjectObservation> observations,
                       const Eigen::Isometry3d& T_W_C, StageFigures* figures) {
  const auto start = Clock::now();
  const auto assignment = associator->AssignKeyframe(*map, segments);
  figures->assign_ms.push_back(Ms(start));
  const auto update_start = Clock::now();
  std::vector<ObjectId> touched;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (assignment[s]) {
      map->AddObservation(*assignment[s], std::move(observations[s]), T_W_C);
      touched.push_back(*assignment[s]);
    } else {
      touched.push_back(map->AddObject(std::move(observations[s]), T_W_C));
    }
  }
  figures->update_ms.push_back(Ms(update_start));
  const auto duplicates_start = Clock::now();
  bool merged = false;
  for (const auto& [kept, absorbed] : associator->FindDuplicates(*map, touched)) {
    merged = map->Merge(kept, absorbed) || merged;
  }
  if (merged) associator->ForgetMissing(*map);
  figures->duplicates_ms.push_back(Ms(duplicates_start));
  figures->total_ms.push_back(Ms(start));
}

// One replay of all keyframes; returns the objects it ends with.
std::size_t Replay(const std::vector<KeyframeInput>& keyframes, PairFigures* pairs,
                   StageFigures* stage_figures) {
  objmap::AssociationConfig every_point_config;
  every_point_config.max_test_points = INT_MAX;  // the paper tests every point
  objmap::Associator every_point(every_point_config);
  objmap::Associator sampled{objmap::AssociationConfig{}};
  objmap::Associator stage{objmap::AssociationConfig{}};
  objmap::ObjectMap map;
  for (const KeyframeInput& keyframe : keyframes) {
    std::vector<objmap::SegmentToAssociate> segments;
    for (const objmap::ObjectObservation& observation : keyframe.observations) {
      segments.push_back({ToWorld(observation.segment_C.points, keyframe.T_W_C),
                          observation.class_scores.front().first});
    }
    MeasurePairs(map, segments, &every_point, &sampled, pairs);
    AssociateAndMerge(&map, &stage, segments, keyframe.observations, keyframe.T_W_C, stage_figures);
  }
  return map.size();
}

void PrintRow(const char* name, const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  std::printf("%-58s %9.3f %9.3f %9.3f\n", name, Percentile(values, 0.5), Percentile(values, 0.9),
              values.empty() ? 0.0 : sum / static_cast<double>(values.size()));
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const int frames = argc > 2 ? std::atoi(argv[2]) : 700;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  std::string why;
  auto reader = objmap::OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "association_bench: %s\n", why.c_str());
    return 1;
  }
  objmap::CenterNetConfig detector_config;
  detector_config.model_path = OBJMAP_DEFAULT_MODEL_PATH;
  auto detector = objmap::MakeCenterNetDetector(detector_config, &why);
  if (!detector) {
    std::fprintf(stderr, "association_bench: %s\n", why.c_str());
    return 1;
  }
  const objmap::MapperConfig mapper_config;
  objmap::Mapper mapper{mapper_config};
  objmap::SequenceRunConfig run_config;
  run_config.max_frames = static_cast<std::size_t>(frames);
  objmap::SequenceRunReport report;
  if (!objmap::RunSequence(*reader, detector.get(), &mapper, run_config, nullptr, &report, &why)) {
    std::fprintf(stderr, "association_bench: %s\n", why.c_str());
    return 1;
  }
  std::vector<double> pipeline_stage_ms;
  for (const objmap::KeyframeReport& keyframe : report.keyframes) {
    pipeline_stage_ms.push_back(keyframe.result.timings.association_ms);
  }
  const std::vector<KeyframeInput> keyframes = KeyframesOf(mapper);
  std::size_t segments = 0;
  for (const KeyframeInput& keyframe : keyframes) segments += keyframe.observations.size();
  std::printf("%zu frames read, %zu keyframes, %zu segments, %zu objects in the pipeline's map\n",
              report.frames_read, report.keyframes.size(), segments, mapper.objects().size());

  PairFigures pairs;
  StageFigures stage;
  std::size_t replay_objects = 0;
  for (int r = 0; r < repeats; ++r) replay_objects = Replay(keyframes, &pairs, &stage);
  const double objmap_median = Percentile(pairs.objmap_ms, 0.5);
  const double baseline_median = Percentile(pairs.baseline_ms, 0.5);
  std::printf(
      "\n%zu pair tests (%d replays), %zu of them joins by the k-d tree; replay ends with "
      "%zu objects\n",
      pairs.baseline_ms.size(), repeats, pairs.joins, replay_objects);
  std::printf("%-58s %9s %9s %9s\n", "ms", "median", "p90", "mean");
  PrintRow("per pair: objmap MatchFraction, every point", pairs.objmap_ms);
  PrintRow("  the same pair again (search structure cached)", pairs.objmap_cached_ms);
  PrintRow("per pair: objmap MatchFraction, default 1000-point sample", pairs.objmap_sampled_ms);
  PrintRow("per pair: k-d tree built for the pair, every point", pairs.baseline_ms);
  std::printf("ratio k-d tree / objmap (every point), medians: %.1fx\n",
              objmap_median > 0.0 ? baseline_median / objmap_median : 0.0);
  std::printf(
      "decision disagreements, objmap every point vs k-d tree: %zu (fractions differing: "
      "%zu)\n",
      pairs.disagreements, pairs.count_mismatches);
  std::printf("decision disagreements, objmap 1000-point sample vs k-d tree: %zu\n",
              pairs.sampled_disagreements);
  PrintRow("per keyframe: association stage, replay", stage.total_ms);
  PrintRow("  of which AssignKeyframe", stage.assign_ms);
  PrintRow("  of which model update (AddObservation, AddObject)", stage.update_ms);
  PrintRow("  of which FindDuplicates and Merge", stage.duplicates_ms);
  PrintRow("per keyframe: association stage, pipeline (Mapper timings)", pipeline_stage_ms);
  return 0;
}
