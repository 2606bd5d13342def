#include "hal/linux/spawn_program.hpp"

#include <csignal>

extern char** environ;

namespace scopekin::hal {

int spawn_program(pid_t& pid, const char* program, const posix_spawn_file_actions_t* actions,
                  char* const argv[]) {
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t none;
    sigemptyset(&none);
    posix_spawnattr_setsigmask(&attributes, &none);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
    const int failed = posix_spawnp(&pid, program, actions, &attributes, argv, environ);
    posix_spawnattr_destroy(&attributes);
    return failed;
}

}  // namespace scopekin::hal
