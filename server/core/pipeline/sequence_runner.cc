#include "pipeline/sequence_runner.h"

#include <algorithm>
#include <chrono>

namespace objmap {
namespace {

using Clock = std::chrono::steady_clock;

// Maps one frame already read; false with a reason when it cannot be mapped.
bool MapFrame(const RgbdFrame& frame, Detector* detector, Mapper* mapper, KeyframeReport* report,
              std::string* why) {
  std::vector<Detection> detections;
  const auto start = Clock::now();
  if (!detector->Detect(frame, &detections, why)) return false;
  report->detection_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  report->detections = static_cast<int>(detections.size());
  return mapper->AddKeyframe(frame, detections, &report->result, why);
}

}  // namespace

bool SequenceRunConfig::IsValid(std::string* why) const { return keyframes.IsValid(why); }

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

bool RunSequence(const SequenceReader& reader, Detector* detector, Mapper* mapper,
                 const SequenceRunConfig& config, const ProgressCallback& progress,
                 SequenceRunReport* report, std::string* why) {
  if (!config.IsValid(why)) return false;
  const std::size_t end = config.max_frames == 0
                              ? reader.size()
                              : std::min(reader.size(), config.first_frame + config.max_frames);
  if (config.first_frame >= end) {
    *why = "no frames selected: first frame " + std::to_string(config.first_frame) + " of " +
           std::to_string(reader.size());
    return false;
  }
  KeyframeSelector selector(config.keyframes);
  const std::size_t total = end - config.first_frame;
  for (std::size_t index = config.first_frame; index < end; ++index) {
    RgbdFrame frame;
    std::string reason;
    bool ok = reader.ReadFrame(index, &frame, &reason);
    ++report->frames_read;
    if (ok && selector.IsKeyframe(frame.T_W_C)) {
      KeyframeReport keyframe;
      keyframe.frame_index = index;
      ok = MapFrame(frame, detector, mapper, &keyframe, &reason);
      if (ok) report->keyframes.push_back(std::move(keyframe));
    }
    if (!ok) {
      const std::string message = "frame " + std::to_string(index) + ": " + reason;
      if (config.stop_on_bad_frame) {
        *why = message;
        return false;
      }
      report->skipped.push_back(message);
    }
    if (progress) progress(index - config.first_frame + 1, total, report->keyframes.size());
  }
  return true;
}

}  // namespace objmap
