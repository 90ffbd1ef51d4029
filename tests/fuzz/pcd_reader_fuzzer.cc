// An untrusted .pcd file (objmap segment reads them): the organized PCD reader.
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_input_file.h"
#include "pointcloud_io/pointcloud_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = objmap::fuzz::WriteInputFile(data, size, "input.pcd");
  if (path.empty()) return 0;
  objmap::OrganizedCloud cloud;
  std::vector<std::uint32_t> labels;
  std::string why;
  (void)objmap::LoadOrganizedPcd(path, &cloud, &labels, &why);
  return 0;
}
