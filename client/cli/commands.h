#pragma once

namespace objmap::cli {

/// `objmap map <dataset> --out <dir>`; returns the process exit code.
int RunMapCommand(int argc, char** argv);

/// `objmap segment <organized.pcd> --out <labelled.pcd>`; returns the process exit code.
int RunSegmentCommand(int argc, char** argv);

}  // namespace objmap::cli
