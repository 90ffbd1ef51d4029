#include "evaluation/change_evaluation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "types/coco_classes.h"

namespace objmap {
namespace {

// A possible match: a real change and a report, and how far apart they are.
struct Candidate {
  double distance_m = 0.0;
  std::size_t real = 0;
  std::size_t report = 0;
};

double MatchDistance(const GroundTruthChange& real, const ChangeEvaluationConfig& config) {
  return std::max(config.min_match_distance_m, config.size_share * real.largest_size_m);
}

// How far a report lies from a real change of its kind: for a move, the worse of its two places,
// since a move is right only when both are.
double Distance(const GroundTruthChange& real, const ReportedChange& report) {
  const double now = (real.position_W - report.position_W).norm();
  if (real.kind != ChangeKind::kMoved) return now;
  return std::max(now, (real.from_W - report.from_W).norm());
}

bool Unseen(const GroundTruthChange& change, const ChangeEvaluationConfig& config) {
  return change.visible_frames >= 0 && change.visible_frames < config.min_visible_frames;
}

// Greedy one-to-one matching, nearest pairs first: `matched_report[r]` is the report index that
// matched real change `real[r]`, or reports.size() when none did.
std::vector<std::size_t> MatchNearestFirst(const std::vector<const GroundTruthChange*>& real,
                                           const std::vector<const ReportedChange*>& reports,
                                           const ChangeEvaluationConfig& config) {
  std::vector<Candidate> candidates;
  for (std::size_t r = 0; r < real.size(); ++r) {
    for (std::size_t p = 0; p < reports.size(); ++p) {
      if (reports[p]->class_id != real[r]->class_id) continue;
      const double distance = Distance(*real[r], *reports[p]);
      if (distance <= MatchDistance(*real[r], config)) candidates.push_back({distance, r, p});
    }
  }
  // Ties broken by file order, so that the result does not depend on the sort's whims.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.distance_m, a.real, a.report) < std::tie(b.distance_m, b.real, b.report);
  });
  std::vector<std::size_t> matched_report(real.size(), reports.size());
  std::vector<bool> report_taken(reports.size(), false);
  for (const Candidate& c : candidates) {
    if (matched_report[c.real] != reports.size() || report_taken[c.report]) continue;
    matched_report[c.real] = c.report;
    report_taken[c.report] = true;
  }
  return matched_report;
}

// The reports of one kind that matched nothing: where to look for moves reported as a removal
// and an addition.
using Leftovers = std::vector<const ReportedChange*>;

// Takes the nearest leftover report of `class_id` within `reach_m` of `place_W` out of `left`;
// false when there is none.
bool TakeNearest(int class_id, const Eigen::Vector3d& place_W, double reach_m, Leftovers* left) {
  auto best = left->end();
  double best_distance = reach_m;
  for (auto it = left->begin(); it != left->end(); ++it) {
    const double distance = ((*it)->position_W - place_W).norm();
    if ((*it)->class_id == class_id && distance <= best_distance) {
      best_distance = distance;
      best = it;
    }
  }
  if (best == left->end()) return false;
  left->erase(best);
  return true;
}

}  // namespace

std::string_view ChangeKindName(ChangeKind kind) {
  switch (kind) {
    case ChangeKind::kRemoved:
      return "removed";
    case ChangeKind::kMoved:
      return "moved";
    case ChangeKind::kAdded:
      return "added";
  }
  return "";
}

bool ChangeEvaluationConfig::IsValid(std::string* why) const {
  if (!(min_match_distance_m > 0.0) || !std::isfinite(min_match_distance_m)) {
    *why = "ChangeEvaluationConfig: min_match_distance_m must be finite and > 0";
    return false;
  }
  if (!(size_share >= 0.0) || !std::isfinite(size_share)) {
    *why = "ChangeEvaluationConfig: size_share must be finite and >= 0";
    return false;
  }
  if (min_session_id < 0) {
    *why = "ChangeEvaluationConfig: min_session_id must be >= 0 (0: every session)";
    return false;
  }
  if (min_visible_frames < 0) {
    *why = "ChangeEvaluationConfig: min_visible_frames must be >= 0";
    return false;
  }
  return true;
}

double ChangeCounts::Precision() const {
  const int claims = true_positives + false_positives;
  return claims == 0 ? 1.0 : static_cast<double>(true_positives) / claims;
}

double ChangeCounts::Recall() const {
  return real == 0 ? 1.0 : static_cast<double>(true_positives) / real;
}

void ChangeCounts::Add(const ChangeCounts& other) {
  real += other.real;
  reported += other.reported;
  true_positives += other.true_positives;
  false_positives += other.false_positives;
  misses += other.misses;
  unseen += other.unseen;
  unknown_class += other.unknown_class;
}

std::vector<int> AttachGroundTruthSizes(const std::vector<GroundTruthObject>& before,
                                        const std::vector<GroundTruthObject>& after,
                                        std::vector<GroundTruthChange>* changes) {
  std::map<int, const GroundTruthObject*> before_by_id, after_by_id;
  for (const GroundTruthObject& object : before) before_by_id[object.id] = &object;
  for (const GroundTruthObject& object : after) after_by_id[object.id] = &object;
  std::vector<int> not_found;
  for (GroundTruthChange& change : *changes) {
    // Removed objects exist only before the change, added ones only after; moved ones in both.
    const bool was_there = change.kind != ChangeKind::kAdded;
    const bool is_there = change.kind != ChangeKind::kRemoved;
    const auto old_it = before_by_id.find(change.id);
    const auto new_it = after_by_id.find(change.id);
    const bool old_found = old_it != before_by_id.end();
    const bool new_found = new_it != after_by_id.end();
    if ((was_there && !before.empty() && !old_found) ||
        (is_there && !after.empty() && !new_found)) {
      not_found.push_back(change.id);
    }
    const GroundTruthObject* object = nullptr;
    if (is_there && new_found) {
      object = new_it->second;
      change.visible_frames = object->visible_frames;
    } else if (was_there && old_found) {
      object = old_it->second;
    }
    if (object != nullptr) change.largest_size_m = object->size_m.maxCoeff();
  }
  return not_found;
}

ChangeEvaluation EvaluateChanges(const std::vector<GroundTruthChange>& real,
                                 const std::vector<ReportedChange>& reported,
                                 const std::vector<MappedObject>* present,
                                 const ChangeEvaluationConfig& config) {
  std::set<ObjectId> present_ids;
  if (present != nullptr) {
    for (const MappedObject& object : *present) present_ids.insert(object.id);
  }
  ChangeEvaluation result;
  std::array<Leftovers, kNumChangeKinds> left;
  std::vector<const GroundTruthChange*> missed_moves;
  for (ChangeKind kind : kChangeKinds) {
    ChangeCounts& counts = result.per_kind[static_cast<int>(kind)];
    std::vector<const GroundTruthChange*> kind_real;
    for (const GroundTruthChange& change : real) {
      if (change.kind != kind) continue;
      if (Unseen(change, config)) {
        ++counts.unseen;
      } else {
        kind_real.push_back(&change);
      }
    }
    std::vector<const ReportedChange*> kind_reports;
    for (const ReportedChange& report : reported) {
      if (report.kind != kind) continue;
      if (config.min_session_id > 0 && report.session_id < config.min_session_id) continue;
      if (report.class_id == kUnknownClassId) {
        ++counts.unknown_class;
      } else {
        kind_reports.push_back(&report);
      }
    }
    counts.real = static_cast<int>(kind_real.size());
    counts.reported = static_cast<int>(kind_reports.size());
    const std::vector<std::size_t> matched = MatchNearestFirst(kind_real, kind_reports, config);
    std::vector<bool> report_used(kind_reports.size(), false);
    for (std::size_t r = 0; r < kind_real.size(); ++r) {
      if (matched[r] == kind_reports.size()) {
        ++counts.misses;
        if (kind == ChangeKind::kMoved) missed_moves.push_back(kind_real[r]);
        continue;
      }
      ++counts.true_positives;
      report_used[matched[r]] = true;
      ChangeMatch match;
      match.kind = kind;
      match.real_id = kind_real[r]->id;
      match.object_id = kind_reports[matched[r]]->object_id;
      match.kept_id = kind == ChangeKind::kMoved &&
                      (present == nullptr || present_ids.count(match.object_id) > 0);
      if (match.kept_id) ++result.moved_kept_id;
      result.matches.push_back(match);
    }
    for (std::size_t p = 0; p < kind_reports.size(); ++p) {
      if (!report_used[p]) left[static_cast<int>(kind)].push_back(kind_reports[p]);
    }
    counts.false_positives = counts.reported - counts.true_positives;
    result.totals.Add(counts);
  }
  result.moved_total = result.Of(ChangeKind::kMoved).real;
  // Each leftover report explains at most one missed move, and stays a false positive.
  for (const GroundTruthChange* move : missed_moves) {
    Leftovers& removals = left[static_cast<int>(ChangeKind::kRemoved)];
    Leftovers& additions = left[static_cast<int>(ChangeKind::kAdded)];
    const double reach_m = MatchDistance(*move, config);
    Leftovers removals_tried = removals;
    if (TakeNearest(move->class_id, move->from_W, reach_m, &removals_tried) &&
        TakeNearest(move->class_id, move->position_W, reach_m, &additions)) {
      removals = std::move(removals_tried);
      ++result.moved_as_removed_and_added;
    }
  }
  return result;
}

}  // namespace objmap
