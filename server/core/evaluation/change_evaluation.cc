#include "evaluation/change_evaluation.h"

#include <algorithm>
#include <cmath>
#include <functional>
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

// Scores the reports against the real changes as they are written (EvaluateChanges without the
// look-alike readings).
ChangeEvaluation EvaluateAsWritten(const std::vector<GroundTruthChange>& real,
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

// A place a group of look-alikes emptied (a removal, a move's old place) or filled (an addition, a
// move's new place), and the real change it comes from.
struct Place {
  Eigen::Vector3d position_W;
  const GroundTruthChange* source = nullptr;
};

// The real changes of one group of look-alike objects, as the places they emptied and filled.
struct LookAlikeGroup {
  std::vector<Place> emptied, filled;
  int moves_as_written = 0;
};

// Groups of two or more real changes of look-alike objects (GroundTruthChange::LookAlike).
std::vector<LookAlikeGroup> LookAlikeGroups(const std::vector<GroundTruthChange>& real,
                                            std::vector<bool>* grouped) {
  const std::size_t n = real.size();
  std::vector<std::size_t> group_of(n);
  for (std::size_t i = 0; i < n; ++i) {
    group_of[i] = i;
    for (std::size_t j = 0; j < i; ++j) {
      if (LookAlike(real[i], real[j])) {
        group_of[i] = group_of[j];
        break;
      }
    }
  }
  std::map<std::size_t, std::vector<std::size_t>> members;
  for (std::size_t i = 0; i < n; ++i) members[group_of[i]].push_back(i);
  std::vector<LookAlikeGroup> groups;
  grouped->assign(n, false);
  for (const auto& [first, indices] : members) {
    if (indices.size() < 2) continue;
    LookAlikeGroup group;
    for (std::size_t i : indices) {
      const GroundTruthChange& change = real[i];
      (*grouped)[i] = true;
      if (change.kind == ChangeKind::kRemoved)
        group.emptied.push_back({change.position_W, &change});
      if (change.kind == ChangeKind::kAdded) group.filled.push_back({change.position_W, &change});
      if (change.kind == ChangeKind::kMoved) {
        group.emptied.push_back({change.from_W, &change});
        group.filled.push_back({change.position_W, &change});
        ++group.moves_as_written;
      }
    }
    groups.push_back(std::move(group));
  }
  return groups;
}

// One reading of a group: which filled place each emptied place moved to (filled.size(): none).
using Reading = std::vector<std::size_t>;

// Every reading of `group` with at least as many moves as its ground truth writes, the reading as
// written first.
std::vector<Reading> ReadingsOf(const LookAlikeGroup& group) {
  const std::size_t none = group.filled.size();
  std::vector<Reading> readings;
  Reading as_written(group.emptied.size(), none);
  for (std::size_t e = 0; e < group.emptied.size(); ++e) {
    for (std::size_t f = 0; f < group.filled.size(); ++f) {
      if (group.emptied[e].source == group.filled[f].source) as_written[e] = f;
    }
  }
  readings.push_back(as_written);
  // Every partial matching of emptied to filled places, depth first; groups are small (a few
  // objects of one mesh in a scene), and larger ones are read as written only.
  constexpr std::size_t kMaxPlaces = 5;
  if (group.emptied.size() > kMaxPlaces || group.filled.size() > kMaxPlaces) return readings;
  Reading current(group.emptied.size(), none);
  std::vector<bool> taken(group.filled.size(), false);
  std::function<void(std::size_t, int)> extend = [&](std::size_t e, int moves) {
    if (e == group.emptied.size()) {
      if (moves >= group.moves_as_written && current != as_written) readings.push_back(current);
      return;
    }
    current[e] = none;
    extend(e + 1, moves);
    for (std::size_t f = 0; f < group.filled.size(); ++f) {
      if (taken[f]) continue;
      taken[f] = true;
      current[e] = f;
      extend(e + 1, moves + 1);
      taken[f] = false;
    }
    current[e] = none;
  };
  extend(0, 0);
  return readings;
}

// The real changes `reading` of `group` stands for.
void AppendReading(const LookAlikeGroup& group, const Reading& reading,
                   std::vector<GroundTruthChange>* changes) {
  std::vector<bool> filled_used(group.filled.size(), false);
  for (std::size_t e = 0; e < group.emptied.size(); ++e) {
    const Place& from = group.emptied[e];
    if (reading[e] == group.filled.size()) {
      GroundTruthChange removal = *from.source;
      removal.kind = ChangeKind::kRemoved;
      removal.position_W = from.position_W;
      removal.from_W.setZero();
      removal.visible_frames = -1;  // what the second session showed of it: nothing
      changes->push_back(removal);
      continue;
    }
    const Place& to = group.filled[reading[e]];
    filled_used[reading[e]] = true;
    // The object that was there moved, and is seen (or not) where it went.
    GroundTruthChange move = *to.source;
    move.kind = ChangeKind::kMoved;
    move.id = from.source->id;
    move.from_W = from.position_W;
    move.position_W = to.position_W;
    changes->push_back(move);
  }
  for (std::size_t f = 0; f < group.filled.size(); ++f) {
    if (filled_used[f]) continue;
    GroundTruthChange addition = *group.filled[f].source;
    addition.kind = ChangeKind::kAdded;
    addition.position_W = group.filled[f].position_W;
    addition.from_W.setZero();
    changes->push_back(addition);
  }
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
    if (object != nullptr) {
      change.largest_size_m = object->size_m.maxCoeff();
      change.size_m = object->size_m;
      change.mesh_vertices = static_cast<int>(object->mesh_vertices_W.size());
      change.mesh_triangles = static_cast<int>(object->mesh_triangles.size());
    }
  }
  return not_found;
}

bool LookAlike(const GroundTruthChange& a, const GroundTruthChange& b) {
  constexpr double kSizeToleranceM = 0.005;
  return a.class_id == b.class_id && a.mesh_vertices > 0 && a.mesh_vertices == b.mesh_vertices &&
         a.mesh_triangles == b.mesh_triangles &&
         ((a.size_m - b.size_m).cwiseAbs().array() <= kSizeToleranceM).all();
}

ChangeEvaluation EvaluateChanges(const std::vector<GroundTruthChange>& real,
                                 const std::vector<ReportedChange>& reported,
                                 const std::vector<MappedObject>* present,
                                 const ChangeEvaluationConfig& config) {
  if (!config.lookalikes_interchangeable) {
    return EvaluateAsWritten(real, reported, present, config);
  }
  std::vector<bool> grouped;
  const std::vector<LookAlikeGroup> groups = LookAlikeGroups(real, &grouped);
  std::vector<GroundTruthChange> fixed;
  for (std::size_t i = 0; i < real.size(); ++i) {
    if (!grouped[i]) fixed.push_back(real[i]);
  }
  std::vector<std::vector<Reading>> readings;
  for (const LookAlikeGroup& group : groups) readings.push_back(ReadingsOf(group));
  // Each group's reading chosen in turn, the others held: groups interact only through reports
  // of their class, and the reading as written wins every tie.
  std::vector<std::size_t> chosen(groups.size(), 0);
  auto evaluate = [&](const std::vector<std::size_t>& choice) {
    std::vector<GroundTruthChange> changes = fixed;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      AppendReading(groups[g], readings[g][choice[g]], &changes);
    }
    return EvaluateAsWritten(changes, reported, present, config);
  };
  ChangeEvaluation best = evaluate(chosen);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    std::vector<std::size_t> trial = chosen;
    for (std::size_t r = 1; r < readings[g].size(); ++r) {
      trial[g] = r;
      ChangeEvaluation e = evaluate(trial);
      if (e.totals.true_positives > best.totals.true_positives) {
        best = std::move(e);
        chosen[g] = r;
      }
    }
  }
  best.lookalike_groups_reread = static_cast<int>(
      std::count_if(chosen.begin(), chosen.end(), [](std::size_t r) { return r != 0; }));
  return best;
}

}  // namespace objmap
