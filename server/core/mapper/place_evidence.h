#pragma once
// What the keyframes said of each object's place, for DetectChanges: views that saw it there or
// saw through it, the baseline of what its own views saw through, and the tops of piles taken
// away. Private to mapper/.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include "mapper/object_changes.h"

namespace objmap {

constexpr KeyframeId kMaxKeyframeId = std::numeric_limits<KeyframeId>::max();

// What the keyframes said of one object's place.
struct PlaceEvidence {
  const MapObject* object = nullptr;
  KeyframeId first_seen = 0, last_seen = 0;
  KeyframeId seen_empty_at = 0;    // see ObjectPlace
  bool seen_empty_before = false;  // min_empty_views saw the place empty before first_seen
  bool judged_before = false;      // some keyframe before first_seen could judge the place
  bool counts = false;             // confirmed (as of its last sighting, when gone)
  const std::map<KeyframeId, ObjectVisibility>* visibility = nullptr;  // every keyframe's view
  std::set<KeyframeId> observed;  // keyframes with an observation of it
};

// A view clearly saw the object there: its place in view, and at most half the share of
// see-through points that would call it empty.
[[nodiscard]] bool SawItThere(const ObjectVisibility& seen, float empty_fraction,
                              const ChangeConfig& config);
// A view saw the object's place empty: it judged the place and saw through at least
// `empty_fraction` of the object's points in view.
[[nodiscard]] bool SawPlaceEmpty(const ObjectVisibility& seen, float empty_fraction,
                                 const ChangeConfig& config);

// The share of its points in view that a view must see through to see an object's place empty.
struct EmptyFractions {
  float within_session = 0.f;    // in a session that detected it there
  float between_sessions = 0.f;  // in another session
  bool baseline = false;         // from the views that detected it (else min_empty_fraction)
};

/// What the views that detected an object saw through, plus min_empty_fraction_over_present
/// (place_evidence.cc says why); only the views before `before` count.
[[nodiscard]] EmptyFractions EmptyFractionsOf(
    const std::map<KeyframeId, ObjectVisibility>& visibility, const std::set<KeyframeId>& observed,
    const ChangeConfig& config, KeyframeId before = kMaxKeyframeId);

// What a run of views that saw a place empty says, once min_empty_views of them agree.
enum class EmptyEvidence {
  // The place is empty now: a later view that sees the object there again cancels the run (it
  // is back, or never went). Removals are judged so, after an object's last sighting.
  kLatest,
  // The place was empty at some time: later views that see the object there do not cancel a
  // completed run, they only show that it arrived since. Additions are judged so, before an
  // object's first sighting: the views between its arrival and its first detection see it there
  // (too far or too small for the detector yet), and say nothing against the empty place before.
  kEver,
};

// Scans the keyframes of `visibility` in [from, to) that did not observe the object: counts the
// independent views that saw its place empty (`empty_fraction_at` each keyframe) since the last
// one that saw it there. Returns the keyframe at which that count reached min_empty_views (0:
// never, or cancelled by a later view that saw it there, for kLatest), and whether any keyframe
// could judge the place.
[[nodiscard]] KeyframeId EmptyViewsBetween(
    const std::map<KeyframeId, ObjectVisibility>& visibility, const std::set<KeyframeId>& observed,
    KeyframeId from, KeyframeId to, const std::map<KeyframeId, int>& view_of_keyframe,
    const std::function<float(KeyframeId)>& empty_fraction_at, const ChangeConfig& config,
    EmptyEvidence kind, bool* judged);

// The first sighting of an object in the first session that detected it in two independent
// views or more (the first sighting at all when none did). One detection in a session is a
// glimpse at most: a false detection there that a later arrival's detections joined (a bottle
// boxed as a book where a book is put down the next day) would make the arrival older than the
// removal it is the other half of.
[[nodiscard]] KeyframeId FirstSightingOfTwoViews(
    const std::set<KeyframeId>& observed, const std::map<KeyframeId, int>& view_of_keyframe,
    const std::function<std::int64_t(KeyframeId)>& session_of);

// A stack that lost its top (EmptiedUnderLaterDetections): a pile of books is modelled by a few
// objects of one label in one place (the whole pile, the top book, the rest), and a detection
// joins whichever fits best. When a later session still detects one of them but looks through
// much of it, one book of the pile is gone: the object of the pile that session no longer
// detected, modelled there before it, is removed (of several, the one the session looks through
// most: the top's own model). Not when one of them was seen empty in that session already: that
// one stands for the change.
void MarkStackTopsTakenAway(const ChangeInputs& inputs, const ChangeConfig& config,
                            std::map<ObjectId, PlaceEvidence>* places, ObjectChanges* changes);

}  // namespace objmap
