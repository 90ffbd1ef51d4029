#include "dataset/frame_stream.h"

#include <algorithm>

namespace objmap {
namespace {

// Walks a range of a SequenceReader; the reader is random access, the stream only moves forward.
class SequenceStream : public FrameStream {
 public:
  SequenceStream(const SequenceReader& reader, std::size_t first_frame, std::size_t end)
      : reader_(reader),
        next_(first_frame),
        end_(std::max(first_frame, end)),
        size_(end_ - first_frame) {}

  FrameStatus Next(RgbdFrame* frame, std::string* why) override {
    if (next_ >= end_) return FrameStatus::kEnded;
    const std::size_t index = next_++;
    const bool read = reader_.ReadFrame(index, frame, why);
    // The sequence index is the frame's identity in reports, whatever the reader filled in.
    frame->frame_index = static_cast<std::int64_t>(index);
    return read ? FrameStatus::kFrame : FrameStatus::kBadFrame;
  }

  std::size_t size() const override { return size_; }
  std::string Describe() const override { return reader_.Describe(); }

 private:
  const SequenceReader& reader_;
  std::size_t next_;
  const std::size_t end_;
  const std::size_t size_;
};

}  // namespace

std::unique_ptr<FrameStream> MakeSequenceStream(const SequenceReader& reader,
                                                std::size_t first_frame, std::size_t max_frames) {
  const std::size_t end =
      max_frames == 0 ? reader.size() : std::min(reader.size(), first_frame + max_frames);
  return std::make_unique<SequenceStream>(reader, first_frame, end);
}

std::unique_ptr<FrameStream> SelectSequenceFrames(const SequenceReader& reader,
                                                  std::size_t first_frame, std::size_t max_frames,
                                                  std::string* why) {
  if (first_frame >= reader.size()) {
    *why = "no frames selected: first frame " + std::to_string(first_frame) + " of " +
           std::to_string(reader.size());
    return nullptr;
  }
  return MakeSequenceStream(reader, first_frame, max_frames);
}

}  // namespace objmap
