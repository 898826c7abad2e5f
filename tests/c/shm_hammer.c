/* shm_hammer.c: hammers the multi-CPU transport (backends/c/runtime/rcs_shm.c).
 *
 *   shm_hammer proc|thread free|lockstep N NAME
 *
 * CPU 0 writes samples 1..N (an odd-sized payload whose every byte is a
 * function of the sample's k), CPU 1 reads, in two processes (`proc`, for
 * ASan and valgrind) or two threads of one process (`thread`, for TSan,
 * which sees only one process).
 *   free:     the reader fetches the newest sample as fast as it can and
 *             checks that every copy is whole (no byte from another
 *             sample) and that k never goes backwards.
 *   lockstep: the reader, released at 1, 2, ..., N (both periods 1), waits
 *             for each sample, must get exactly that k with nothing missing;
 *             the writer waits for the reader before reusing a slot.
 * Prints `ok READS` and exits 0, or a message and exits 1.
 */
#define _POSIX_C_SOURCE 200809L

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "rcs_shm.h"

#define PAYLOAD 301u

static const char *g_name;
static int g_lockstep;
static uint64_t g_n;
static rcs_shm_cpu g_cpus[2] = {{1, PAYLOAD, 2u}, {1, 0u, 0u}};

static unsigned char expected(uint64_t k, size_t j) { return (unsigned char)((k * 131u + j * 7u) & 0xffu); }

static int writer(void) {
    rcs_shm *s = rcs_shm_open(g_name, g_cpus, 2, 0, stderr);
    if (s == NULL || rcs_shm_start(s, 0, 10000000000, NULL) < 0) return 1;
    unsigned char p[PAYLOAD];
    for (uint64_t k = 1; k <= g_n; k++) {
        for (size_t j = 0; j < PAYLOAD; j++) p[j] = expected(k, j);
        if (g_lockstep && rcs_shm_wait_readers(s, k, NULL) != 0) {
            fprintf(stderr, "writer: the reader went away at %llu\n", (unsigned long long)k);
            return 1;
        }
        rcs_shm_publish(s, k, p);
    }
    rcs_shm_set_state(s, RCS_SHM_FINISHED);
    rcs_shm_close(s, 1);
    return 0;
}

static int check(const unsigned char *p, uint64_t k) {
    for (size_t j = 0; j < PAYLOAD; j++) {
        if (p[j] != expected(k, j)) {
            fprintf(stderr, "torn: sample %llu byte %zu is %u\n", (unsigned long long)k, j, p[j]);
            return 0;
        }
    }
    return 1;
}

static int reader(void) {
    rcs_shm *s = rcs_shm_open(g_name, g_cpus, 2, 1, stderr);
    if (s == NULL || rcs_shm_start(s, 0, 10000000000, NULL) < 0) return 1;
    unsigned char p[PAYLOAD];
    uint64_t have = 0, reads = 0;
    int missing = 0;
    if (g_lockstep) {
        for (uint64_t t = 1; t <= g_n; t++) {
            if (rcs_shm_wait_published(s, 0, (int64_t)t, NULL) != 0) return 1;
            uint64_t k = rcs_shm_fetch(s, 0, (int64_t)t, have, p, &missing);
            if (k != t || missing || !check(p, k)) {
                fprintf(stderr, "lockstep: release %llu got %llu (missing %d)\n", (unsigned long long)t,
                        (unsigned long long)k, missing);
                return 1;
            }
            have = k;
            reads++;
            rcs_shm_next_release(s, (int64_t)t + 1);
        }
    } else {
        while (have < g_n) {
            uint64_t k = rcs_shm_fetch(s, 0, INT64_MAX, have, p, &missing);
            if (k < have) {
                fprintf(stderr, "out of order: %llu after %llu\n", (unsigned long long)k, (unsigned long long)have);
                return 1;
            }
            if (k > have) {
                if (!check(p, k)) return 1;
                have = k;
                reads++;
            }
        }
    }
    rcs_shm_set_state(s, RCS_SHM_FINISHED);
    rcs_shm_close(s, 1);
    printf("ok %llu\n", (unsigned long long)reads);
    return 0;
}

static void *writer_thread(void *arg) {
    *(int *)arg = writer();
    return NULL;
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: %s proc|thread free|lockstep N NAME\n", argv[0]);
        return 2;
    }
    g_lockstep = strcmp(argv[2], "lockstep") == 0;
    g_n = strtoull(argv[3], NULL, 10);
    g_name = argv[4];
    if (strcmp(argv[1], "thread") == 0) {
        pthread_t th;
        int wr = 1;
        if (pthread_create(&th, NULL, writer_thread, &wr) != 0) return 1;
        int rd = reader();
        pthread_join(th, NULL);
        return wr || rd;
    }
    pid_t pid = fork();
    if (pid < 0) return 1;
    if (pid == 0) _exit(writer());
    int rd = reader(), ws = 0;
    waitpid(pid, &ws, 0);
    return rd || !WIFEXITED(ws) || WEXITSTATUS(ws) != 0;
}
