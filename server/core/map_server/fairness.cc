#include "map_server/fairness.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace objmap {

bool FairnessConfig::IsValid(std::string* why) const {
  if (heavy_query_threads < 1 || heavy_query_threads > 64) {
    *why = "server: heavy_query_threads must be in [1, 64]";
    return false;
  }
  if (heavy_query_nice < 0 || heavy_query_nice > 19) {
    *why = "server: heavy_query_nice must be in [0, 19]";
    return false;
  }
  if (max_waiting_heavy_queries < 0) {
    *why = "server: max_waiting_heavy_queries must be >= 0";
    return false;
  }
  return true;
}

bool LowerThisThreadPriority(int nice, std::string* why) {
  if (nice == 0) return true;
  // On Linux a thread id names one thread to setpriority (POSIX would mean the whole process).
  const id_t thread = static_cast<id_t>(syscall(SYS_gettid));
  errno = 0;
  const int current = getpriority(PRIO_PROCESS, thread);
  if (errno != 0 || setpriority(PRIO_PROCESS, thread, current + nice) != 0) {
    *why = std::string("cannot lower the thread's priority: ") + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace objmap
