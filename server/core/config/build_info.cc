#include "config/build_info.h"

// The definitions come from the top-level CMakeLists.txt once every optional part is known.
#ifndef OBJMAP_VERSION_STRING
#error "OBJMAP_VERSION_STRING is defined by CMakeLists.txt"
#endif

namespace objmap {

std::string BuildDescription() {
  return std::string("objmap ") + OBJMAP_VERSION_STRING + "\n" +
         "  gRPC server and client:  " + OBJMAP_BUILT_WITH_GRPC + "\n" +
         "  ROS1 node and bags:      " + OBJMAP_BUILT_WITH_ROS + "\n" +
         "  OpenNI2 cameras (.oni):  " + OBJMAP_BUILT_WITH_OPENNI2 + "\n" +
         "  build type:              " + OBJMAP_BUILD_TYPE + "\n";
}

}  // namespace objmap
