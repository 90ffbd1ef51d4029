#pragma once

#include <cstddef>

namespace objmap::cli {

/// A progress bar on stderr, redrawn only when it or the keyframe count changes so that a log
/// file stays short. Thread-safety: none.
class ProgressBar {
 public:
  /// Draws "[####....] done/total frames, keyframes keyframes"; ends the line when done == total.
  /// With total 0 (unknown: a live camera) draws "done frames, keyframes keyframes" instead.
  void Update(std::size_t done, std::size_t total, std::size_t keyframes);

 private:
  int last_filled_ = -1;
  std::size_t last_keyframes_ = 0;
};

}  // namespace objmap::cli
