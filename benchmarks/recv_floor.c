/* The receive floor in C: blocking recv() on a connected socket, nothing decoded.
 *
 * receive_loops.py hands over a socket that has done the RTDE handshake (its descriptor
 * number in argv[1]) and execs this; it reads for argv[2] seconds and prints its CPU
 * time, the packages read (bytes / argv[3]) and its voluntary context switches as the
 * Python rows' JSON line. What one wake-up per package costs this machine, with no
 * interpreter at all: no Python loop can spend less per package.
 */
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>

static double seconds_of(struct timeval tv) { return tv.tv_sec + tv.tv_usec / 1e6; }

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + t.tv_nsec / 1e9;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: recv_floor FD SECONDS PACKAGE_SIZE\n");
        return 2;
    }
    int fd = atoi(argv[1]);
    double span = atof(argv[2]);
    long size = atol(argv[3]);
    static char buf[65536];
    long long got = 0;
    struct rusage r0, r1;
    getrusage(RUSAGE_SELF, &r0);
    double t0 = now();
    while (now() - t0 < span) {
        ssize_t n = recv(fd, buf, sizeof buf, 0);
        if (n <= 0) {
            perror("recv");
            return 1;
        }
        got += n;
    }
    getrusage(RUSAGE_SELF, &r1);
    double cpu = seconds_of(r1.ru_utime) - seconds_of(r0.ru_utime) + seconds_of(r1.ru_stime) -
                 seconds_of(r0.ru_stime);
    printf("{\"cpu\": %.6f, \"packages\": %.3f, \"wakeups\": %ld}\n", cpu, (double)got / size,
           r1.ru_nvcsw - r0.ru_nvcsw);
    return 0;
}
