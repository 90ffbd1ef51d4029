// `objmap ingest`: the keyframes of a recorded sequence, streamed to a running server.
#include <algorithm>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <set>

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
    "  --stop-on-error           stop at the first unreadable frame instead of skipping it\n"
    "  --resume                  skip the keyframes the server already holds (by name): goes on\n"
    "                            after a run that a server crash or restart cut short\n"
    "  --session NAME            start a new session named NAME first (a new run into the same\n"
    "                            map; with estimated poses the server places its first keyframe\n"
    "                            in the saved map by relocalisation); without it the keyframes\n"
    "                            join the server's current session\n";

constexpr char kCommand[] = "ingest";

struct IngestSettings {
  KeyframeSelectorConfig keyframes;
  std::size_t first_frame = 0;
  std::size_t max_frames = 0;     // 0: to the end
  std::size_t max_keyframes = 0;  // 0: all
  bool stop_on_error = false;
  bool resume = false;
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
  settings.resume = args.Has("--resume");
  return settings;
}

struct IngestCounts {
  std::size_t frames_read = 0;
  std::size_t keyframes_sent = 0;
  std::size_t skipped = 0;
  std::size_t already_held = 0;  // keyframes --resume found on the server
  std::string stopped_at;  // the bad frame that ended the run with --stop-on-error
};

// The names of the keyframes the server holds, read page by page.
grpc::Status HeldKeyframeNames(MapClient* client, std::set<std::string>* names) {
  v1::ListKeyframesRequest request;
  request.set_max_results(1000);
  while (true) {
    v1::ListKeyframesResponse page;
    const grpc::Status status = client->ListKeyframes(request, &page);
    if (!status.ok()) return status;
    for (const v1::KeyframeInfo& keyframe : page.keyframes()) names->insert(keyframe.name());
    if (page.keyframes_size() < request.max_results()) return grpc::Status::OK;
    request.set_first_id(page.keyframes(page.keyframes_size() - 1).id() + 1);
  }
}

// Reads, selects and sends the frames. Returns the stream's status (OK when every keyframe was
// written); a bad frame is skipped with a message, or ends the run with --stop-on-error (the
// keyframes before it are still committed by Finish()).
grpc::Status SendFrames(const SequenceReader& reader, Detector* detections,
                        const IngestSettings& settings, const KeyframeEncoding& encoding,
                        const std::set<std::string>& held, IngestWriter* writer,
                        IngestCounts* counts) {
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
    // The selector sees every frame, held or not, so a resumed run picks the same keyframes.
    const bool keyframe = ok && selector.IsKeyframe(frame.T_W_C);
    if (keyframe && held.count(frame.name) > 0) {
      ++counts->already_held;
    } else if (keyframe) {
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
  if (counts.already_held > 0) std::cout << ", " << counts.already_held << " already held";
  if (summary.keyframes_added() > 0) {
    std::cout << " (ids " << summary.first_keyframe_id() << ".." << summary.last_keyframe_id()
              << ")";
  }
  std::cout << "; skipped frames: " << counts.skipped << "\n";
  if (summary.keyframes_repeated() > 0 || summary.keyframes_repeated_in_part() > 0) {
    std::cout << "keyframes kept as revisits of stored views (the same view, nothing changed; "
                 "not stored again): "
              << summary.keyframes_repeated() << "; mapped with only the part new to the map: "
              << summary.keyframes_repeated_in_part() << "\n";
  }
  if (summary.keyframes_untracked() > 0) {
    // With estimated poses: keyframes the server could not place, skipped by it.
    std::cout << "keyframes the server could not place when they came: "
              << summary.keyframes_untracked() << " (" << summary.keyframes_held()
              << " held in a provisional part of the session, " << summary.keyframes_attached()
              << " of them mapped once a later keyframe placed it)\n";
    for (const std::string& reason : summary.untracked()) std::cerr << "  " << reason << "\n";
  }
  std::cout << "objects created: " << summary.objects_created() << "\n"
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

// After a failed stream: how many of this run's keyframes the server acknowledged (committed),
// from its keyframe count before and now, and how to go on.
void PrintAcknowledged(MapClient* client, std::int64_t keyframes_before, std::size_t sent) {
  v1::StatusResponse now;
  if (client->Status(v1::StatusRequest(), &now).ok()) {
    std::cerr << "\n" << now.keyframes() - keyframes_before << " of the " << sent
              << " keyframes sent were acknowledged (stored); ";
  } else {
    std::cerr << "\n" << sent << " keyframes were sent; the server does not answer, so how many "
              << "it stored is not known; ";
  }
  std::cerr << "run again with --resume to send only the keyframes it does not hold\n";
}

// Streams the keyframes and prints the summary; returns the exit code.
int Ingest(MapClient* client, const SequenceReader& reader, Detector* detections,
           const IngestSettings& settings, std::int64_t keyframes_before) {
  const auto start = std::chrono::steady_clock::now();
  IngestCounts counts;
  std::set<std::string> held;
  if (settings.resume) {
    const grpc::Status listed = HeldKeyframeNames(client, &held);
    if (!listed.ok()) return FailWithStatus(kCommand, listed);
    std::cout << "resuming: the server holds " << held.size()
              << " keyframes; frames it holds by name are not sent again" << std::endl;
  }
  std::unique_ptr<IngestWriter> writer = client->StartIngest();
  grpc::Status status = SendFrames(reader, detections, settings, client->options().encoding, held,
                                   writer.get(), &counts);
  v1::IngestSummary summary;
  if (status.ok()) status = writer->Finish(&summary);
  if (!status.ok()) {
    PrintAcknowledged(client, keyframes_before, counts.keyframes_sent);
    return FailWithStatus(kCommand, status);
  }
  PrintSummary(counts, summary,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!counts.stopped_at.empty()) return Fail(kCommand, "stopped at " + counts.stopped_at);
  return kExitOk;
}

}  // namespace

int RunIngestCommand(int argc, char** argv) {
  Arguments args(argc, argv,
                 WithServerFlags({"--detections", "--min-translation", "--min-rotation",
                                  "--first-frame", "--max-frames", "--max-keyframes",
                                  "--session"}),
                 {"--every-frame", "--jpeg", "--stop-on-error", "--resume", "--help"});
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
  if (args.Has("--session")) {
    v1::StartSessionRequest request;
    request.set_name(args.Get("--session", ""));
    v1::Session started;
    const grpc::Status session = client->StartSession(request, &started);
    if (!session.ok()) return FailWithStatus(kCommand, session);
    std::cout << "started session " << started.id() << " \"" << started.name() << "\""
              << std::endl;
  }
  std::cout << "ingesting " << reader->Describe() << " into " << client->address()
            << " (map version " << before.map_version() << ", " << before.keyframes()
            << " keyframes); detections from "
            << (detections ? args.Get("--detections", "") : "the server's detector") << std::endl;
  return Ingest(client.get(), *reader, detections.get(), settings, before.keyframes());
}

}  // namespace objmap::cli
