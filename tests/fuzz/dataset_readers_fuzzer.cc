// Untrusted dataset text files: a TUM trajectory (`objmap map --trajectory`) and a 7-Scenes
// pose or intrinsics matrix. The first byte picks the reader.
#include <cstdint>
#include <string>
#include <vector>

#include "dataset/image_io.h"
#include "dataset/trajectory.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool trajectory = data[0] % 2 == 0;
  const std::string path = objmap::fuzz::WriteInputFile(data + 1, size - 1, "input.txt");
  if (path.empty()) return 0;
  std::string why;
  if (trajectory) {
    std::vector<objmap::TrajectoryPose> poses;
    if (objmap::ReadTumTrajectory(path, &poses, &why)) {
      for (const objmap::TrajectoryPose& pose : poses) {
        if (!pose.T_W_C.matrix().allFinite()) __builtin_trap();
      }
    }
  } else {
    double values[16];
    (void)objmap::ReadMatrixText(path, 4, 4, values, &why);
  }
  return 0;
}
