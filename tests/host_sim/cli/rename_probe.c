// rename_probe.c: an LD_PRELOAD library for the output-order test (cli_checks.py output_order).
// It sees every rename a process makes (std::filesystem::rename and Python's os.replace both
// call rename or renameat) and its children inherit it:
//   SCOPEKIN_RENAME_LOG=FILE     appends "FROM<TAB>TO" per rename to FILE, before renaming
//   SCOPEKIN_RENAME_KILL_AT=N    the N-th rename logged in FILE (counted over all processes) kills
//                                the process with SIGKILL instead, as `kill -9` at that moment
//                                would; only a process named "scopekin" is killed
// Built without sanitizers: it is loaded into Python as well as into the sanitized scopekin.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef int (*rename_fn)(const char*, const char*);
typedef int (*renameat_fn)(int, const char*, int, const char*);

/// Lines in the log so far (every process appends to the same file, one at a time).
static long logged_renames(const char* log) {
    FILE* f = fopen(log, "r");
    if (f == NULL) return 0;
    long lines = 0;
    int c;
    while ((c = fgetc(f)) != EOF)
        if (c == '\n') ++lines;
    fclose(f);
    return lines;
}

static void note(const char* from, const char* to) {
    const char* log = getenv("SCOPEKIN_RENAME_LOG");
    if (log == NULL) return;
    const int saved = errno;
    const long number = logged_renames(log) + 1;
    const char* kill_at = getenv("SCOPEKIN_RENAME_KILL_AT");
    if (kill_at != NULL && atol(kill_at) == number &&
        strcmp(program_invocation_short_name, "scopekin") == 0) {
        FILE* f = fopen(log, "a");
        if (f != NULL) {
            fprintf(f, "KILLED\t%s\t%s\n", from, to);
            fclose(f);
        }
        kill(getpid(), SIGKILL);
    }
    FILE* f = fopen(log, "a");
    if (f != NULL) {
        fprintf(f, "%s\t%s\n", from, to);
        fclose(f);
    }
    errno = saved;
}

int rename(const char* from, const char* to) {
    note(from, to);
    rename_fn real = (rename_fn)dlsym(RTLD_NEXT, "rename");
    return real(from, to);
}

int renameat(int from_dir, const char* from, int to_dir, const char* to) {
    note(from, to);
    renameat_fn real = (renameat_fn)dlsym(RTLD_NEXT, "renameat");
    return real(from_dir, from, to_dir, to);
}
