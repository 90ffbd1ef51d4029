// objmap_sim: writes a synthetic scene as a recorded sequence with ground truth, and optionally
// a second session of it with objects removed, moved and added (usage in kUsage).
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>

#include "sim/furniture_catalog.h"
#include "sim/revisit.h"
#include "sim/scene.h"
#include "sim/sequence_writer.h"

namespace {

constexpr char kUsage[] =
    "usage: objmap_sim --out DIR [--kind desk|office|kitchen|lab] [--seed N] [--frames N] "
    "[--perfect]\n"
    "                  [--drift] [--procedural]\n"
    "                  [--revisit DIR2 [--removed N] [--moved N] [--added N] [--revisit-seed N]\n"
    "                   [--patrol]]\n"
    "       objmap_sim --out DIR --scene scene.json [--perfect] [--drift] [--procedural]\n"
    "  writes DIR/frame-NNNNNN.{color,depth,instance}.png and .pose.txt, camera-intrinsics.txt,\n"
    "  detections.json (the ground-truth detector) and ground_truth.json\n"
    "  --kind K     scene kind (default office)\n"
    "  --scene F    the scene from a file (room, objects, camera; see tests/sim/scene.h)\n"
    "  --seed N     scene, noise and detector seed (default 1)\n"
    "  --frames N   frames along the camera sweep (default 300)\n"
    "  --perfect    no depth noise and a detector without errors\n"
    "  --procedural procedural objects only; by default tables, chairs, monitors, cups, books,\n"
    "               laptops and plants are furniture meshes of sweethome3d-furniture when it is\n"
    "               installed\n"
    "  --drift      the pose files hold drifting odometry (2 deg/m heading, 2 % scale);\n"
    "               corrected_poses.txt holds the true poses for `objmap map --corrected-poses`\n"
    "  --revisit DIR2 also a second session of the same room in DIR2, in the same world frame and\n"
    "               format (its ground_truth.json: the objects present then, unchanged and moved\n"
    "               ones with their first ids), with objects removed, moved and added, and\n"
    "               DIR2/changes.json: {\"format\": \"objmap-changes-1\", \"kind\", \"seed\",\n"
    "               \"revisit_seed\", \"removed\": [{\"id\", \"class\", \"name\", \"position\"}],\n"
    "               \"moved\": [{..., \"from\", \"to\", \"other_support\"}], \"added\": [...]}\n"
    "               (box centres, metres). Its camera starts over the middle of the first sweep,\n"
    "               farther and higher, and sweeps to both sides; as many frames as --frames\n"
    "  --removed N, --moved N, --added N  changes of each kind (default 3 each)\n"
    "  --revisit-seed N  picks the changes and the second trajectory (default: --seed + 1)\n"
    "  --patrol     the second session drives the first one's path again, a few centimetres and\n"
    "               degrees to one side (a patrol route), instead of starting elsewhere\n";

}  // namespace

int main(int argc, char** argv) {
  std::string out, kind = "office", scene_file;
  std::uint64_t seed = 1;
  int frames = 300;
  bool perfect = false, drift = false, procedural = false;
  std::string revisit_out;
  objmap::sim::RevisitConfig revisit;
  std::uint64_t revisit_seed = 0;
  bool revisit_seed_given = false, revisit_option_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--out" && has_value) {
      out = argv[++i];
    } else if (arg == "--kind" && has_value) {
      kind = argv[++i];
    } else if (arg == "--scene" && has_value) {
      scene_file = argv[++i];
    } else if (arg == "--seed" && has_value) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (arg == "--frames" && has_value) {
      frames = std::atoi(argv[++i]);
    } else if (arg == "--revisit" && has_value) {
      revisit_out = argv[++i];
    } else if (arg == "--removed" && has_value) {
      revisit.removed = std::atoi(argv[++i]);
      revisit_option_given = true;
    } else if (arg == "--moved" && has_value) {
      revisit.moved = std::atoi(argv[++i]);
      revisit_option_given = true;
    } else if (arg == "--added" && has_value) {
      revisit.added = std::atoi(argv[++i]);
      revisit_option_given = true;
    } else if (arg == "--patrol") {
      revisit.patrol = true;
      revisit_option_given = true;
    } else if (arg == "--revisit-seed" && has_value) {
      revisit_seed = std::strtoull(argv[++i], nullptr, 10);
      revisit_seed_given = revisit_option_given = true;
    } else if (arg == "--perfect") {
      perfect = true;
    } else if (arg == "--drift") {
      drift = true;
    } else if (arg == "--procedural") {
      procedural = true;
    } else if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    } else {
      std::cerr << "objmap_sim: unexpected argument '" << arg << "'\n" << kUsage;
      return 2;
    }
  }
  if (out.empty()) {
    std::cerr << "objmap_sim: --out DIR is required\n" << kUsage;
    return 2;
  }
  if (revisit_out.empty() && revisit_option_given) {
    std::cerr << "objmap_sim: --removed, --moved, --added, --revisit-seed and --patrol need "
                 "--revisit DIR2\n"
              << kUsage;
    return 2;
  }
  std::string why;
  std::unique_ptr<objmap::sim::FurnitureCatalog> catalog;
  if (!procedural) {
    catalog =
        objmap::sim::FurnitureCatalog::Open(objmap::sim::FurnitureCatalog::kDefaultFolder, &why);
    if (!catalog) std::cerr << "objmap_sim: " << why << "; procedural objects only\n";
  }
  objmap::sim::Scene scene;
  const bool made = scene_file.empty()
                        ? objmap::sim::MakeScene(kind, seed, frames, &scene, &why, catalog.get())
                        : objmap::sim::MakeSceneFromFile(scene_file, catalog.get(), &scene, &why);
  if (!made) {
    std::cerr << "objmap_sim: " << why << "\n";
    return 2;
  }
  objmap::sim::SequenceOptions options;
  if (perfect) {
    options.depth_noise.enabled = false;
    options.detector.miss_probability = 0.0;
    options.detector.confusion_probability = 0.0;
    options.detector.false_positives_per_frame = 0.0;
    options.detector.box_jitter = 0.0;
  }
  options.drift.enabled = drift;
  if (!objmap::sim::WriteSequence(scene, options, out, &why)) {
    std::cerr << "objmap_sim: " << why << "\n";
    return 1;
  }
  std::cout << "objmap_sim: " << scene.kind << " scene (seed " << scene.seed << "), "
            << scene.trajectory.size() << " frames, " << scene.objects.size() << " objects, in "
            << out << "\n";
  if (revisit_out.empty()) return 0;
  // The second session draws its own noise and detections: another seed than the first's.
  objmap::sim::Scene second;
  objmap::sim::SceneChanges changes;
  if (!objmap::sim::MakeRevisit(scene, revisit, revisit_seed_given ? revisit_seed : scene.seed + 1,
                                static_cast<int>(scene.trajectory.size()), &second, &changes, &why,
                                catalog.get())) {
    std::cerr << "objmap_sim: revisit: " << why << "\n";
    return 2;
  }
  if (!objmap::sim::WriteRevisitSequence(second, changes, options, revisit_out, &why)) {
    std::cerr << "objmap_sim: " << why << "\n";
    return 1;
  }
  std::cout << "objmap_sim: revisit (seed " << second.seed << "), " << second.trajectory.size()
            << " frames, " << changes.removed.size() << " removed, " << changes.moved.size()
            << " moved, " << changes.added.size() << " added, in " << revisit_out << "\n";
  return 0;
}
