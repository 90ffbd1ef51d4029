#include "mapper/object_changes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <tuple>

#include "mapper/place_evidence.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// Sizes along the bounding box's axes, largest first.
std::array<float, 3> SortedExtents(const MapObject& object) {
  const Eigen::Vector3f size = object.max_W - object.min_W;
  std::array<float, 3> extents = {size.x(), size.y(), size.z()};
  std::sort(extents.begin(), extents.end(), std::greater<float>());
  return extents;
}

// The larger ratio between corresponding extents of the two largest (at least 1); a few
// centimetres of either extent are within the noise of a model seen from a few sides. The
// smallest extent is left out: it is the depth a view sees least of (a chair seen from the front
// is a thin slab until a view from the side fills it in).
float SizeRatio(const std::array<float, 3>& ea, const std::array<float, 3>& eb) {
  float worst = 1.f;
  for (int i = 0; i < 2; ++i) {
    const float small = std::max(std::min(ea[i], eb[i]), 0.03f);
    const float large = std::max(std::max(ea[i], eb[i]), 0.03f);
    worst = std::max(worst, large / small);
  }
  return worst;
}

// The colours of a model: a coarse histogram (4 bins per channel, 64 wide: light and the side
// seen shift a colour within a bin more often than across), each voxel weighted by the views
// that reached it, summing to 1. A colour is shared between the two nearest bins of each channel
// in proportion to its distance from their centres, so that 63 and 65 (a dark grey laptop seen
// in two lights) fall into the same bins, not into neighbours that share nothing.
using ColourHistogram = std::array<float, 64>;
ColourHistogram ColoursOf(const MapObject& object) {
  constexpr int kBins = 4;
  constexpr float kBinWidth = 256.f / kBins;
  ColourHistogram histogram{};
  double total = 0.0;
  object.model_W.ForEachVoxel([&](const Eigen::Vector3f&, std::uint32_t views, auto colour) {
    const std::array<std::uint8_t, 3> rgb = colour();
    std::array<std::array<int, 2>, 3> bin{};
    std::array<std::array<float, 2>, 3> share{};
    for (int c = 0; c < 3; ++c) {
      const float position = std::clamp(rgb[c] / kBinWidth - 0.5f, 0.f, kBins - 1.f);
      const int low = std::min(static_cast<int>(position), kBins - 2);
      bin[c] = {low, low + 1};
      share[c] = {1.f - (position - low), position - low};
    }
    for (int r = 0; r < 2; ++r) {
      for (int g = 0; g < 2; ++g) {
        for (int b = 0; b < 2; ++b) {
          histogram[(bin[0][r] * kBins + bin[1][g]) * kBins + bin[2][b]] +=
              static_cast<float>(views) * share[0][r] * share[1][g] * share[2][b];
        }
      }
    }
    total += views;
    return true;
  });
  if (total > 0.0) {
    for (float& weight : histogram) weight = static_cast<float>(weight / total);
  }
  return histogram;
}

// The share of colour two models have in common (histogram intersection, 0..1). A model that
// took in some of its neighbours at its border (a bottle beside a white one, a cup on the floor)
// still shares its own colours with the same object elsewhere, where the means of all voxels
// drift apart.
float ColourOverlap(const ColourHistogram& a, const ColourHistogram& b) {
  float overlap = 0.f;
  for (std::size_t i = 0; i < a.size(); ++i) overlap += std::min(a[i], b[i]);
  return overlap;
}

ObjectPlace PlaceOf(const PlaceEvidence& evidence) {
  ObjectPlace place;
  place.object = evidence.object->id;
  place.centroid_W = evidence.object->centroid_W;
  place.min_W = evidence.object->min_W;
  place.max_W = evidence.object->max_W;
  place.first_seen = evidence.first_seen;
  place.last_seen = evidence.last_seen;
  place.seen_empty_at = evidence.seen_empty_at;
  return place;
}

}  // namespace

ObjectId ObjectChanges::PublishedId(ObjectId object) const {
  const auto it = published_id.find(object);
  return it != published_id.end() ? it->second : object;
}

const char* ChangeKindName(ObjectChange::Kind kind) {
  switch (kind) {
    case ObjectChange::Kind::kAdded:
      return "added";
    case ObjectChange::Kind::kRemoved:
      return "removed";
    case ObjectChange::Kind::kMoved:
      return "moved";
  }
  return "?";
}

const char* ObjectStateName(ObjectState state) {
  switch (state) {
    case ObjectState::kPresent:
      return "present";
    case ObjectState::kRemoved:
      return "removed";
    case ObjectState::kMoved:
      return "moved";
  }
  return "?";
}

std::vector<ObjectChange> ChangeList(const ObjectChanges& changes) {
  std::vector<ObjectChange> list;
  for (const auto& [id, history] : changes.histories) {
    if (history.places.empty()) continue;
    auto change_at = [&](ObjectChange::Kind kind, KeyframeId keyframe, const ObjectPlace& place) {
      ObjectChange& change = list.emplace_back();
      change.kind = kind;
      change.id = id;
      change.class_id = history.class_id;
      change.keyframe_id = keyframe;
      change.centroid_W = place.centroid_W;
      change.min_W = place.min_W;
      change.max_W = place.max_W;
      return &change;
    };
    if (history.added_at != 0) {
      change_at(ObjectChange::Kind::kAdded, history.added_at, history.places.front());
    }
    for (std::size_t i = 1; i < history.places.size(); ++i) {
      const ObjectPlace& from = history.places[i - 1];
      const ObjectPlace& to = history.places[i];
      // Known once both are: the old place seen empty and the object seen at the new one.
      ObjectChange* moved =
          change_at(ObjectChange::Kind::kMoved, std::max(from.seen_empty_at, to.first_seen), to);
      moved->from_W = from.centroid_W;
      moved->from_last_seen = from.last_seen;
    }
    if (history.state == ObjectState::kRemoved) {
      const ObjectPlace& last = history.places.back();
      change_at(ObjectChange::Kind::kRemoved, last.seen_empty_at, last);
    }
  }
  std::stable_sort(list.begin(), list.end(), [](const ObjectChange& a, const ObjectChange& b) {
    return std::tie(a.keyframe_id, a.id) < std::tie(b.keyframe_id, b.id);
  });
  return list;
}

ObjectChanges DetectChanges(const ChangeInputs& inputs, const ChangeConfig& config) {
  ObjectChanges changes;
  if (!config.enabled || inputs.objects == nullptr || inputs.view_of_keyframe == nullptr) {
    return changes;
  }
  std::map<ObjectId, PlaceEvidence> places;
  for (const auto& [id, object] : inputs.objects->objects()) {
    if (object.Label() == kUnknownClassId || object.observations.empty()) continue;
    std::set<KeyframeId> observed;
    for (const ObjectObservation& observation : object.observations) {
      observed.insert(observation.keyframe_id);
    }
    PlaceEvidence evidence;
    evidence.object = &object;
    evidence.last_seen = *observed.rbegin();
    const std::map<KeyframeId, ObjectVisibility>& visibility = inputs.visibility_of(object);
    evidence.visibility = &visibility;
    auto session_of = [&inputs](KeyframeId keyframe) -> std::int64_t {
      return inputs.session_of ? inputs.session_of(keyframe) : 0;
    };
    evidence.first_seen = FirstSightingOfTwoViews(observed, *inputs.view_of_keyframe, session_of);
    std::set<std::int64_t> detecting_sessions;
    for (const KeyframeId keyframe : observed) detecting_sessions.insert(session_of(keyframe));
    const EmptyFractions fractions = EmptyFractionsOf(visibility, observed, config);
    auto empty_fraction_at = [&](KeyframeId keyframe) {
      return detecting_sessions.count(session_of(keyframe)) > 0 ? fractions.within_session
                                                                : fractions.between_sessions;
    };
    evidence.seen_empty_at = EmptyViewsBetween(
        visibility, observed, evidence.last_seen + 1, kMaxKeyframeId, *inputs.view_of_keyframe,
        empty_fraction_at, config, EmptyEvidence::kLatest, nullptr);
    evidence.seen_empty_before =
        EmptyViewsBetween(visibility, observed, 0, evidence.first_seen, *inputs.view_of_keyframe,
                          empty_fraction_at, config, EmptyEvidence::kEver,
                          &evidence.judged_before) != 0;
    if (evidence.seen_empty_at != 0) changes.gone.insert(id);
    // A removed object counts as what the views up to its removal made of it: those that saw it
    // there and did not detect it are misses, so a false detection that a view confirmed once,
    // and many saw there without detecting, is no removal when its place changes.
    evidence.counts = inputs.confirmed_through(
        object, evidence.seen_empty_at != 0 ? evidence.seen_empty_at : kMaxKeyframeId);
    evidence.observed = std::move(observed);
    places.emplace(id, std::move(evidence));
  }
  MarkStackTopsTakenAway(inputs, config, &places, &changes);

  // Moves: removed objects and later arrivals of their label, shape and colour are paired, the
  // surest pairs first. Surest are arrivals that only a move explains: their place was seen
  // before their first detection and never empty (flat things a view cannot see through, a book
  // put on the floor looks like the floor to the depth; or an object there all along that the
  // detector missed until then, which only a removed object of its label, shape and colour can
  // claim). Then arrivals whose place was seen empty first: surely put there, moved or added;
  // unpaired, they are reported added. Last those whose place nothing saw before (a place the
  // map had not looked at, where the object may have stood all along).
  std::map<ObjectId, ObjectId> next, previous;
  std::map<ObjectId, ColourHistogram> colours;  // worked out when first compared
  auto colours_of = [&colours](const MapObject& object) -> const ColourHistogram& {
    auto it = colours.find(object.id);
    if (it == colours.end()) it = colours.emplace(object.id, ColoursOf(object)).first;
    return it->second;
  };
  auto colour_overlap = [&](const PlaceEvidence& a, const PlaceEvidence& b) {
    return ColourOverlap(colours_of(*a.object), colours_of(*b.object));
  };
  std::map<ObjectId, std::array<float, 3>> extents;  // worked out when first compared
  auto extents_of = [&extents](const MapObject& object) -> const std::array<float, 3>& {
    auto it = extents.find(object.id);
    if (it == extents.end()) it = extents.emplace(object.id, SortedExtents(object)).first;
    return it->second;
  };
  auto size_ratio = [&](const PlaceEvidence& a, const PlaceEvidence& b) {
    return SizeRatio(extents_of(*a.object), extents_of(*b.object));
  };
  std::vector<const PlaceEvidence*> removed;
  for (const auto& [id, evidence] : places) {
    if (evidence.counts && evidence.seen_empty_at != 0) removed.push_back(&evidence);
  }
  std::sort(removed.begin(), removed.end(), [](const PlaceEvidence* a, const PlaceEvidence* b) {
    return std::tie(a->seen_empty_at, a->object->id) < std::tie(b->seen_empty_at, b->object->id);
  });
  // Whether `arrival` could be `gone` moved: later, one label, size, far enough, colour.
  auto could_be_move = [&](const PlaceEvidence& gone, const PlaceEvidence& arrival) {
    if (!arrival.counts || &arrival == &gone) return false;
    if (arrival.first_seen <= gone.last_seen || arrival.object->Label() != gone.object->Label()) {
      return false;
    }
    if (size_ratio(gone, arrival) > config.max_move_size_ratio) return false;
    if ((arrival.object->centroid_W - gone.object->centroid_W).norm() <
        config.min_move_distance_m) {
      return false;
    }
    return colour_overlap(gone, arrival) >= config.min_move_colour_overlap;
  };
  auto surety_of = [](const PlaceEvidence& arrival) {
    return !arrival.seen_empty_before && arrival.judged_before ? 0
           : arrival.seen_empty_before                         ? 1
                                                               : 2;
  };
  // How unlike the two are, each key scaled by its limit: 0 for one shape and one colour, 1 at
  // the limit of either.
  auto unlikeness = [&](const PlaceEvidence& gone, const PlaceEvidence& arrival) {
    float cost =
        std::log(size_ratio(gone, arrival)) / std::log(std::max(config.max_move_size_ratio, 1.01f));
    if (config.min_move_colour_overlap > 0.f) cost += 1.f - colour_overlap(gone, arrival);
    return cost;
  };
  struct MoveCandidate {
    const PlaceEvidence* gone = nullptr;
    const PlaceEvidence* arrival = nullptr;
    int surety = 0;
    float unlikeness = 0.f;
  };
  std::vector<MoveCandidate> candidates;
  for (const PlaceEvidence* gone : removed) {
    for (const auto& [id, arrival] : places) {
      if (!could_be_move(*gone, arrival)) continue;
      candidates.push_back({gone, &arrival, surety_of(arrival), unlikeness(*gone, arrival)});
    }
  }
  // The surest, most alike pairs first, over all removals and arrivals at once: a removal that
  // went first does not take the arrival that fits a later one better.
  std::sort(
      candidates.begin(), candidates.end(), [](const MoveCandidate& a, const MoveCandidate& b) {
        return std::make_tuple(a.surety, a.unlikeness, a.gone->seen_empty_at, a.arrival->first_seen,
                               a.gone->object->id, a.arrival->object->id) <
               std::make_tuple(b.surety, b.unlikeness, b.gone->seen_empty_at, b.arrival->first_seen,
                               b.gone->object->id, b.arrival->object->id);
      });
  std::set<ObjectId> undecided_gone, undecided_arrivals;
  for (const MoveCandidate& candidate : candidates) {
    const ObjectId gone_id = candidate.gone->object->id;
    const ObjectId arrival_id = candidate.arrival->object->id;
    if (next.count(gone_id) > 0 || previous.count(arrival_id) > 0 ||
        undecided_gone.count(gone_id) > 0 || undecided_arrivals.count(arrival_id) > 0) {
      continue;
    }
    if (config.move_ambiguity_overlap_margin > 0.f) {
      // Look-alikes (two mugs of one make): another arrival as sure that fits this removal as
      // well, or another removal that fits this arrival as well, leaves the move undecided. Two
      // changes reported as they were seen (removed, added) are wrong less often than a guess.
      const float limit = colour_overlap(*candidate.gone, *candidate.arrival) -
                          config.move_ambiguity_overlap_margin;
      const bool ambiguous =
          std::any_of(candidates.begin(), candidates.end(), [&](const MoveCandidate& other) {
            if (&other == &candidate || other.surety != candidate.surety) return false;
            const bool rival_arrival =
                other.gone == candidate.gone && previous.count(other.arrival->object->id) == 0;
            const bool rival_gone =
                other.arrival == candidate.arrival && next.count(other.gone->object->id) == 0;
            return (rival_arrival || rival_gone) &&
                   colour_overlap(*other.gone, *other.arrival) >= limit;
          });
      if (ambiguous) {
        undecided_gone.insert(gone_id);
        undecided_arrivals.insert(arrival_id);
        continue;
      }
    }
    next[gone_id] = arrival_id;
    previous[arrival_id] = gone_id;
  }

  for (const auto& [id, head] : places) {
    if (!head.counts || previous.count(id) > 0) continue;
    ObjectHistory history;
    history.class_id = head.object->Label();
    history.id = id;
    for (ObjectId at = id;;) {
      const PlaceEvidence& place = places.at(at);
      history.places.push_back(PlaceOf(place));
      history.id = std::min(history.id, at);
      const auto successor = next.find(at);
      if (successor == next.end()) break;
      at = successor->second;
    }
    const ObjectPlace& last = history.places.back();
    history.state = last.seen_empty_at != 0     ? ObjectState::kRemoved
                    : history.places.size() > 1 ? ObjectState::kMoved
                                                : ObjectState::kPresent;
    if (head.seen_empty_before) history.added_at = head.first_seen;
    if (history.added_at == 0 && history.places.size() == 1 &&
        history.state == ObjectState::kPresent) {
      continue;  // no change
    }
    for (const ObjectPlace& place : history.places) {
      if (place.object != history.id) changes.published_id[place.object] = history.id;
    }
    changes.histories.emplace(history.id, std::move(history));
  }
  return changes;
}

}  // namespace objmap
