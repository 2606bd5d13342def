// Starting another program from a process that blocks or catches SIGINT/SIGTERM (the box, the view
// server): the child must start with no signal blocked, or Ctrl-C and SIGTERM would not reach it.
#pragma once

#include <spawn.h>
#include <sys/types.h>

namespace scopekin::hal {

/// posix_spawnp(pid, program, actions, argv, environ) with an empty signal mask (exec resets the
/// caught signals' handlers to the default); returns 0 or the error number.
int spawn_program(pid_t& pid, const char* program, const posix_spawn_file_actions_t* actions,
                  char* const argv[]);

}  // namespace scopekin::hal
