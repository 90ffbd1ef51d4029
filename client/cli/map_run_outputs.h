#pragma once
// What a run of `objmap map` leaves besides the map itself, shared by a run into a new folder
// (--out) and a run added to a map folder (--map): the detections and keyframe images seen, the
// per-keyframe timings.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "detection/detections_file.h"
#include "detection/detector.h"
#include "pipeline/sequence_runner.h"

namespace objmap::cli {

/// Wraps a detector and keeps what it found per frame (for --save-detections) and the JPEG of
/// each keyframe's colour image (for the map folder's keyframes/).
class RecordingDetector : public Detector {
 public:
  explicit RecordingDetector(std::unique_ptr<Detector> inner) : inner_(std::move(inner)) {}
  bool Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
              std::string* why) override;
  std::string Name() const override { return inner_->Name(); }
  const DetectionsByFrame& recorded() const { return recorded_; }
  /// Frame index -> the JPEG of its colour image.
  const std::map<std::int64_t, std::vector<std::uint8_t>>& keyframe_jpegs() const {
    return keyframe_jpegs_;
  }

 private:
  std::unique_ptr<Detector> inner_;
  DetectionsByFrame recorded_;
  std::map<std::int64_t, std::vector<std::uint8_t>> keyframe_jpegs_;
};

/// keyframes/<keyframe id>.jpg in `dir`: the colour image of each keyframe the run mapped.
[[nodiscard]] bool WriteKeyframeImages(const SequenceRunReport& report,
                                       const std::map<std::int64_t, std::vector<std::uint8_t>>& jpegs,
                                       const std::string& dir, std::string* why);

/// timings.csv: per keyframe of the run, the time of each stage.
[[nodiscard]] bool WriteTimings(const SequenceRunReport& report, const std::string& path,
                                std::string* why);

}  // namespace objmap::cli
