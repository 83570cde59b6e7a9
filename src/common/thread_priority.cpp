#include "vitamin_e/common/thread_priority.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#endif

namespace vitamin_e {

#ifdef __linux__
namespace {
// On Linux, PRIO_PROCESS with a thread id reads and sets that thread's nice value only.
id_t currentThreadId() { return static_cast<id_t>(syscall(SYS_gettid)); }
}  // namespace
#endif

bool lowerCurrentThreadPriority(int increment) {
  if (!isNiceIncrement(increment)) {
    throw std::invalid_argument("nice increment " + std::to_string(increment) + " is outside [0, " +
                                std::to_string(kMaxNice) + "]");
  }
  if (increment == 0) return true;
#ifdef __linux__
  const int nice = std::min(kMaxNice, currentThreadNice() + increment);
  return setpriority(PRIO_PROCESS, currentThreadId(), nice) == 0;
#else
  return false;
#endif
}

int currentThreadNice() {
#ifdef __linux__
  errno = 0;  // -1 is also a nice value: only errno tells a failure
  const int nice = getpriority(PRIO_PROCESS, currentThreadId());
  return errno == 0 ? nice : 0;
#else
  return 0;
#endif
}

}  // namespace vitamin_e
