// objmap: object-oriented semantic mapping from the command line.
#include <cstring>
#include <iostream>

#include "commands.h"

namespace {

void PrintUsage() {
  std::cerr << "usage:\n"
               "  objmap map <dataset> --out <dir> [options]   map an RGB-D sequence\n"
               "  objmap segment <organized.pcd> --out <labelled.pcd>   segment one cloud\n"
               "run `objmap <command> --help` for the options of a command\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    PrintUsage();
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  if (command == "map") return objmap::cli::RunMapCommand(argc - 2, argv + 2);
  if (command == "segment") return objmap::cli::RunSegmentCommand(argc - 2, argv + 2);
  std::cerr << "objmap: unknown command '" << command << "'\n";
  PrintUsage();
  return 2;
}
