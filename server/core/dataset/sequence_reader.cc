#include "dataset/sequence_reader.h"

#include <filesystem>

#include "dataset/seven_scenes_reader.h"
#include "dataset/tum_reader.h"

namespace objmap {

std::unique_ptr<SequenceReader> OpenSequence(const std::string& path, std::string* why) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(path)) {
    *why = path + ": not a directory";
    return nullptr;
  }
  if (fs::exists(path + "/rgb.txt") && fs::exists(path + "/depth.txt")) {
    return OpenTum(path, TumReaderConfig{}, why);
  }
  return OpenSevenScenes(path, why);
}

}  // namespace objmap
