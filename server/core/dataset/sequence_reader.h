#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "types/frame.h"

namespace objmap {

/// Random access to the frames of a recorded RGB-D sequence.
/// Thread-safety: ReadFrame() is const and may be called from several threads.
class SequenceReader {
 public:
  virtual ~SequenceReader() = default;

  [[nodiscard]] virtual std::size_t size() const = 0;

  /// Loads frame `index` (colour, depth in metres, intrinsics, T_W_C). On failure returns false
  /// and says which file of which frame is wrong; the caller decides whether to skip it.
  [[nodiscard]] virtual bool ReadFrame(std::size_t index, RgbdFrame* frame,
                                       std::string* why) const = 0;

  /// "7-Scenes folder <path>, 1000 frames" and the like.
  [[nodiscard]] virtual std::string Describe() const = 0;
  /// False when the frames come without poses of their own (a bag without TF opened for a
  /// caller that estimates the poses): ReadFrame then gives them the identity.
  [[nodiscard]] virtual bool has_poses() const { return true; }
};

/// Opens a sequence folder, recognising the layout: 7-Scenes / 3DMatch (frame-NNNNNN.*) or TUM
/// RGB-D (rgb.txt, depth.txt, groundtruth.txt). Returns nullptr and a reason otherwise, including
/// for a folder with no frames.
[[nodiscard]] std::unique_ptr<SequenceReader> OpenSequence(const std::string& path,
                                                           std::string* why);

}  // namespace objmap
