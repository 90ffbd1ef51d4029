#include "progress_bar.h"

#include <algorithm>
#include <cstdio>
#include <string>

namespace objmap::cli {

void ProgressBar::Update(std::size_t done, std::size_t total, std::size_t keyframes) {
  constexpr int kWidth = 40;
  if (total == 0) {  // a live camera: no end known, so a counter instead of a bar
    if (done % 30 != 0 && keyframes == last_keyframes_) return;
    last_keyframes_ = keyframes;
    std::fprintf(stderr, "\r%zu frames, %zu keyframes", done, keyframes);
    return;
  }
  const int filled = static_cast<int>(kWidth * done / std::max<std::size_t>(total, 1));
  if (filled == last_filled_ && keyframes == last_keyframes_ && done != total) return;
  last_filled_ = filled;
  last_keyframes_ = keyframes;
  std::fprintf(stderr, "\r[%s%s] %zu/%zu frames, %zu keyframes", std::string(filled, '#').c_str(),
               std::string(kWidth - filled, '.').c_str(), done, total, keyframes);
  if (done == total) std::fprintf(stderr, "\n");
}

}  // namespace objmap::cli
