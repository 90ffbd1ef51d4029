#pragma once
// For fuzz targets whose parser reads a file: the input written to a file of this process's own
// (in /dev/shm when it exists, so that millions of runs do not wear a disk).

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace objmap::fuzz {

/// Writes `data` to this process's scratch file `name` and returns its path ("" on failure).
inline std::string WriteInputFile(const std::uint8_t* data, std::size_t size,
                                  const std::string& name) {
  const std::string dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  const std::string path = dir + "/objmap_fuzz_" + std::to_string(getpid()) + "_" + name;
  FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return "";
  const bool written = size == 0 || std::fwrite(data, 1, size, file) == size;
  return std::fclose(file) == 0 && written ? path : "";
}

}  // namespace objmap::fuzz
