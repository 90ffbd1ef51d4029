// CenterNet recall on rendered synthetic scenes (objmap_sim output), whole image against tiled
// inference in the same run, with the cost per image of each. The truth per frame is the box of
// each object's visible pixels in frame-NNNNNN.instance.png; a detection finds it when its class
// matches and its box overlaps by IoU >= 0.5 (greedy, best score first).
//   detector_bench MODEL STEP SCENE_DIR... [--tiles N]... [--overlap F] [--min-px N]
// e.g. detector_bench models/centernet_coco.pb 10 /tmp/s/desk-31 /tmp/s/office-31 --tiles 1
//      --tiles 2
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "detection/centernet_decode.h"
#include "detection/centernet_detector.h"
#include "types/coco_classes.h"

namespace {

using Clock = std::chrono::steady_clock;

struct TruthBox {
  objmap::BoundingBox2D box;
  int class_id = -1;
  int pixels = 0;
};

// Visible-pixel size bands (COCO's small / medium / large areas, here of visible pixels).
int Band(int pixels) { return pixels < 32 * 32 ? 0 : pixels < 96 * 96 ? 1 : 2; }
const char* const kBandNames[3] = {"small (<32x32 px)", "medium", "large (>96x96 px)"};

struct Tally {
  int truth[3] = {0, 0, 0};
  int found[3] = {0, 0, 0};
  int detections = 0;
  int correct = 0;
  double ms = 0.0;
  int images = 0;
  struct PerClass {
    int truth = 0, found = 0, detections = 0, correct = 0;
  };
  std::map<int, PerClass> per_class;
};

std::map<int, int> ReadClasses(const std::string& scene_dir) {
  std::ifstream in(scene_dir + "/ground_truth.json");
  std::map<int, int> classes;
  if (!in) return classes;
  const nlohmann::json truth = nlohmann::json::parse(in, nullptr, false);
  if (truth.is_discarded() || !truth.contains("objects")) return classes;
  for (const auto& object : truth["objects"]) {
    classes[object["id"].get<int>()] = objmap::CocoClassId(object["class"].get<std::string>());
  }
  return classes;
}

std::vector<TruthBox> TruthOf(const cv::Mat& instance, const std::map<int, int>& classes,
                              int min_px) {
  std::map<int, TruthBox> boxes;
  for (int v = 0; v < instance.rows; ++v) {
    for (int u = 0; u < instance.cols; ++u) {
      const int id = instance.at<std::uint16_t>(v, u);
      if (id == 0) continue;
      auto [it, fresh] = boxes.try_emplace(id);
      TruthBox& t = it->second;
      const float x = static_cast<float>(u), y = static_cast<float>(v);
      if (fresh) t.box = {x, y, x + 1.f, y + 1.f};
      t.box.x_min = std::min(t.box.x_min, x), t.box.x_max = std::max(t.box.x_max, x + 1.f);
      t.box.y_min = std::min(t.box.y_min, y), t.box.y_max = std::max(t.box.y_max, y + 1.f);
      ++t.pixels;
    }
  }
  std::vector<TruthBox> result;
  for (auto& [id, t] : boxes) {
    const auto known = classes.find(id);
    if (known == classes.end() || known->second < 0 || t.pixels < min_px) continue;
    t.class_id = known->second;
    result.push_back(t);
  }
  return result;
}

void Score(const std::vector<objmap::Detection>& detections, const std::vector<TruthBox>& truth,
           Tally* tally) {
  std::vector<bool> taken(truth.size(), false);
  for (const objmap::Detection& d : detections) {  // best first
    int best = -1;
    float best_iou = 0.5f;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (taken[i] || truth[i].class_id != d.class_id) continue;
      const float iou = objmap::BoxIoU(d.box, truth[i].box);
      if (iou >= best_iou) best_iou = iou, best = static_cast<int>(i);
    }
    ++tally->detections;
    ++tally->per_class[d.class_id].detections;
    if (best >= 0) {
      taken[static_cast<std::size_t>(best)] = true;
      ++tally->correct;
      ++tally->per_class[d.class_id].correct;
    }
  }
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const int band = Band(truth[i].pixels);
    ++tally->truth[band];
    Tally::PerClass& per_class = tally->per_class[truth[i].class_id];
    ++per_class.truth;
    if (taken[i]) {
      ++tally->found[band];
      ++per_class.found;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr,
                 "usage: detector_bench MODEL STEP SCENE_DIR... [--tiles N]... [--overlap F] "
                 "[--min-px N]\n");
    return 2;
  }
  const std::string model = argv[1];
  const int step = std::max(1, std::atoi(argv[2]));
  std::vector<std::string> scenes;
  std::vector<int> tile_settings;
  float overlap = objmap::CenterNetConfig().tile_overlap;
  int min_px = 150;  // objmap_sim's ground-truth detector never reports fewer visible pixels
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--tiles" && i + 1 < argc) {
      tile_settings.push_back(std::atoi(argv[++i]));
    } else if (arg == "--overlap" && i + 1 < argc) {
      overlap = static_cast<float>(std::atof(argv[++i]));
    } else if (arg == "--min-px" && i + 1 < argc) {
      min_px = std::atoi(argv[++i]);
    } else {
      scenes.push_back(arg);
    }
  }
  if (tile_settings.empty()) tile_settings = {1, 2};

  std::vector<std::unique_ptr<objmap::Detector>> detectors;
  for (int tiles : tile_settings) {
    objmap::CenterNetConfig config;
    config.model_path = model;
    config.tiles_per_side = tiles;
    config.tile_overlap = overlap;
    config.num_threads = 1;
    std::string why;
    detectors.push_back(objmap::MakeCenterNetDetector(config, &why));
    if (!detectors.back()) {
      std::fprintf(stderr, "detector_bench: %s\n", why.c_str());
      return 1;
    }
  }
  std::vector<Tally> tallies(detectors.size());
  for (const std::string& scene : scenes) {
    const std::map<int, int> classes = ReadClasses(scene);
    if (classes.empty()) {
      std::fprintf(stderr, "detector_bench: %s/ground_truth.json is missing or unreadable\n",
                   scene.c_str());
      return 1;
    }
    std::vector<Tally> in_scene(detectors.size());
    for (int index = 0;; index += step) {
      char stem[64];
      std::snprintf(stem, sizeof(stem), "/frame-%06d", index);
      // The sequence ends at the first missing frame (imread would warn about it).
      if (!std::filesystem::exists(scene + stem + ".color.png")) break;
      const cv::Mat bgr = cv::imread(scene + stem + ".color.png", cv::IMREAD_COLOR);
      const cv::Mat instance = cv::imread(scene + stem + ".instance.png", cv::IMREAD_UNCHANGED);
      if (bgr.empty() || instance.empty()) break;
      cv::Mat rgb;
      cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
      objmap::RgbdFrame frame;
      frame.frame_index = index;
      frame.color.width = rgb.cols;
      frame.color.height = rgb.rows;
      frame.color.rgb.assign(rgb.data, rgb.data + rgb.total() * 3);
      const std::vector<TruthBox> truth = TruthOf(instance, classes, min_px);
      for (std::size_t k = 0; k < detectors.size(); ++k) {
        std::vector<objmap::Detection> detections;
        std::string why;
        const auto start = Clock::now();
        if (!detectors[k]->Detect(frame, &detections, &why)) {
          std::fprintf(stderr, "detector_bench: %s\n", why.c_str());
          return 1;
        }
        in_scene[k].ms += std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        ++in_scene[k].images;
        Score(detections, truth, &in_scene[k]);
      }
    }
    for (std::size_t k = 0; k < detectors.size(); ++k) {
      const Tally& t = in_scene[k];
      const int truth = t.truth[0] + t.truth[1] + t.truth[2];
      const int found = t.found[0] + t.found[1] + t.found[2];
      std::printf("%-28s tiles %d: %3d images, recall %.3f (%d/%d), precision %.3f\n",
                  scene.c_str(), tile_settings[k], t.images, truth ? 1.0 * found / truth : 0.0,
                  found, truth, t.detections ? 1.0 * t.correct / t.detections : 0.0);
      Tally& all = tallies[k];
      for (int b = 0; b < 3; ++b) all.truth[b] += t.truth[b], all.found[b] += t.found[b];
      all.detections += t.detections, all.correct += t.correct;
      all.ms += t.ms, all.images += t.images;
      for (const auto& [c, counts] : t.per_class) {
        Tally::PerClass& sum = all.per_class[c];
        sum.truth += counts.truth, sum.found += counts.found;
        sum.detections += counts.detections, sum.correct += counts.correct;
      }
    }
  }
  std::printf("\npooled over %zu scenes, every %d-th frame, objects >= %d visible px:\n",
              scenes.size(), step, min_px);
  for (std::size_t k = 0; k < detectors.size(); ++k) {
    const Tally& t = tallies[k];
    const int truth = t.truth[0] + t.truth[1] + t.truth[2];
    const int found = t.found[0] + t.found[1] + t.found[2];
    std::printf("tiles %d: recall %.3f (%d/%d), precision %.3f (%d/%d), %.1f ms per image\n",
                tile_settings[k], truth ? 1.0 * found / truth : 0.0, found, truth,
                t.detections ? 1.0 * t.correct / t.detections : 0.0, t.correct, t.detections,
                t.images ? t.ms / t.images : 0.0);
    for (int b = 0; b < 3; ++b) {
      std::printf("    %-18s recall %.3f (%d/%d)\n", kBandNames[b],
                  t.truth[b] ? 1.0 * t.found[b] / t.truth[b] : 0.0, t.found[b], t.truth[b]);
    }
  }
  std::printf(
      "\nper class: truth boxes; for each setting, found (recall) and detections (precision)\n");
  std::map<int, int> truth_per_class;
  for (const Tally& t : tallies) {
    for (const auto& [c, counts] : t.per_class) truth_per_class[c] = counts.truth;
  }
  for (const auto& [c, truth] : truth_per_class) {
    std::printf("  %-14s %5d", std::string(objmap::CocoClassName(c)).c_str(), truth);
    for (const Tally& t : tallies) {
      const auto it = t.per_class.find(c);
      const Tally::PerClass counts = it == t.per_class.end() ? Tally::PerClass{} : it->second;
      std::printf("  | %5d (%.2f) %5d (%.2f)", counts.found,
                  truth ? 1.0 * counts.found / truth : 0.0, counts.detections,
                  counts.detections ? 1.0 * counts.correct / counts.detections : 0.0);
    }
    std::printf("\n");
  }
  return 0;
}
