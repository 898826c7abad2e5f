/* events_fuzz.c: libFuzzer harness for the C event reader (docs/events.md).
 *
 * Built by bench/fuzz_events.py with
 *   clang -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
 * against backends/c/runtime/rcs_runtime.c and the hand-made fixture design
 * of tests/c/runtime_fixture.c (included below with its main() renamed, so
 * that its static tables are the design the reader checks against).
 *
 * Each input goes through the reader's normal entry point,
 * rcs_scenario_load(), from a file of its own (the reader takes a path; the
 * runtime is not changed for the harness).  The reader never exit()s on bad
 * input: it prints one error and returns NULL.  The oracle, besides "no crash
 * and no sanitizer report":
 *   - a refused file gives exactly one line `PATH:LINE: error: MESSAGE\n`,
 *     LINE between 1 and the file's line count + 1, MESSAGE printable ASCII;
 *   - an accepted file gives no output at all, and its cycles are 1..2^32-1;
 *   - reading the same bytes twice gives the same outcome.
 * Any breach calls abort(): libFuzzer writes the input as crash-<hash>.
 * Whether the Rust reader agrees is the replay step's job (fuzz_events.py).
 *
 * With -DPLANT_BUG the oracle also rejects the refusal of a malformed version
 * number in the header (no seed has one: a planted finding that only a
 * mutation reaches; tests/test_fuzz_readers.py shows it is reported).
 */
#define main rcs_fixture_main
#include "../../tests/c/runtime_fixture.c"
#undef main

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_path[64];

static int read_once(const uint8_t *data, size_t size, char **msg, size_t *msg_len, uint64_t *cycles) {
    FILE *f = fopen(g_path, "wb");
    if (f == NULL || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        perror(g_path);
        abort();
    }
    FILE *err = open_memstream(msg, msg_len);
    if (err == NULL) abort();
    rcs_scenario *sc = rcs_scenario_load(g_path, &design, err);
    fclose(err);
    *cycles = rcs_scenario_cycles(sc);
    rcs_scenario_free(sc);
    return sc != NULL;
}

static void finding(const char *what, const char *msg) {
    fprintf(stderr, "events_fuzz: FINDING: %s\n%s\n", what, msg ? msg : "");
    abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
    (void)argc;
    (void)argv;
    const char *dir = getenv("TMPDIR");
    snprintf(g_path, sizeof g_path, "%.40s/rcs-fuzz-%ld.events", dir && strlen(dir) < 40 ? dir : "/tmp", (long)getpid());
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *msg = NULL, *again = NULL;
    size_t msg_len = 0, again_len = 0;
    uint64_t cycles = 0, cycles2 = 0;
    int ok = read_once(data, size, &msg, &msg_len, &cycles);
    int ok2 = read_once(data, size, &again, &again_len, &cycles2);
    if (ok != ok2 || cycles != cycles2 || msg_len != again_len || memcmp(msg, again, msg_len) != 0)
        finding("two readings of the same bytes differ", msg);
    if (ok) {
        if (msg_len != 0) finding("an accepted file printed something", msg);
        if (cycles < 1 || cycles > UINT32_MAX) finding("an accepted file has cycles outside 1..2^32-1", msg);
    } else {
        size_t lines = 1;
        for (size_t i = 0; i < size; i++) lines += data[i] == '\n';
        size_t plen = strlen(g_path);
        if (msg_len < plen + 2 || strncmp(msg, g_path, plen) != 0 || msg[plen] != ':' || msg[msg_len - 1] != '\n')
            finding("a refusal is not `PATH:LINE: error: ...`", msg);
        for (size_t i = 0; i + 1 < msg_len; i++)
            if ((unsigned char)msg[i] < 0x20u || (unsigned char)msg[i] > 0x7eu)
                finding("a refusal is not one line of printable ASCII", msg);
        char *end = NULL;
        unsigned long line = strtoul(msg + plen + 1, &end, 10);
        if (end == msg + plen + 1 || line < 1 || line > lines || strncmp(end, ": error: ", 9) != 0)
            finding("a refusal names no line of the file", msg);
#ifdef PLANT_BUG
        /* No seed has a malformed version number: only a mutation finds one. */
        if (line == 1 && strstr(msg, "is not a decimal number") != NULL) finding("planted: a malformed version number", msg);
#endif
    }
    free(msg);
    free(again);
    return 0;
}
