// Copyright zdenoise contributors.
// SPDX-License-Identifier: BSD-3-Clause
//
// peak_rss COMMAND [ARGS...]: run the command and print its peak resident
// memory in KiB (the last line of stdout); exit with its status.
//
// A test cannot take this from wait4() on a child of its own: Linux carries
// the memory high-water mark of the process image an exec replaces into the
// new one, so a child started by a test process that once held a lot reports
// at least that. This small program is exec'd fresh, then starts the command.

#include <cstdio>

#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

extern char** environ;

int
main(int argc, char* argv[])
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: peak_rss COMMAND [ARGS...]\n");
        return 2;
    }
    pid_t pid = -1;
    if (posix_spawnp(&pid, argv[1], nullptr, nullptr, argv + 1, environ) != 0) {
        std::perror(argv[1]);
        return 127;
    }
    int status = 0;
    struct rusage usage = {};
    if (wait4(pid, &status, 0, &usage) != pid) {
        std::perror("wait4");
        return 127;
    }
    std::printf("%ld\n", usage.ru_maxrss);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}
