#include "pem_file.h"

#include <fstream>
#include <sstream>

namespace objmap {

bool ReadPemFile(const std::string& path, const char* what, std::string* pem, std::string* why) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  if (file) text << file.rdbuf();
  *pem = text.str();
  if (!file || pem->find("-----BEGIN") == std::string::npos) {
    *why = path + ": cannot read the " + std::string(what) + " (a PEM file)";
    return false;
  }
  return true;
}

}  // namespace objmap
