#include "detection/detections_file.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

#include "types/coco_classes.h"

namespace objmap {
namespace {

using nlohmann::json;

void SetWhy(std::string* why, const std::string& text) {
  if (why != nullptr) *why = text;
}

bool ParseBox(const json& box, BoundingBox2D* out, std::string* problem) {
  if (!box.is_array() || box.size() != 4) {
    *problem = "\"box\" must be an array [x_min, y_min, x_max, y_max]";
    return false;
  }
  float v[4];
  for (int i = 0; i < 4; ++i) {
    if (!box[i].is_number() || !std::isfinite(box[i].get<double>())) {
      *problem = "\"box\" values must be finite numbers";
      return false;
    }
    v[i] = box[i].get<float>();
  }
  if (v[2] < v[0] || v[3] < v[1]) {
    *problem = "\"box\" has x_max < x_min or y_max < y_min";
    return false;
  }
  *out = BoundingBox2D{v[0], v[1], v[2], v[3]};
  return true;
}

bool ParseEntry(const json& entry, Detection* out, std::string* problem) {
  if (!entry.is_object()) {
    *problem = "entry must be an object";
    return false;
  }
  if (!entry.contains("box") || !ParseBox(entry["box"], &out->box, problem)) {
    if (problem->empty()) *problem = "missing \"box\"";
    return false;
  }
  if (!entry.contains("class") || !entry["class"].is_string()) {
    *problem = "missing or non-string \"class\"";
    return false;
  }
  const std::string name = entry["class"].get<std::string>();
  out->class_id = CocoClassId(name);
  if (out->class_id < 0) {
    *problem = "unknown class \"" + name + "\" (expected a COCO class name)";
    return false;
  }
  out->score = 1.f;
  if (entry.contains("score")) {
    const json& score = entry["score"];
    if (!score.is_number() || !(score.get<double>() >= 0.0 && score.get<double>() <= 1.0)) {
      *problem = "\"score\" must be a number in [0, 1]";
      return false;
    }
    out->score = score.get<float>();
  }
  return true;
}

bool ParseFrame(const std::string& key, const json& entries, std::vector<Detection>* out,
                std::string* why) {
  if (!entries.is_array()) {
    SetWhy(why, "frame \"" + key + "\": detections must be an array");
    return false;
  }
  out->resize(entries.size());
  for (std::size_t i = 0; i < entries.size(); ++i) {
    std::string problem;
    if (!ParseEntry(entries[i], &(*out)[i], &problem)) {
      SetWhy(why, "frame \"" + key + "\" entry " + std::to_string(i) + ": " + problem);
      return false;
    }
  }
  return true;
}

json EntryToJson(const Detection& d) {
  return json{{"box", {d.box.x_min, d.box.y_min, d.box.x_max, d.box.y_max}},
              {"class", std::string(CocoClassName(d.class_id))},
              {"score", d.score}};
}

class DetectionsFileDetector final : public Detector {
 public:
  DetectionsFileDetector(DetectionsFileConfig config, DetectionsByFrame frames)
      : config_(std::move(config)), frames_(std::move(frames)) {}

  bool Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
              std::string* why) override {
    detections->clear();
    auto it = frame.name.empty() ? frames_.end() : frames_.find(frame.name);
    if (it == frames_.end()) it = frames_.find(std::to_string(frame.frame_index));
    if (it != frames_.end()) {
      *detections = it->second;
      return true;
    }
    if (!config_.require_every_frame) return true;
    SetWhy(why, config_.path + ": no detections for frame \"" + frame.name + "\" (index " +
                    std::to_string(frame.frame_index) + ")");
    return false;
  }

  std::string Name() const override { return "file"; }

 private:
  DetectionsFileConfig config_;
  DetectionsByFrame frames_;
};

}  // namespace

bool ParseDetectionsJson(const std::string& text, DetectionsByFrame* frames, std::string* why) {
  frames->clear();
  const json root = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) {
    SetWhy(why, "not valid JSON");
    return false;
  }
  if (!root.is_object() || !root.contains("frames") || !root["frames"].is_object()) {
    SetWhy(why, "top level must be an object with a \"frames\" object");
    return false;
  }
  for (const auto& [key, entries] : root["frames"].items()) {
    if (!ParseFrame(key, entries, &(*frames)[key], why)) {
      frames->clear();
      return false;
    }
  }
  return true;
}

bool ReadDetectionsFile(const std::string& path, DetectionsByFrame* frames, std::string* why) {
  std::ifstream in(path);
  if (!in) {
    SetWhy(why, path + ": cannot open detections file");
    return false;
  }
  std::ostringstream text;
  text << in.rdbuf();
  std::string problem;
  if (!ParseDetectionsJson(text.str(), frames, &problem)) {
    SetWhy(why, path + ": " + problem);
    return false;
  }
  return true;
}

bool WriteDetectionsFile(const std::string& path, const DetectionsByFrame& frames,
                         std::string* why) {
  json out_frames = json::object();
  for (const auto& [key, detections] : frames) {
    json entries = json::array();
    for (std::size_t i = 0; i < detections.size(); ++i) {
      if (CocoClassName(detections[i].class_id).empty()) {
        SetWhy(why, path + ": frame \"" + key + "\" entry " + std::to_string(i) +
                        ": invalid class id " + std::to_string(detections[i].class_id));
        return false;
      }
      entries.push_back(EntryToJson(detections[i]));
    }
    out_frames[key] = std::move(entries);
  }
  std::ofstream out(path);
  out << json{{"frames", out_frames}}.dump(1) << '\n';
  if (!out) {
    SetWhy(why, path + ": cannot write detections file");
    return false;
  }
  return true;
}

bool DetectionsFileConfig::IsValid(std::string* why) const {
  if (path.empty()) {
    SetWhy(why, "detections file: path is empty");
    return false;
  }
  return true;
}

std::unique_ptr<Detector> MakeDetectionsFileDetector(const DetectionsFileConfig& config,
                                                     std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  DetectionsByFrame frames;
  if (!ReadDetectionsFile(config.path, &frames, why)) return nullptr;
  return std::make_unique<DetectionsFileDetector>(config, std::move(frames));
}

}  // namespace objmap
