// A pid that ran and ended, so that no process has it now: what a lock file left by a
// crashed kanesim holds (the stale-lock tests of batch/file_guard.h and the CLI).
#pragma once

#include <sys/wait.h>
#include <unistd.h>

namespace kanesim::test {

inline long DeadPid() {
  pid_t p = ::fork();
  if (p == 0) ::_exit(0);
  int status = 0;
  ::waitpid(p, &status, 0);
  return p;
}

}  // namespace kanesim::test
