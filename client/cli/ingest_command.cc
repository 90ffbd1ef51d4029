// `objmap ingest`: the keyframes of a recorded sequence, streamed to a running server.
#include <algorithm>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.h"
#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "detection/detections_file.h"
#include "progress_bar.h"
#include "server_common.h"

namespace objmap::cli {
namespace {

constexpr char kIngestUsage[] =
    "objmap ingest: streams a recorded sequence's keyframes to a running server.\n"
    "usage: objmap ingest <dataset> [options]\n"
    "  <dataset>                 7-Scenes folder (frame-NNNNNN.*) or TUM RGB-D folder\n"
    "  --detections FILE         send the detections of this file (as written by `objmap map\n"
    "                            --save-detections`) with each keyframe; without it the server\n"
    "                            runs its own detector\n"
    "  --every-frame             every frame is a keyframe\n"
    "  --min-translation M       keyframe after this much motion, metres (default 0.10)\n"
    "  --min-rotation DEG        keyframe after this much rotation, degrees (default 10)\n"
    "  --first-frame N           first frame index (default 0)\n"
    "  --max-frames N            number of frames to read (default: all)\n"
    "  --max-keyframes N         stop after N keyframes (default: all)\n"
    "  --jpeg                    send colour as JPEG (default: lossless PNG)\n"
    "  --stop-on-error           stop at the first unreadable frame instead of skipping it\n";

constexpr char kCommand[] = "ingest";

struct IngestSettings {
  KeyframeSelectorConfig keyframes;
  std::size_t first_frame = 0;
  std::size_t max_frames = 0;     // 0: to the end
  std::size_t max_keyframes = 0;  // 0: all
  bool stop_on_error = false;
};

IngestSettings SettingsFrom(Arguments& args) {
  IngestSettings settings;
  settings.keyframes.every_nth_frame = args.Has("--every-frame") ? 1 : 0;
  settings.keyframes.min_translation_m =
      args.GetNumber("--min-translation", settings.keyframes.min_translation_m);
  settings.keyframes.min_rotation_deg =
      args.GetNumber("--min-rotation", settings.keyframes.min_rotation_deg);
  settings.first_frame = static_cast<std::size_t>(args.GetInteger("--first-frame", 0, 0));
  settings.max_frames = static_cast<std::size_t>(args.GetInteger("--max-frames", 0, 0));
  settings.max_keyframes = static_cast<std::size_t>(args.GetInteger("--max-keyframes", 0, 0));
  settings.stop_on_error = args.Has("--stop-on-error");
  return settings;
}

struct IngestCounts {
  std::size_t frames_read = 0;
  std::size_t keyframes_sent = 0;
  std::size_t skipped = 0;
  std::string stopped_at;  // the bad frame that ended the run with --stop-on-error
};

// Reads, selects and sends the frames. Returns the stream's status (OK when every keyframe was
// written); a bad frame is skipped with a message, or ends the run with --stop-on-error (the
// keyframes before it are still committed by Finish()).
grpc::Status SendFrames(const SequenceReader& reader, Detector* detections,
                        const IngestSettings& settings, const KeyframeEncoding& encoding,
                        IngestWriter* writer, IngestCounts* counts) {
  const std::size_t end = settings.max_frames == 0
                              ? reader.size()
                              : std::min(reader.size(), settings.first_frame + settings.max_frames);
  KeyframeSelector selector(settings.keyframes);
  ProgressBar bar;
  const std::size_t total = end - settings.first_frame;
  std::size_t done = 0;
  for (std::size_t index = settings.first_frame; index < end; ++index) {
    if (settings.max_keyframes > 0 && counts->keyframes_sent >= settings.max_keyframes) break;
    RgbdFrame frame;
    std::string why;
    std::vector<Detection> found;
    v1::AddKeyframeRequest request;
    bool ok = reader.ReadFrame(index, &frame, &why);
    ++counts->frames_read;
    if (ok && selector.IsKeyframe(frame.T_W_C)) {
      ok = (detections == nullptr || detections->Detect(frame, &found, &why)) &&
           MakeAddKeyframeRequest(frame, detections == nullptr ? nullptr : &found, encoding,
                                  &request, &why);
      if (ok) {
        const grpc::Status status = writer->Write(request);
        if (!status.ok()) return status;
        ++counts->keyframes_sent;
      }
    }
    if (!ok) {
      const std::string message = "frame " + std::to_string(index) + ": " + why;
      if (settings.stop_on_error) {
        counts->stopped_at = message;
        break;
      }
      std::cerr << "\nskipped " << message << "\n";
      ++counts->skipped;
    }
    done = index - settings.first_frame + 1;
    bar.Update(done, total, counts->keyframes_sent);
  }
  if (done != total) std::cerr << "\n";  // the bar stopped short of its end
  return grpc::Status::OK;
}

void PrintSummary(const IngestCounts& counts, const v1::IngestSummary& summary, double wall_s) {
  std::cout << "keyframes: " << summary.keyframes_added() << " added of " << counts.frames_read
            << " frames read";
  if (summary.keyframes_added() > 0) {
    std::cout << " (ids " << summary.first_keyframe_id() << ".." << summary.last_keyframe_id()
              << ")";
  }
  std::cout << "; skipped frames: " << counts.skipped << "\n"
            << "objects created: " << summary.objects_created() << "\n"
            << "map version: " << summary.map_version() << "\n"
            << "wall time: " << std::fixed << std::setprecision(1) << wall_s << " s\n";
}

// The sequence and, with --detections, the file detector; false with a reason naming the file.
bool OpenInputs(Arguments& args, const IngestSettings& settings,
                std::unique_ptr<SequenceReader>* reader, std::unique_ptr<Detector>* detections,
                std::string* why) {
  if (!settings.keyframes.IsValid(why)) return false;
  *reader = OpenSequence(args.positional()[0], why);
  if (!*reader) return false;
  if (settings.first_frame >= (*reader)->size()) {
    *why = "--first-frame " + std::to_string(settings.first_frame) + " is past the last frame (" +
           std::to_string((*reader)->size()) + " frames)";
    return false;
  }
  if (!args.Has("--detections")) return true;
  DetectionsFileConfig config;
  config.path = args.Get("--detections", "");
  *detections = MakeDetectionsFileDetector(config, why);
  return *detections != nullptr;
}

// Streams the keyframes and prints the summary; returns the exit code.
int Ingest(MapClient* client, const SequenceReader& reader, Detector* detections,
           const IngestSettings& settings) {
  const auto start = std::chrono::steady_clock::now();
  IngestCounts counts;
  std::unique_ptr<IngestWriter> writer = client->StartIngest();
  grpc::Status status =
      SendFrames(reader, detections, settings, client->options().encoding, writer.get(), &counts);
  if (!status.ok()) {
    std::cerr << "\nthe stream ended after " << counts.keyframes_sent << " keyframes were sent\n";
    return FailWithStatus(kCommand, status);
  }
  v1::IngestSummary summary;
  status = writer->Finish(&summary);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  PrintSummary(counts, summary,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!counts.stopped_at.empty()) return Fail(kCommand, "stopped at " + counts.stopped_at);
  return kExitOk;
}

}  // namespace

int RunIngestCommand(int argc, char** argv) {
  Arguments args(argc, argv,
                 WithServerFlags({"--detections", "--min-translation", "--min-rotation",
                                  "--first-frame", "--max-frames", "--max-keyframes"}),
                 {"--every-frame", "--jpeg", "--stop-on-error", "--help"});
  const std::string usage = std::string(kIngestUsage) + kServerOptionsUsage;
  if (args.Has("--help")) {
    std::cout << usage;
    return kExitOk;
  }
  const IngestSettings settings = SettingsFrom(args);
  MapClientOptions options;
  if (args.Has("--jpeg")) options.encoding.color = KeyframeEncoding::Color::kJpeg;
  std::unique_ptr<MapClient> client = MakeClient(args, 30.0, options);
  if (!args.error().empty() || args.positional().size() != 1) return UsageError(args, usage);

  std::unique_ptr<SequenceReader> reader;
  std::unique_ptr<Detector> detections;
  std::string why;
  if (!OpenInputs(args, settings, &reader, &detections, &why)) return Fail(kCommand, why);
  // A Status call first, so that an unreachable server is reported before any frame is read.
  v1::StatusResponse before;
  const grpc::Status status = client->Status(v1::StatusRequest(), &before);
  if (!status.ok()) return FailWithStatus(kCommand, status);
  std::cout << "ingesting " << reader->Describe() << " into " << client->address()
            << " (map version " << before.map_version() << ", " << before.keyframes()
            << " keyframes); detections from "
            << (detections ? args.Get("--detections", "") : "the server's detector") << std::endl;
  return Ingest(client.get(), *reader, detections.get(), settings);
}

}  // namespace objmap::cli
