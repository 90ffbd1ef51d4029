#pragma once
// `objmap map INPUT --map DIR`: a run added to a map folder as a new session of the map kept in
// DIR/map.db (the store objmap_server keeps), instead of a new map each time.
#include <string>

#include "dataset/frame_stream.h"
#include "map_run_outputs.h"
#include "map_server/map_server.h"
#include "pipeline/sequence_runner.h"

namespace objmap::cli {

struct MapFolderRun {
  std::string dir;           ///< the map folder; created with its map.db when missing
  std::string session_name;  ///< the new session's name (empty: "session N")
  /// pose_source kEstimate: the frames' poses are tracked and the session's first keyframe is
  /// placed in the saved map by relocalisation; kRequest: the input's poses are the map's.
  MapServerConfig server;
  SequenceRunConfig run;
  /// The input brings poses of its own (a dataset's): with estimated poses the estimate of this
  /// run's keyframes is scored against them.
  bool source_has_poses = false;
};

/// Maps `stream` into the folder's map as a new session, then writes the folder's files again
/// from the whole map: map.bt, objects.json, objects/*.ply, keyframes.txt (every session's
/// keyframes), and keyframes/<id>.jpg of this run's keyframes. Returns the exit code (0; 1 when
/// the map cannot be opened or written, or the run stopped).
[[nodiscard]] int RunIntoMapFolder(const MapFolderRun& config, FrameStream* stream,
                                   RecordingDetector* detector);

}  // namespace objmap::cli
