// objmap_sim: writes a synthetic scene as a recorded sequence with ground truth.
//   objmap_sim --out DIR [--kind desk|office|kitchen|lab] [--seed N] [--frames N] [--perfect]
//   [--drift]
//              [--procedural]
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>

#include "sim/furniture_catalog.h"
#include "sim/scene.h"
#include "sim/sequence_writer.h"

namespace {

constexpr char kUsage[] =
    "usage: objmap_sim --out DIR [--kind desk|office|kitchen|lab] [--seed N] [--frames N] "
    "[--perfect]\n"
    "                  [--drift] [--procedural]\n"
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
    "               corrected_poses.txt holds the true poses for `objmap map --corrected-poses`\n";

}  // namespace

int main(int argc, char** argv) {
  std::string out, kind = "office", scene_file;
  std::uint64_t seed = 1;
  int frames = 300;
  bool perfect = false, drift = false, procedural = false;
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
  return 0;
}
