#pragma once
// What this build of objmap is: its version and the optional parts it was configured with, for
// `objmap --version` and `objmap_server --version`.

#include <string>

namespace objmap {

/// "objmap 0.1.0" and one line per optional part: "gRPC: yes", "ROS1: no (...)",
/// "OpenNI2: yes", then the build type.
[[nodiscard]] std::string BuildDescription();

}  // namespace objmap
