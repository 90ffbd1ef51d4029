#include "mapper/place_evidence.h"

#include <algorithm>
#include <iterator>
#include <vector>

namespace objmap {
namespace {

// Fewer views that detected an object and judged its place: no baseline to speak of.
constexpr std::size_t kMinPresentViews = 3;

// The keyframe at which a later session saw an object's place empty although it still detected
// the object there: the top of a stack taken away (a book off a pile of books). The book below
// is still there and detected, and its detections keep joining the object that modelled the
// stack, so no view after the last detection is left to see the place empty (EmptyViewsBetween).
// What shows the change is that the session looks through much of what the views before it saw
// there: more than the baseline of those views (EmptyFractionsOf) in min_empty_views independent
// views, and in most of the session's views that judged the place, detecting or not. 0: the
// session saw it as the earlier ones did.
KeyframeId EmptiedUnderLaterDetections(const PlaceEvidence& place, std::int64_t session,
                                       KeyframeId session_start,
                                       const KeyframeSessionLookup& session_of,
                                       const std::map<KeyframeId, int>& view_of_keyframe,
                                       const ChangeConfig& config) {
  const EmptyFractions before =
      EmptyFractionsOf(*place.visibility, place.observed, config, session_start);
  if (!before.baseline) return 0;
  const float threshold = before.between_sessions;
  int judged = 0, empty = 0;
  std::set<int> empty_views;
  KeyframeId reached_at = 0;
  for (auto it = place.visibility->lower_bound(session_start); it != place.visibility->end();
       ++it) {
    if (session_of(it->first) != session || !CouldJudgePlace(it->second, config)) continue;
    ++judged;
    if (it->second.empty_fraction < threshold) continue;
    ++empty;
    const auto view = view_of_keyframe.find(it->first);
    empty_views.insert(view != view_of_keyframe.end() ? view->second
                                                      : -static_cast<int>(it->first));
    if (reached_at == 0 && static_cast<int>(empty_views.size()) >= config.min_empty_views) {
      reached_at = it->first;
    }
  }
  return 2 * empty > judged ? reached_at : 0;
}

// The median share of an object's points in view that a session's views which judged its place
// saw through; -1 when none judged it.
float MedianEmptyIn(const PlaceEvidence& place, std::int64_t session, KeyframeId session_start,
                    const KeyframeSessionLookup& session_of, const ChangeConfig& config) {
  std::vector<float> fractions;
  for (auto it = place.visibility->lower_bound(session_start); it != place.visibility->end();
       ++it) {
    if (session_of(it->first) == session && CouldJudgePlace(it->second, config)) {
      fractions.push_back(it->second.empty_fraction);
    }
  }
  if (fractions.empty()) return -1.f;
  const auto middle = fractions.begin() + static_cast<std::ptrdiff_t>(fractions.size() / 2);
  std::nth_element(fractions.begin(), middle, fractions.end());
  return *middle;
}

// Whether two objects stand in one place: the centre of either inside the other's bounds.
bool OnePlace(const MapObject& a, const MapObject& b) {
  const Eigen::AlignedBox3f bounds_a(a.min_W, a.max_W), bounds_b(b.min_W, b.max_W);
  return bounds_a.contains(b.centroid_W) || bounds_b.contains(a.centroid_W);
}

}  // namespace

// A view clearly saw the object there: its place in view, and at most half the share of
// see-through points that would call it empty.
bool SawItThere(const ObjectVisibility& seen, float empty_fraction, const ChangeConfig& config) {
  return CouldJudgePlace(seen, config) && seen.empty_fraction < 0.5f * empty_fraction;
}

// A view saw the object's place empty: it judged the place and saw through at least
// `empty_fraction` of the object's points in view.
bool SawPlaceEmpty(const ObjectVisibility& seen, float empty_fraction, const ChangeConfig& config) {
  return CouldJudgePlace(seen, config) && seen.empty_fraction >= empty_fraction;
}

// An object's baseline is what the views which detected it there saw through (their 90th
// percentile, plus min_empty_fraction_over_present): a view that sees through clearly more saw
// the place empty. A keyboard or a mug whose model took in a rim of the desk around it keeps
// that rim in view when it is taken away, and a view sees through only 40 % of it; while it was
// there, views saw through 2-6 %. A chair is seen through between its legs and the bars of its
// back while it stands there, 40-60 % from some sides: those views are not empty. Between
// sessions the baseline decides (objects are put down and taken away between visits). Within a
// session that detected the object it must also reach min_empty_fraction: an object taken away
// while the camera still looks is rare, and a bare baseline of a few views would call the
// noisier views of a static scene empty. Without a baseline: min_empty_fraction. Only the views
// before `before` count.
EmptyFractions EmptyFractionsOf(const std::map<KeyframeId, ObjectVisibility>& visibility,
                                const std::set<KeyframeId>& observed, const ChangeConfig& config,
                                KeyframeId before) {
  const EmptyFractions no_baseline{config.min_empty_fraction, config.min_empty_fraction};
  if (!(config.min_empty_fraction_over_present > 0.f)) return no_baseline;
  std::vector<float> present;
  for (const KeyframeId keyframe : observed) {
    if (keyframe >= before) break;
    const auto it = visibility.find(keyframe);
    if (it != visibility.end() && CouldJudgePlace(it->second, config)) {
      present.push_back(it->second.empty_fraction);
    }
  }
  if (present.size() < kMinPresentViews) return no_baseline;
  const auto p90 = present.begin() + static_cast<std::ptrdiff_t>(present.size() * 9 / 10);
  std::nth_element(present.begin(), p90, present.end());
  const float baseline = std::min(1.f, *p90 + config.min_empty_fraction_over_present);
  return {std::max(config.min_empty_fraction, baseline), baseline, /*baseline=*/true};
}

// Scans the keyframes of `visibility` in [from, to) that did not observe the object: counts the
// independent views that saw its place empty (`empty_fraction_at` each keyframe) since the last
// one that saw it there. Returns the keyframe at which that count reached min_empty_views (0:
// never, or cancelled by a later view that saw it there, for kLatest), and whether any keyframe
// could judge the place.
KeyframeId EmptyViewsBetween(const std::map<KeyframeId, ObjectVisibility>& visibility,
                             const std::set<KeyframeId>& observed, KeyframeId from, KeyframeId to,
                             const std::map<KeyframeId, int>& view_of_keyframe,
                             const std::function<float(KeyframeId)>& empty_fraction_at,
                             const ChangeConfig& config, EmptyEvidence kind, bool* judged) {
  std::set<int> empty_views;
  KeyframeId reached_at = 0;
  for (auto it = visibility.lower_bound(from); it != visibility.end() && it->first < to; ++it) {
    if (observed.count(it->first) > 0) continue;
    const ObjectVisibility& seen = it->second;
    if (CouldJudgePlace(seen, config) && judged != nullptr) *judged = true;
    const float empty_fraction = empty_fraction_at(it->first);
    if (SawItThere(seen, empty_fraction, config)) {
      if (kind == EmptyEvidence::kEver && reached_at != 0) return reached_at;
      empty_views.clear();
      reached_at = 0;
      continue;
    }
    if (!SawPlaceEmpty(seen, empty_fraction, config)) continue;
    const auto view = view_of_keyframe.find(it->first);
    empty_views.insert(view != view_of_keyframe.end() ? view->second
                                                      : -static_cast<int>(it->first));
    if (reached_at == 0 && static_cast<int>(empty_views.size()) >= config.min_empty_views) {
      reached_at = it->first;
    }
  }
  return reached_at;
}

KeyframeId FirstSightingOfTwoViews(const std::set<KeyframeId>& observed,
                                   const std::map<KeyframeId, int>& view_of_keyframe,
                                   const std::function<std::int64_t(KeyframeId)>& session_of) {
  auto session_first = observed.begin();
  std::set<int> views;
  for (auto it = observed.begin(); it != observed.end(); ++it) {
    if (session_of(*it) != session_of(*session_first)) {
      session_first = it;
      views.clear();
    }
    const auto view = view_of_keyframe.find(*it);
    views.insert(view != view_of_keyframe.end() ? view->second : -static_cast<int>(*it));
    if (views.size() >= 2) return *session_first;
  }
  return *observed.begin();
}

void MarkStackTopsTakenAway(const ChangeInputs& inputs, const ChangeConfig& config,
                            std::map<ObjectId, PlaceEvidence>* places, ObjectChanges* changes) {
  if (!inputs.session_of) return;
  const KeyframeSessionLookup& session_of = inputs.session_of;
  struct Removal {
    KeyframeId empty_at = 0, last_seen = 0;
  };
  std::map<ObjectId, Removal> taken;
  for (const auto& [id, place] : *places) {
    if (place.seen_empty_at != 0 || !place.counts) continue;
    // The first keyframe of each later session that saw the place.
    std::map<std::int64_t, KeyframeId> session_starts;
    const std::int64_t first_session = session_of(place.first_seen);
    for (auto it = place.visibility->upper_bound(place.first_seen); it != place.visibility->end();
         ++it) {
      const std::int64_t session = session_of(it->first);
      if (session != first_session) session_starts.emplace(session, it->first);
    }
    for (const auto& [session, start] : session_starts) {
      if (place.observed.lower_bound(start) == place.observed.end()) continue;  // not detected
      const KeyframeId empty_at = EmptiedUnderLaterDetections(place, session, start, session_of,
                                                              *inputs.view_of_keyframe, config);
      if (empty_at == 0) continue;
      // The pile's objects that stood there before the session: the one it no longer detected
      // (the top's own model), else the one it looks through most.
      const PlaceEvidence* top = nullptr;
      std::pair<bool, float> top_rank{false, -1.f};  // (not detected in the session, empty)
      int pile = 0;
      bool top_seen_empty = false;
      for (const auto& [other_id, other] : *places) {
        if (other.object->Label() != place.object->Label() ||
            (other_id != id && !OnePlace(*other.object, *place.object))) {
          continue;
        }
        if (other.seen_empty_at != 0) {
          top_seen_empty = top_seen_empty || session_of(other.seen_empty_at) == session;
          continue;
        }
        if (other.first_seen >= start || !inputs.confirmed_through(*other.object, start)) continue;
        ++pile;
        const std::pair<bool, float> rank{other.observed.lower_bound(start) == other.observed.end(),
                                          MedianEmptyIn(other, session, start, session_of, config)};
        if (top == nullptr || rank > top_rank) {
          top = &other;
          top_rank = rank;
        }
      }
      if (pile < 2 || top_seen_empty) continue;
      // Its last sighting there is its last before the session (one detected in the session was
      // seen as the rest of the pile).
      taken[top->object->id] = {empty_at, *std::prev(top->observed.lower_bound(start))};
      break;
    }
  }
  for (const auto& [id, removal] : taken) {
    PlaceEvidence& place = places->at(id);
    place.seen_empty_at = removal.empty_at;
    place.last_seen = removal.last_seen;
    place.counts = inputs.confirmed_through(*place.object, removal.empty_at);
    changes->gone.insert(id);
  }
}

}  // namespace objmap
