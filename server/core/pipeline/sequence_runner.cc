#include "pipeline/sequence_runner.h"

#include <algorithm>
#include <chrono>

namespace objmap {
namespace {

using Clock = std::chrono::steady_clock;

// Maps one frame already read; false with a reason when it cannot be mapped.
bool MapFrame(const RgbdFrame& frame, Detector* detector, const KeyframeSink& sink,
              KeyframeReport* report, std::string* why) {
  std::vector<Detection> detections;
  const auto start = Clock::now();
  if (!detector->Detect(frame, &detections, why)) return false;
  report->detection_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  report->detections = static_cast<int>(detections.size());
  return sink(frame, detections, &report->result, why);
}

KeyframeSink MapperSink(Mapper* mapper) {
  return [mapper](const RgbdFrame& frame, const std::vector<Detection>& detections,
                  KeyframeResult* result, std::string* why) {
    return mapper->AddKeyframe(frame, detections, result, why);
  };
}

// Frames the run will read when the stream knows its length, else 0.
std::size_t ExpectedFrames(const FrameStream& stream, const SequenceRunConfig& config) {
  if (stream.size() == 0) return config.max_frames;
  const std::size_t left =
      stream.size() > config.first_frame ? stream.size() - config.first_frame : 0;
  return config.max_frames == 0 ? left : std::min(left, config.max_frames);
}

// Reads and drops the frames before first_frame; false when the stream fails or ends first.
bool SkipFrames(FrameStream* stream, std::size_t count, std::string* why) {
  RgbdFrame frame;
  for (std::size_t skipped = 0; skipped < count; ++skipped) {
    std::string reason;
    const FrameStatus status = stream->Next(&frame, &reason);
    if (status == FrameStatus::kEnded || status == FrameStatus::kFailed) {
      *why = "no frames selected: the stream has " + std::to_string(skipped) +
             " frames before first frame " + std::to_string(count) +
             (reason.empty() ? "" : " (" + reason + ")");
      return false;
    }
  }
  return true;
}

}  // namespace

bool SequenceRunConfig::IsValid(std::string* why) const { return keyframes.IsValid(why); }

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

bool RunSequence(FrameStream* stream, Detector* detector, Mapper* mapper,
                 const SequenceRunConfig& config, const ProgressCallback& progress,
                 SequenceRunReport* report, std::string* why) {
  return RunSequence(stream, detector, MapperSink(mapper), config, progress, report, why);
}

bool RunSequence(FrameStream* stream, Detector* detector, const KeyframeSink& sink,
                 const SequenceRunConfig& config, const ProgressCallback& progress,
                 SequenceRunReport* report, std::string* why) {
  if (!config.IsValid(why)) return false;
  const std::size_t total = ExpectedFrames(*stream, config);
  if (!SkipFrames(stream, config.first_frame, why)) return false;
  KeyframeSelector selector(config.keyframes);
  for (std::size_t done = 0; config.max_frames == 0 || done < config.max_frames; ++done) {
    RgbdFrame frame;
    std::string reason;
    const FrameStatus status = stream->Next(&frame, &reason);
    if (status == FrameStatus::kEnded) break;
    if (status == FrameStatus::kFailed) {
      *why = stream->Describe() + ": " + reason;
      return false;
    }
    ++report->frames_read;
    bool ok = status == FrameStatus::kFrame;
    if (ok && selector.IsKeyframe(frame.T_W_C)) {
      KeyframeReport keyframe;
      keyframe.frame_index = static_cast<std::size_t>(frame.frame_index);
      ok = MapFrame(frame, detector, sink, &keyframe, &reason);
      if (ok) report->keyframes.push_back(std::move(keyframe));
    }
    if (!ok) {
      const std::string message = "frame " + std::to_string(frame.frame_index) + ": " + reason;
      if (config.stop_on_bad_frame) {
        *why = message;
        return false;
      }
      report->skipped.push_back(message);
    }
    if (progress) progress(done + 1, total, report->keyframes.size());
  }
  return true;
}

bool RunSequence(const SequenceReader& reader, Detector* detector, Mapper* mapper,
                 const SequenceRunConfig& config, const ProgressCallback& progress,
                 SequenceRunReport* report, std::string* why) {
  if (!config.IsValid(why)) return false;
  // The selection is applied by random access here, not by reading and dropping frames.
  const auto stream = SelectSequenceFrames(reader, config.first_frame, config.max_frames, why);
  if (!stream) return false;
  SequenceRunConfig stream_config = config;
  stream_config.first_frame = 0;
  stream_config.max_frames = 0;
  return RunSequence(stream.get(), detector, mapper, stream_config, progress, report, why);
}

}  // namespace objmap
