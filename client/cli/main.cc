// objmap: object-oriented semantic mapping from the command line.
#include <cstring>
#include <iostream>
#include <map>
#include <string>

#include "commands.h"
#include "config/build_info.h"

namespace {

using Command = int (*)(int, char**);

void PrintUsage(std::ostream& out) {
  out << "objmap: object-oriented semantic maps (what is where) from RGB-D keyframes: maps\n"
         "sequences locally, and queries and feeds a running objmap_server.\n"
         "usage:\n"
         "  objmap map <dataset> --out <dir> [options]   map an RGB-D sequence\n"
         "  objmap segment <organized.pcd> --out <labelled.pcd>   segment one cloud\n"
         "  objmap eval <map-dir> --gt ground_truth.json | --inventory counts.json\n"
         "                                               score a map against ground truth\n"
         "  objmap eval-trajectory <estimated.txt> <reference.txt>\n"
         "                                               score a camera trajectory (ATE, RPE)\n"
         "  objmap render <map-dir> --out FILE.png       a picture of a map (headless)\n"
         "  objmap view <map-dir>                        the map in the browser (prints the URL)\n"
#ifdef OBJMAP_CLI_WITH_SERVER
         "commands for a running objmap_server (--server ADDR, default 127.0.0.1:50051):\n"
         "  objmap ingest <dataset>                      stream a sequence's keyframes\n"
         "  objmap inventory [--since VERSION] [--json]  objects per class\n"
         "  objmap objects [--class NAME] [--region X0 Y0 Z0 X1 Y1 Z1] [--near X Y Z] [--json]\n"
         "  objmap free X0 Y0 Z0 X1 Y1 Z1                exit code 0 when free, 3 when not\n"
         "  objmap export --octomap f.bt --objects dir/  OctoMap and object models as files\n"
         "  objmap update-poses <poses.txt> [--wait]     corrected keyframe poses\n"
         "  objmap keyframes [--out poses.txt]           keyframe poses (update-poses format)\n"
         "  objmap sessions [--start NAME] [--json]      the map's sessions; start a new one\n"
         "  objmap changes [--since-session S] [--json]  objects added, removed and moved\n"
         "  objmap status                                map version, counts, queue\n"
#endif
         "  objmap --version                             version and the build's options\n"
         "run `objmap <command> --help` for the options of a command\n";
}

const std::map<std::string, Command>& Commands() {
  static const std::map<std::string, Command> commands = {
      {"map", objmap::cli::RunMapCommand},
      {"segment", objmap::cli::RunSegmentCommand},
      {"eval", objmap::cli::RunEvalCommand},
      {"eval-trajectory", objmap::cli::RunEvalTrajectoryCommand},
      {"render", objmap::cli::RunRenderCommand},
      {"view", objmap::cli::RunViewCommand},
#ifdef OBJMAP_CLI_WITH_SERVER
      {"ingest", objmap::cli::RunIngestCommand},
      {"inventory", objmap::cli::RunInventoryCommand},
      {"objects", objmap::cli::RunObjectsCommand},
      {"free", objmap::cli::RunFreeCommand},
      {"export", objmap::cli::RunExportCommand},
      {"keyframes", objmap::cli::RunKeyframesCommand},
      {"sessions", objmap::cli::RunSessionsCommand},
      {"changes", objmap::cli::RunChangesCommand},
      {"update-poses", objmap::cli::RunUpdatePosesCommand},
      {"status", objmap::cli::RunStatusCommand},
#endif
  };
  return commands;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    PrintUsage(std::cerr);
    return 2;
  }
  if (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    PrintUsage(std::cout);
    return 0;
  }
  if (std::strcmp(argv[1], "--version") == 0) {
    std::cout << objmap::BuildDescription();
    return 0;
  }
  const std::string command = argv[1];
  const auto it = Commands().find(command);
  if (it != Commands().end()) return it->second(argc - 2, argv + 2);
  std::cerr << "objmap: unknown command '" << command << "'";
#ifndef OBJMAP_CLI_WITH_SERVER
  std::cerr << " (this build has no server commands: configure with OBJMAP_WITH_GRPC=ON)";
#endif
  std::cerr << "\n";
  PrintUsage(std::cerr);
  return 2;
}
