// `objmap eval-trajectory`: an estimated camera trajectory scored against a reference one.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "arguments.h"
#include "commands.h"
#include "dataset/trajectory.h"
#include "evaluation/trajectory_evaluation.h"

namespace objmap::cli {
namespace {

constexpr char kEvalTrajectoryUsage[] =
    "objmap eval-trajectory: scores an estimated camera trajectory against a reference one.\n"
    "usage: objmap eval-trajectory <estimated.txt> <reference.txt> [options]\n"
    "  both files in TUM format: lines `stamp tx ty tz qx qy qz qw` (seconds, metres, the\n"
    "  camera-to-world pose T_W_C), '#' comments\n"
    "  --max-dt S        largest stamp difference of a pose pair, seconds (default 0.02)\n"
    "  --rpe-distance M  relative error over stretches of this much path, metres (default 1)\n"
    "  --errors FILE     write `stamp ate_m` per matched pose\n"
    "  --json            print the scores as JSON\n"
    "ATE: distances between the positions after the rigid alignment that fits them best (as\n"
    "the TUM RGB-D benchmark); RPE: the error of the motion over each stretch, translation in\n"
    "percent of its length and rotation in degrees per metre.\n";

constexpr int kOk = 0, kError = 1, kUsage = 2;

}  // namespace

int RunEvalTrajectoryCommand(int argc, char** argv) {
  Arguments args(argc, argv, {"--max-dt", "--rpe-distance", "--errors"}, {"--json", "--help"});
  if (args.Has("--help")) {
    std::cout << kEvalTrajectoryUsage;
    return kOk;
  }
  TrajectoryEvaluationConfig config;
  config.max_stamp_difference_s = args.GetNumber("--max-dt", config.max_stamp_difference_s);
  config.rpe_distance_m = args.GetNumber("--rpe-distance", config.rpe_distance_m);
  std::string why;
  if (args.error().empty() && !config.IsValid(&why)) args.SetError(why);
  if (!args.error().empty() || args.positional().size() != 2) {
    std::cerr << (args.error().empty() ? "" : args.error() + "\n") << kEvalTrajectoryUsage;
    return kUsage;
  }
  std::vector<TrajectoryPose> estimated, reference;
  if (!ReadTumTrajectory(args.positional()[0], &estimated, &why) ||
      !ReadTumTrajectory(args.positional()[1], &reference, &why)) {
    std::cerr << "objmap eval-trajectory: " << why << "\n";
    return kError;
  }
  TrajectoryErrors errors;
  if (!EvaluateTrajectory(estimated, reference, config, &errors, &why)) {
    std::cerr << "objmap eval-trajectory: " << why << "\n";
    return kError;
  }
  if (args.Has("--errors")) {
    std::ofstream out(args.Get("--errors", ""));
    out << "# stamp ate_m\n";
    char line[64];
    for (const auto& [stamp, error] : errors.ate_per_pose) {
      std::snprintf(line, sizeof(line), "%.6f %.6f\n", stamp, error);
      out << line;
    }
    if (!out) {
      std::cerr << "objmap eval-trajectory: cannot write " << args.Get("--errors", "") << "\n";
      return kError;
    }
  }
  if (args.Has("--json")) {
    nlohmann::json json = {{"estimated", errors.estimated},
                           {"reference", errors.reference},
                           {"matched", errors.matched},
                           {"ate_rmse_m", errors.ate_rmse_m},
                           {"ate_mean_m", errors.ate_mean_m},
                           {"ate_median_m", errors.ate_median_m},
                           {"ate_max_m", errors.ate_max_m},
                           {"rpe_distance_m", config.rpe_distance_m},
                           {"rpe_pairs", errors.rpe_pairs},
                           {"rpe_translation_percent", errors.rpe_translation_percent},
                           {"rpe_rotation_deg_per_m", errors.rpe_rotation_deg_per_m}};
    std::cout << json.dump(2) << "\n";
    return kOk;
  }
  char text[512];
  std::snprintf(text, sizeof(text),
                "matched %zu of %zu estimated poses (reference: %zu poses)\n"
                "ATE RMSE %.4f m (mean %.4f, median %.4f, max %.4f) after rigid alignment\n",
                errors.matched, errors.estimated, errors.reference, errors.ate_rmse_m,
                errors.ate_mean_m, errors.ate_median_m, errors.ate_max_m);
  std::cout << text;
  if (errors.rpe_pairs == 0) {
    std::printf("RPE: none (the reference path is shorter than %.2f m)\n", config.rpe_distance_m);
  } else {
    std::printf("RPE over %.2f m: translation %.2f %%, rotation %.3f deg/m (%zu stretches)\n",
                config.rpe_distance_m, errors.rpe_translation_percent,
                errors.rpe_rotation_deg_per_m, errors.rpe_pairs);
  }
  return kOk;
}

}  // namespace objmap::cli
