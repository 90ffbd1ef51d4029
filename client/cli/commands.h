#pragma once
// Every `objmap` command takes the words after its name and returns the process exit code.

namespace objmap::cli {

/// `objmap map <dataset> --out <dir>`: maps a recorded sequence locally.
int RunMapCommand(int argc, char** argv);

/// `objmap segment <organized.pcd> --out <labelled.pcd>`: segments one cloud locally.
int RunSegmentCommand(int argc, char** argv);

/// `objmap eval <map-dir | ADDR> --gt ground_truth.json | --inventory counts.json`: scores a map.
int RunEvalCommand(int argc, char** argv);

/// `objmap eval-trajectory <estimated.txt> <reference.txt>`: ATE and RPE of a trajectory.
int RunEvalTrajectoryCommand(int argc, char** argv);

/// `objmap render <map-dir> --out FILE.png`: a picture of a map folder.
int RunRenderCommand(int argc, char** argv);

/// `objmap view <map-dir>`: the web viewer on a map folder, until Ctrl-C.
int RunViewCommand(int argc, char** argv);

// Commands that talk to a running objmap_server (built with OBJMAP_WITH_GRPC).

/// `objmap ingest <dataset>`: streams the keyframes of a recorded sequence to the server.
int RunIngestCommand(int argc, char** argv);

/// `objmap inventory`: objects per class.
int RunInventoryCommand(int argc, char** argv);

/// `objmap objects`: objects by class, region, confidence, distance.
int RunObjectsCommand(int argc, char** argv);

/// `objmap free X0 Y0 Z0 X1 Y1 Z1`: exit code 0 when the box is free, 3 when it is not.
int RunFreeCommand(int argc, char** argv);

/// `objmap export --octomap f.bt --objects dir/`: the OctoMap and the object models as files.
int RunExportCommand(int argc, char** argv);

/// `objmap update-poses poses.txt`: corrected keyframe poses from a pose-graph back end.
int RunUpdatePosesCommand(int argc, char** argv);

/// `objmap keyframes`: stored keyframes and their current poses, in the poses-file format.
int RunKeyframesCommand(int argc, char** argv);
/// `objmap sessions`: the map's sessions; `--start NAME` opens a new one.
int RunSessionsCommand(int argc, char** argv);
/// `objmap changes`: objects added, removed and moved, since a version, a session or a time.
int RunChangesCommand(int argc, char** argv);
/// `objmap status`: map version, counts, queue, regeneration, database.
int RunStatusCommand(int argc, char** argv);

}  // namespace objmap::cli
