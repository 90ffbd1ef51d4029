// RunSequence over a FrameStream maps exactly what it maps over the SequenceReader behind it,
// on a small rendered scene (no data files needed).
#include <gtest/gtest.h>

#include "pipeline/sequence_runner.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// The mappers of these tests run at the defaults.
const MapperConfig kDefaultConfig;

using testing::SceneBox;

const std::vector<SceneBox> kBoxes = {{{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},
                                      {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},
                                      {{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}}};

CameraIntrinsics SmallCamera() {
  CameraIntrinsics K;
  K.width = 160;
  K.height = 120;
  K.fx = K.fy = 146.0;
  K.cx = 80.0;
  K.cy = 60.0;
  return K;
}

// Six rendered frames moving sideways; frame 3 cannot be read.
class RenderedSequence : public SequenceReader {
 public:
  std::size_t size() const override { return 6; }
  bool ReadFrame(std::size_t index, RgbdFrame* frame, std::string* why) const override {
    if (index == 3) {
      *why = "frame-000003.depth.png: unreadable";
      return false;
    }
    *frame = testing::RenderFrame(kBoxes, SmallCamera(), Pose(index), "");
    frame->frame_index = static_cast<std::int64_t>(index);
    frame->name = "frame-00000" + std::to_string(index);
    return true;
  }
  std::string Describe() const override { return "rendered table, 6 frames"; }
  static Eigen::Isometry3d Pose(std::size_t index) {
    return testing::LookAt({-1.0, -0.3 + 0.12 * index, 1.3}, Eigen::Vector3d(0, 0, 0.7));
  }
};

// Boxes of the two cups as seen from the frame's pose.
class CupDetector : public Detector {
 public:
  bool Detect(const RgbdFrame& frame, std::vector<Detection>* detections, std::string*) override {
    detections->clear();
    for (int cup = 1; cup <= 2; ++cup) {
      detections->push_back({testing::ProjectBox(kBoxes[cup], frame.T_W_C, frame.intrinsics),
                             CocoClassId("cup"), 0.7f});
    }
    return true;
  }
  std::string Name() const override { return "cups"; }
};

// Hides the stream's length, as a live camera does.
class UnknownLength : public FrameStream {
 public:
  explicit UnknownLength(std::unique_ptr<FrameStream> inner) : inner_(std::move(inner)) {}
  FrameStatus Next(RgbdFrame* frame, std::string* why) override { return inner_->Next(frame, why); }
  std::string Describe() const override { return inner_->Describe(); }

 private:
  std::unique_ptr<FrameStream> inner_;
};

struct MapRun {
  SequenceRunReport report;
  std::size_t objects = 0;
  std::size_t confirmed = 0;
  std::vector<std::size_t> totals;  // progress totals seen
  bool ok = false;
};

SequenceRunConfig EveryFrameFrom1To4() {
  SequenceRunConfig config;
  config.keyframes.every_nth_frame = 1;
  config.first_frame = 1;
  config.max_frames = 4;
  return config;
}

template <typename Source>
MapRun MapWith(Source&& source, const SequenceRunConfig& config) {
  MapRun run;
  CupDetector detector;
  MapperConfig mapper_config;
  mapper_config.inventory.min_observations = 2;
  Mapper mapper(mapper_config);
  std::string why;
  run.ok = RunSequence(
      source, &detector, &mapper, config,
      [&](std::size_t, std::size_t total, std::size_t) { run.totals.push_back(total); },
      &run.report, &why);
  EXPECT_TRUE(run.ok) << why;
  run.objects = mapper.objects().size();
  run.confirmed = mapper.ConfirmedObjects().size();
  return run;
}

TEST(SequenceRunnerStream, StreamMapsWhatTheReaderMaps) {
  const RenderedSequence sequence;
  const MapRun by_reader = MapWith(sequence, EveryFrameFrom1To4());
  // The same selection applied by the stream runner: frame 0 read and dropped, four frames.
  UnknownLength stream(MakeSequenceStream(sequence));
  const MapRun by_stream = MapWith(&stream, EveryFrameFrom1To4());

  ASSERT_EQ(by_reader.report.frames_read, 4u);
  EXPECT_EQ(by_stream.report.frames_read, 4u);
  ASSERT_EQ(by_reader.report.keyframes.size(), 3u);  // frames 1, 2 and 4; 3 is unreadable
  ASSERT_EQ(by_stream.report.keyframes.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(by_stream.report.keyframes[k].frame_index, by_reader.report.keyframes[k].frame_index);
    EXPECT_EQ(by_stream.report.keyframes[k].result.detections_used,
              by_reader.report.keyframes[k].result.detections_used);
  }
  EXPECT_EQ(by_reader.report.keyframes[2].frame_index, 4u);
  EXPECT_EQ(by_reader.report.skipped,
            std::vector<std::string>{"frame 3: frame-000003.depth.png: unreadable"});
  EXPECT_EQ(by_stream.report.skipped, by_reader.report.skipped);
  EXPECT_GE(by_reader.confirmed, 2u);  // both cups
  EXPECT_EQ(by_stream.objects, by_reader.objects);
  EXPECT_EQ(by_stream.confirmed, by_reader.confirmed);
  // Progress: the reader knows its total; a stream of unknown length reports max_frames.
  EXPECT_EQ(by_reader.totals, std::vector<std::size_t>(4, 4));
  EXPECT_EQ(by_stream.totals, std::vector<std::size_t>(4, 4));
}

TEST(SequenceRunnerStream, UnknownLengthWithoutLimitReportsTotalZeroAndReadsToTheEnd) {
  const RenderedSequence sequence;
  UnknownLength stream(MakeSequenceStream(sequence));
  SequenceRunConfig config;
  config.keyframes.every_nth_frame = 1;
  const MapRun run = MapWith(&stream, config);
  EXPECT_EQ(run.report.frames_read, 6u);
  EXPECT_EQ(run.totals, std::vector<std::size_t>(6, 0));
}

TEST(SequenceRunnerStream, StopOnBadFrameAndFailedStreamStopTheRun) {
  const RenderedSequence sequence;
  SequenceRunConfig config;
  config.stop_on_bad_frame = true;
  CupDetector detector;
  Mapper mapper{kDefaultConfig};
  SequenceRunReport report;
  std::string why;
  auto stream = MakeSequenceStream(sequence);
  EXPECT_FALSE(RunSequence(stream.get(), &detector, &mapper, config, nullptr, &report, &why));
  EXPECT_EQ(why, "frame 3: frame-000003.depth.png: unreadable");

  // A stream shorter than first_frame selects nothing.
  config.first_frame = 10;
  stream = MakeSequenceStream(sequence);
  EXPECT_FALSE(RunSequence(stream.get(), &detector, &mapper, config, nullptr, &report, &why));
  EXPECT_NE(why.find("no frames selected"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
