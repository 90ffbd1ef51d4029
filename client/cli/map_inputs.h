#pragma once
// What `objmap map` reads: the one place that turns its input argument into a FrameStream.

#include <memory>
#include <string>

#include "dataset/frame_stream.h"
#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"

namespace objmap::cli {

/// Options of `objmap map` that shape the input, whatever its kind.
struct MapInputOptions {
  /// First frame and number of frames (0: all); a sequence folder selects them by index.
  std::size_t first_frame = 0;
  std::size_t max_frames = 0;
  /// TUM trajectory giving the poses of a camera or recording; empty: a static camera at the
  /// identity pose. Sequence folders bring their own poses and ignore it.
  std::string trajectory_path;
  TrajectoryMatchConfig trajectory_match;
};

/// An opened input: the stream, and the sequence behind it when there is one (it must outlive the
/// stream, which reads from it).
struct MapInput {
  std::unique_ptr<SequenceReader> sequence;
  std::unique_ptr<FrameStream> stream;
  /// True when the stream's selection already applies first_frame and max_frames.
  bool selection_applied = false;
  /// Printed before the run: how poses are obtained, when the user should know.
  std::string note;
};

/// Opens `argument`: `openni2` (the first OpenNI2 device), `openni2:<uri>`, a path ending in
/// `.oni` (an OpenNI2 recording), else a sequence folder (7-Scenes or TUM RGB-D). False with a
/// reason, e.g. "no OpenNI2 device found: ...", or for OpenNI2 inputs in a build without OpenNI2.
[[nodiscard]] bool OpenMapInput(const std::string& argument, const MapInputOptions& options,
                                MapInput* input, std::string* why);

}  // namespace objmap::cli
