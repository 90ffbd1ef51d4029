#include "sim/revisit.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "sim/object_meshes.h"
#include "sim/renderer.h"
#include "sim/revisit_geometry.h"
#include "sim/sim_random.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

// Whether an object is seen, not just in view (a cup behind a monitor is in view), is judged on
// a few poses of the second trajectory rendered at a quarter of the resolution; 12 pixels there
// are about 190 at full resolution, a little above what the detector needs.
constexpr int kSightPoses = 10;
constexpr int kSightScale = 4;
constexpr int kSightMinPixels = 12;
constexpr int kPlacementTries = 400;
// New boxes keep 3 cm from every other box; a box may sink 5 mm into what it stands on.
constexpr double kGapM = 0.03;
constexpr double kTouchM = 0.005;
// Changes are preferably this far apart (box centres, old and new places alike), so that each is
// told from the others: not the three books of one stack, not a cup put where a book was.
constexpr double kDistinctM = 0.25;

std::string ClassOf(int class_id) { return std::string(CocoClassName(class_id)); }
std::string ClassOf(const SceneObject& object) { return ClassOf(object.class_id); }

// Things a person carries away or brings along, standing on tables and counters.
bool Carried(const std::string& c) {
  static const std::set<std::string> kCarried = {"cup",    "book",     "bottle",
                                                 "laptop", "keyboard", "mouse"};
  return kCarried.count(c) > 0;
}
bool FloorStanding(const std::string& c) { return c == "chair" || c == "potted plant"; }
// Taken away, but not put elsewhere: a monitor or microwave moves with its cables.
bool Removable(const std::string& c) {
  return Carried(c) || FloorStanding(c) || c == "tv" || c == "microwave";
}

// The distance from `p_W` to the nearest place, old or new, of the changes so far.
double NearestChange(const Eigen::Vector3d& p_W, const SceneChanges& changes) {
  double nearest = std::numeric_limits<double>::infinity();
  for (const auto* list : {&changes.removed, &changes.moved, &changes.added}) {
    for (const ObjectChange& c : *list) {
      if (list != &changes.added) nearest = std::min(nearest, (p_W - c.from_W).norm());
      if (list != &changes.removed) nearest = std::min(nearest, (p_W - c.to_W).norm());
    }
  }
  return nearest;
}

// A new object of `class_name` (procedural, or dressed from the catalog).
SceneObject NewObject(const std::string& class_name, int id, const std::string& name,
                      std::uint64_t seed, const FurnitureCatalog* catalog, Random* random) {
  const Rgb color = Jitter({static_cast<std::uint8_t>(random->Uniform(40.0, 220.0)),
                            static_cast<std::uint8_t>(random->Uniform(40.0, 220.0)),
                            static_cast<std::uint8_t>(random->Uniform(40.0, 220.0))},
                           random);
  TriangleMesh mesh;
  if (class_name == "cup") {
    mesh = CupMesh(color);
  } else if (class_name == "book") {
    mesh = BookMesh(static_cast<float>(random->Uniform(0.2, 0.26)),
                    static_cast<float>(random->Uniform(0.15, 0.19)),
                    static_cast<float>(random->Uniform(0.02, 0.04)), color);
  } else if (class_name == "bottle") {
    mesh = BottleMesh(color);
  } else if (class_name == "laptop") {
    mesh = LaptopMesh(color, Jitter({30, 60, 120}, random));
  } else if (class_name == "chair") {
    mesh = ChairMesh(color);
  } else {
    mesh = PottedPlantMesh();
  }
  SceneObject object;
  object.id = id;
  object.class_id = CocoClassId(class_name);
  object.name = name;
  object.mesh = DressFromCatalog(catalog, class_name, mesh, seed, id, nullptr, &object.name);
  return object;
}

// Picks and places the changes on a working copy of the scene, at the resolution of the sight
// renders.
class RevisitPlanner {
 public:
  RevisitPlanner(const Scene& first, const RevisitConfig& config, const RoomLayout& layout,
                 const std::vector<Eigen::Isometry3d>& trajectory, std::uint64_t seed,
                 const FurnitureCatalog* catalog)
      : first_(first),
        config_(config),
        layout_(layout),
        trajectory_(trajectory),
        seed_(seed),
        catalog_(catalog),
        random_(seed, 0xC4A26Eull) {
    const int frames = static_cast<int>(trajectory.size());
    required_frames_ = std::max(std::min(10, frames),
                                static_cast<int>(std::ceil(config.min_view_fraction * frames)));
    work_.structure = first.structure;
    work_.objects = first.objects;
    work_.intrinsics = first.intrinsics;
    work_.intrinsics.width /= kSightScale;
    work_.intrinsics.height /= kSightScale;
    work_.intrinsics.fx /= kSightScale;
    work_.intrinsics.fy /= kSightScale;
    work_.intrinsics.cx /= kSightScale;
    work_.intrinsics.cy /= kSightScale;
    for (int k = 0; k < kSightPoses; ++k) {
      sight_poses_.push_back(
          trajectory[static_cast<std::size_t>(k) * (trajectory.size() - 1) / (kSightPoses - 1)]);
    }
    for (const SceneObject& object : first.objects) old_boxes_.push_back(ObjectWorldBox(object));
  }

  bool Plan(SceneChanges* changes, std::string* why) {
    const std::vector<int> order = CandidateOrder();
    for (int m = 0; m < config_.moved; ++m) {
      if (!MoveOne(order, changes)) {
        *why = "only " + std::to_string(changes->moved.size()) + " of " +
               std::to_string(config_.moved) + " objects could be moved where the second " +
               "trajectory sees them";
        return false;
      }
    }
    for (int r = 0; r < config_.removed; ++r) {
      if (!RemoveOne(order, changes)) {
        *why = "only " + std::to_string(changes->removed.size()) + " of " +
               std::to_string(config_.removed) + " objects the second trajectory sees are left " +
               "to remove after the moves";
        return false;
      }
    }
    int next_id = 0;
    for (const SceneObject& object : first_.objects) next_id = std::max(next_id, object.id);
    for (int a = 0; a < config_.added; ++a) {
      if (!AddOne(++next_id, changes)) {
        *why = "no free place the second trajectory sees for added object " +
               std::to_string(a + 1) + " of " + std::to_string(config_.added);
        return false;
      }
    }
    return true;
  }

  std::vector<SceneObject> TakeObjects() { return std::move(work_.objects); }

 private:
  // Indices into first_.objects of the objects worth changing, in the order they are tried:
  // drawn by seed, the better seen ones more likely first (exponential clocks weighted by the
  // square root of the pixels they show).
  std::vector<int> CandidateOrder() {
    std::map<int, int> poses_seen, pixels;
    Sight(&poses_seen, &pixels);
    std::vector<std::pair<double, int>> keyed;
    for (std::size_t i = 0; i < first_.objects.size(); ++i) {
      const SceneObject& object = first_.objects[i];
      const double draw = random_.Uniform();
      if (!Removable(ClassOf(object)) || 2 * poses_seen[object.id] < kSightPoses ||
          !InView(ObjectBoxCentre(object))) {
        continue;
      }
      const double weight = std::sqrt(1.0 + pixels[object.id]);
      keyed.emplace_back(-std::log(1.0 - draw) / weight, static_cast<int>(i));
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<int> order;
    for (const auto& [key, index] : keyed) order.push_back(index);
    return order;
  }

  // Per object id: the sight poses showing at least kSightMinPixels of it, and its pixels in all.
  void Sight(std::map<int, int>* poses_seen, std::map<int, int>* pixels) const {
    DepthNoiseConfig exact;
    exact.enabled = false;
    for (std::size_t k = 0; k < sight_poses_.size(); ++k) {
      const RenderedFrame frame = Render(work_, sight_poses_[k], exact, 0, static_cast<int>(k));
      std::map<int, int> in_frame;
      for (std::uint16_t id : frame.instance) {
        if (id != 0) ++in_frame[id];
      }
      for (const auto& [id, count] : in_frame) {
        (*pixels)[id] += count;
        if (count >= kSightMinPixels) ++(*poses_seen)[id];
      }
    }
  }

  bool InView(const Eigen::Vector3d& point_W) const {
    return FramesInView(point_W, trajectory_, first_.intrinsics, config_.max_view_m) >=
           required_frames_;
  }

  // The working object with `id`, or nullptr when it was removed.
  SceneObject* Working(int id) {
    for (SceneObject& object : work_.objects) {
      if (object.id == id) return &object;
    }
    return nullptr;
  }

  // Something stands on it: taking it away would leave that floating.
  bool CarriesSomething(const SceneObject& object) const {
    const WorldBox box = ObjectWorldBox(object);
    return std::any_of(work_.objects.begin(), work_.objects.end(), [&](const SceneObject& other) {
      if (other.id == object.id) return false;
      const WorldBox on = ObjectWorldBox(other);
      return std::abs(on.min.z() - box.max.z()) < 0.01 && BoxesClash(on, box, -0.01, -1.0);
    });
  }

  // Still in its first-session place, and free to go.
  bool Changeable(int index) {
    const SceneObject& object = first_.objects[static_cast<std::size_t>(index)];
    return changed_.count(object.id) == 0 && Working(object.id) != nullptr &&
           !CarriesSomething(object);
  }

  bool MoveOne(const std::vector<int>& order, SceneChanges* changes) {
    const bool other_support_wanted =
        layout_.supports.size() > 1 &&
        std::none_of(changes->moved.begin(), changes->moved.end(),
                     [](const ObjectChange& c) { return c.other_support; });
    // First try to put something on another support, then anything anywhere; first something
    // away from the other changes, then anything.
    for (const bool other_support : {other_support_wanted, false}) {
      for (const bool distinct : {true, false}) {
        for (int index : order) {
          if (TryMove(index, other_support, distinct, changes)) return true;
        }
      }
    }
    return false;
  }

  bool TryMove(int index, bool other_support, bool distinct, SceneChanges* changes) {
    const SceneObject& before = first_.objects[static_cast<std::size_t>(index)];
    const std::string c = ClassOf(before);
    const Eigen::Vector3d from_W = ObjectBoxCentre(before);
    if (!Changeable(index) || !(Carried(c) || FloorStanding(c)) ||
        (other_support && FloorStanding(c)) ||
        (distinct && NearestChange(from_W, *changes) < kDistinctM)) {
      return false;
    }
    const int old_support = SupportUnder(layout_, ObjectWorldBox(before));
    SceneObject moved = before;
    int support = -1;
    if (!Place(Destinations(c, old_support, other_support), &from_W, *changes, &moved, &support)) {
      return false;
    }
    *Working(before.id) = moved;
    changed_.insert(before.id);
    changes->moved.push_back({before.id, before.class_id, before.name, from_W,
                              ObjectBoxCentre(moved), support != old_support});
    return true;
  }

  // The supports an object of class `c` may go to: the floor for chairs and plants; tables and
  // counters for carried things (another one than `old_support` when `other_support`, the floor
  // when the room has no other), or the floor in a room without any.
  std::vector<int> Destinations(const std::string& c, int old_support, bool other_support) const {
    if (FloorStanding(c)) return {0};
    std::vector<int> raised;
    for (std::size_t i = 1; i < layout_.supports.size(); ++i) {
      if (!other_support || static_cast<int>(i) != old_support) {
        raised.push_back(static_cast<int>(i));
      }
    }
    if (!raised.empty()) return raised;
    if (other_support && old_support == 0) return {};
    return {0};
  }

  bool RemoveOne(const std::vector<int>& order, SceneChanges* changes) {
    for (const bool distinct : {true, false}) {
      for (int index : order) {
        const SceneObject& object = first_.objects[static_cast<std::size_t>(index)];
        const Eigen::Vector3d from_W = ObjectBoxCentre(object);
        if (!Changeable(index) || (distinct && NearestChange(from_W, *changes) < kDistinctM)) {
          continue;
        }
        changed_.insert(object.id);
        changes->removed.push_back({object.id, object.class_id, object.name, from_W, {}, false});
        work_.objects.erase(std::remove_if(work_.objects.begin(), work_.objects.end(),
                                           [&](const SceneObject& o) { return o.id == object.id; }),
                            work_.objects.end());
        return true;
      }
    }
    return false;
  }

  bool AddOne(int id, SceneChanges* changes) {
    std::vector<std::string> classes = {"cup", "book", "bottle", "laptop", "chair", "potted plant"};
    for (std::size_t i = classes.size(); i > 1; --i) {
      std::swap(classes[i - 1], classes[random_.Next() % i]);
    }
    for (const std::string& c : classes) {
      int count = 1;
      for (const ObjectChange& added : changes->added) count += ClassOf(added.class_id) == c;
      const std::string name = "new " + c + (count > 1 ? " " + std::to_string(count) : "");
      SceneObject object = NewObject(c, id, name, seed_, catalog_, &random_);
      int support = -1;
      if (!Place(Destinations(c, -1, false), nullptr, *changes, &object, &support)) continue;
      changes->added.push_back(
          {id, object.class_id, object.name, {}, ObjectBoxCentre(object), false});
      work_.objects.push_back(std::move(object));
      return true;
    }
    return false;
  }

  // Puts `object` on one of `supports`: inside it, clear of every box of both sessions and of
  // the structure, at least min_move_m from `from_W` when given, in view of the trajectory and
  // seen in the sight renders; in the first half of the tries also kDistinctM from the other
  // changes. False when no try succeeds.
  bool Place(const std::vector<int>& supports, const Eigen::Vector3d* from_W,
             const SceneChanges& changes, SceneObject* object, int* support) {
    if (supports.empty()) return false;
    Eigen::Vector3f min_O, max_O;
    object->mesh.Bounds(&min_O, &max_O);
    for (int t = 0; t < kPlacementTries; ++t) {
      const int s = supports[random_.Next() % supports.size()];
      const SupportSurface& surface = layout_.supports[static_cast<std::size_t>(s)];
      const Eigen::AngleAxisd yaw(random_.Uniform(0.0, 2.0 * M_PI), Eigen::Vector3d::UnitZ());
      object->T_W_O = Eigen::Isometry3d(yaw);
      const WorldBox turned = ObjectWorldBox(*object);  // around the origin, turned
      const double margin = surface.floor ? 0.25 : 0.02;
      const Eigen::Vector2d lo = surface.min_xy.array() + margin - turned.min.head<2>().array();
      const Eigen::Vector2d hi = surface.max_xy.array() - margin - turned.max.head<2>().array();
      if ((lo.array() > hi.array()).any()) continue;
      object->T_W_O.translation() =
          Eigen::Vector3d(random_.Uniform(lo.x(), hi.x()), random_.Uniform(lo.y(), hi.y()),
                          surface.z - static_cast<double>(min_O.z()));
      const Eigen::Vector3d centre = ObjectBoxCentre(*object);
      if (from_W != nullptr && (centre - *from_W).norm() < config_.min_move_m + 0.05) continue;
      if (2 * t < kPlacementTries && NearestChange(centre, changes) < kDistinctM) continue;
      if (!Clear(*object) || !InView(centre) || !SeenThere(*object)) continue;
      *support = s;
      return true;
    }
    return false;
  }

  bool Clear(const SceneObject& object) const {
    const WorldBox box = ObjectWorldBox(object);
    auto clash = [&](const WorldBox& other) { return BoxesClash(box, other, kGapM, kTouchM); };
    if (std::any_of(old_boxes_.begin(), old_boxes_.end(), clash) ||
        std::any_of(layout_.obstacles.begin(), layout_.obstacles.end(), clash)) {
      return false;
    }
    return std::none_of(work_.objects.begin(), work_.objects.end(), [&](const SceneObject& o) {
      return o.id != object.id && clash(ObjectWorldBox(o));
    });
  }

  // Whether the sight renders show `object` where it was put, with everything else in place.
  bool SeenThere(const SceneObject& object) {
    SceneObject* existing = Working(object.id);
    const SceneObject kept = existing != nullptr ? *existing : SceneObject{};
    if (existing != nullptr) {
      *existing = object;
    } else {
      work_.objects.push_back(object);
    }
    std::map<int, int> poses_seen, pixels;
    Sight(&poses_seen, &pixels);
    if (existing != nullptr) {
      *Working(object.id) = kept;
    } else {
      work_.objects.pop_back();
    }
    return 2 * poses_seen[object.id] >= kSightPoses;
  }

  const Scene& first_;
  const RevisitConfig& config_;
  const RoomLayout& layout_;
  const std::vector<Eigen::Isometry3d>& trajectory_;
  const std::uint64_t seed_;
  const FurnitureCatalog* catalog_;
  Random random_;
  int required_frames_ = 0;
  Scene work_;  // the second session's objects so far, at the sight renders' resolution
  std::vector<Eigen::Isometry3d> sight_poses_;
  std::vector<WorldBox> old_boxes_;  // the first session's: no new place overlaps an old one
  std::set<int> changed_;            // ids moved or removed
};

// At least 0.5 m or 30 degrees from `other`.
bool Elsewhere(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& other) {
  const double angle = Eigen::AngleAxisd(pose.linear().transpose() * other.linear()).angle();
  return (pose.translation() - other.translation()).norm() >= 0.5 || angle >= M_PI / 6.0;
}

nlohmann::ordered_json Point(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

bool RevisitConfig::IsValid(std::string* why) const {
  if (!(patrol_offset_m >= 0.0) || !(patrol_offset_deg >= 0.0)) {
    *why = "revisit: patrol_offset_m and patrol_offset_deg must be >= 0";
    return false;
  }
  if (removed < 0 || moved < 0 || added < 0 || !(min_move_m > 0.0) ||
      !(min_view_fraction > 0.0 && min_view_fraction <= 1.0) || !(max_view_m > 0.0)) {
    *why =
        "RevisitConfig: removed, moved, added >= 0, min_move_m > 0, min_view_fraction in (0, 1] "
        "and max_view_m > 0 are required";
    return false;
  }
  return true;
}

bool MakeRevisit(const Scene& first, const RevisitConfig& config, std::uint64_t seed, int frames,
                 Scene* second, SceneChanges* changes, std::string* why,
                 const FurnitureCatalog* catalog) {
  if (!config.IsValid(why)) return false;
  if (frames < 2 || first.trajectory.empty()) {
    *why = "a revisit needs a first session with a trajectory and at least 2 frames";
    return false;
  }
  RoomLayout layout;
  if (!FindRoomLayout(first, &layout, why)) return false;
  Random path_random(seed, 0x7AC3ull);
  std::vector<Eigen::Isometry3d> trajectory =
      config.patrol ? PatrolTrajectory(first.trajectory, frames, config.patrol_offset_m,
                                       config.patrol_offset_deg, &path_random)
                    : RevisitTrajectory(first.trajectory, layout.supports[0], frames, &path_random);
  if (!config.patrol && (!Elsewhere(trajectory.front(), first.trajectory.front()) ||
                         !Elsewhere(trajectory.front(), first.trajectory.back()))) {
    *why = "the second trajectory would start where the first starts or ends";
    return false;
  }
  *changes = SceneChanges{};
  changes->kind = first.kind;
  changes->scene_seed = first.seed;
  changes->revisit_seed = seed;
  RevisitPlanner planner(first, config, layout, trajectory, seed, catalog);
  if (!planner.Plan(changes, why)) {
    *why = first.kind + " scene (seed " + std::to_string(first.seed) + "), revisit seed " +
           std::to_string(seed) + ": " + *why;
    return false;
  }
  *second = Scene{};
  second->kind = first.kind;
  second->seed = seed;
  second->structure = first.structure;
  second->objects = planner.TakeObjects();
  second->intrinsics = first.intrinsics;
  second->trajectory = std::move(trajectory);
  return true;
}

std::string ChangesJson(const SceneChanges& changes) {
  auto entry = [](const ObjectChange& c) {
    return nlohmann::ordered_json{
        {"id", c.id}, {"class", std::string(CocoClassName(c.class_id))}, {"name", c.name}};
  };
  nlohmann::ordered_json removed = nlohmann::ordered_json::array();
  nlohmann::ordered_json moved = nlohmann::ordered_json::array();
  nlohmann::ordered_json added = nlohmann::ordered_json::array();
  for (const ObjectChange& c : changes.removed) {
    removed.push_back(entry(c));
    removed.back()["position"] = Point(c.from_W);
  }
  for (const ObjectChange& c : changes.moved) {
    moved.push_back(entry(c));
    moved.back()["from"] = Point(c.from_W);
    moved.back()["to"] = Point(c.to_W);
    moved.back()["other_support"] = c.other_support;
  }
  for (const ObjectChange& c : changes.added) {
    added.push_back(entry(c));
    added.back()["position"] = Point(c.to_W);
  }
  return nlohmann::ordered_json{{"format", "objmap-changes-1"},
                                {"kind", changes.kind},
                                {"seed", changes.scene_seed},
                                {"revisit_seed", changes.revisit_seed},
                                {"removed", removed},
                                {"moved", moved},
                                {"added", added}}
      .dump(1);
}

bool WriteRevisitSequence(const Scene& second, const SceneChanges& changes,
                          const SequenceOptions& options, const std::string& dir,
                          std::string* why) {
  if (!WriteSequence(second, options, dir, why)) return false;
  const std::string path = (std::filesystem::path(dir) / "changes.json").string();
  std::ofstream out(path);
  out << ChangesJson(changes) << "\n";
  if (!out) {
    *why = path + ": write failed";
    return false;
  }
  return true;
}

}  // namespace objmap::sim
