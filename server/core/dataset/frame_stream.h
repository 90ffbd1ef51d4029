#pragma once
// Frames in order, one at a time: what a live camera, a recording played back and a recorded
// sequence folder have in common. The mapping loop (pipeline/sequence_runner.h) reads only this.

#include <cstddef>
#include <memory>
#include <string>

#include "dataset/sequence_reader.h"
#include "types/frame.h"

namespace objmap {

/// What FrameStream::Next() produced.
enum class FrameStatus {
  kFrame,     ///< `frame` holds the next frame
  kBadFrame,  ///< this frame cannot be used (`why` says why); later ones may be fine
  kEnded,     ///< no more frames: end of a recording, or the stream was asked to stop
  kFailed,    ///< the stream cannot go on (camera lost, file unreadable); `why` says why
};

/// A source of RGB-D frames read in order. Unlike SequenceReader it need not be random access or
/// know its length, so a live camera fits. Thread-safety: none; one reader at a time.
class FrameStream {
 public:
  virtual ~FrameStream() = default;

  /// Reads the next frame. On kBadFrame, frame->frame_index still names the frame that failed,
  /// so that a skipped frame can be reported.
  [[nodiscard]] virtual FrameStatus Next(RgbdFrame* frame, std::string* why) = 0;

  /// Frames this stream will deliver in all, when known; 0 when unknown (a live camera).
  [[nodiscard]] virtual std::size_t size() const { return 0; }

  /// "7-Scenes folder <path>, 1000 frames", "OpenNI2 device <uri>" and the like.
  [[nodiscard]] virtual std::string Describe() const = 0;
};

/// Frames first_frame .. first_frame + max_frames - 1 of `reader` (max_frames 0: to the end), in
/// order. `reader` must outlive the stream. A frame that cannot be read is a kBadFrame.
[[nodiscard]] std::unique_ptr<FrameStream> MakeSequenceStream(const SequenceReader& reader,
                                                              std::size_t first_frame = 0,
                                                              std::size_t max_frames = 0);

/// MakeSequenceStream for a selection that must hold a frame: nullptr and "no frames selected:
/// first frame F of N" when first_frame is not a frame of `reader`.
[[nodiscard]] std::unique_ptr<FrameStream> SelectSequenceFrames(const SequenceReader& reader,
                                                                std::size_t first_frame,
                                                                std::size_t max_frames,
                                                                std::string* why);

}  // namespace objmap
