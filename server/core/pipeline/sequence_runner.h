#pragma once
// Runs a stream of frames (a recorded sequence, a recording, a live camera) through detector and
// mapper: the body of `objmap map`.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "dataset/frame_stream.h"
#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "detection/detector.h"
#include "mapper/mapper.h"

namespace objmap {

/// Which frames of a sequence are mapped and what happens with bad ones.
struct SequenceRunConfig {
  KeyframeSelectorConfig keyframes;
  /// Frames to pass over before the first one mapped (a sequence folder: the first frame index).
  std::size_t first_frame = 0;
  /// Number of frames to read from first_frame; 0 reads to the end of the stream.
  std::size_t max_frames = 0;
  /// A frame that cannot be read or mapped stops the run (true) or is skipped with a message
  /// naming its file (false, the default).
  bool stop_on_bad_frame = false;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Per-keyframe record of a run, for timings and reports.
struct KeyframeReport {
  std::size_t frame_index = 0;  ///< RgbdFrame::frame_index of the keyframe
  double detection_ms = 0.0;
  int detections = 0;
  KeyframeResult result;
};

struct SequenceRunReport {
  std::size_t frames_read = 0;
  std::vector<KeyframeReport> keyframes;
  std::vector<std::string> skipped;  ///< one message per skipped frame, naming the file
};

/// Called after every frame: (frames done, frames in total or 0 when the stream does not know,
/// keyframes so far).
using ProgressCallback = std::function<void(std::size_t, std::size_t, std::size_t)>;

/// Maps one keyframe with its detections: Mapper::AddKeyframe, or a map server's AddKeyframe
/// when the run adds to a stored map. False with the reason when the keyframe is not mapped.
using KeyframeSink = std::function<bool(const RgbdFrame& frame,
                                        const std::vector<Detection>& detections,
                                        KeyframeResult* result, std::string* why)>;

/// Runs the frames of `stream` in order until it ends or max_frames were read: keyframe selection
/// by camera motion, then detection and `sink`. Returns false only when the run stops (bad frame
/// with stop_on_bad_frame, a failed stream); `why` names the frame and the problem.
[[nodiscard]] bool RunSequence(FrameStream* stream, Detector* detector, const KeyframeSink& sink,
                               const SequenceRunConfig& config, const ProgressCallback& progress,
                               SequenceRunReport* report, std::string* why);

/// Maps the frames of `stream` in order until it ends or max_frames were read: keyframe selection
/// by camera motion, then detection and Mapper::AddKeyframe. Returns false only when the run
/// stops (bad frame with stop_on_bad_frame, a failed stream); `why` names the frame and the
/// problem. A stream that fails after frames were mapped keeps what was mapped in `mapper`.
[[nodiscard]] bool RunSequence(FrameStream* stream, Detector* detector, Mapper* mapper,
                               const SequenceRunConfig& config, const ProgressCallback& progress,
                               SequenceRunReport* report, std::string* why);

/// The same over a recorded sequence, reading only the frames selected (random access); false
/// also for an empty selection.
[[nodiscard]] bool RunSequence(const SequenceReader& reader, Detector* detector, Mapper* mapper,
                               const SequenceRunConfig& config, const ProgressCallback& progress,
                               SequenceRunReport* report, std::string* why);

/// Median of a list of values (0 for an empty list).
[[nodiscard]] double Median(std::vector<double> values);

}  // namespace objmap
