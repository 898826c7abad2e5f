/* driver_c.c: the generated C PR running its AHEAD plan, for bench/bench_rust_step.py.
 *
 *     driver_c [STEPS [trace]]        (default 10000)
 *
 * The world of bench/c_ahead/world.h (the one driver.c runs the generated
 * and the hand-written PR in), but only the generated controller is
 * stepped, through bench_c_pr_step (never inlined: callgrind's
 * --toggle-collect target).  It is the twin of driver.rs (the generated
 * Rust): both print the rule mix and an FNV-1a digest of what PR wrote
 * after every step (its status head, tb_fault, and TB's command head and
 * rpm), and with `trace` one line per step; the script requires the two
 * outputs to be identical.
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "submarine_PR.h"

#include "world.h"

static submarine_PR pr;
static submarine_buffers buf;

/* The measured call: one step of the generated controller. */
__attribute__((noinline)) void bench_c_pr_step(submarine_PR *self, submarine_buffers *b, uint64_t cycle)
{
    submarine_PR__step(self, b, cycle);
}

static uint64_t mix(uint64_t h, uint64_t x)
{
    for (int i = 0; i < 8; i++) {
        h ^= (x >> (8 * i)) & 0xffu;
        h *= UINT64_C(0x100000001b3);
    }
    return h;
}

static uint64_t bits(double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return u;
}

int main(int argc, char **argv)
{
    const unsigned long steps = argc > 1 ? strtoul(argv[1], NULL, 10) : 10000ul;
    const int trace = argc > 2 && strcmp(argv[2], "trace") == 0;
    submarine_buffers *const bufs[] = {&buf};
    bench_world w;
    uint64_t cycle;
    uint64_t digest = UINT64_C(0xcbf29ce484222325);

    world_init(&w);
    memset(&buf, 0, sizeof buf);
    submarine_buffers_init(&buf);
    submarine_PR__init(&pr);

    for (cycle = 1u; cycle <= steps; cycle++) {
        const rcs_status_head *s = &buf.PR__status.head;
        world_before_step(&w, bufs, 1u, cycle);
        bench_c_pr_step(&pr, &buf, cycle);
        {
            const uint64_t v[] = {s->echo_serial, (uint32_t)s->status, (uint32_t)s->verb, (uint32_t)s->state,
                                  (uint32_t)s->rule, (uint32_t)s->error_code, s->stamp,
                                  (uint32_t)buf.PR__status.f.tb_fault, buf.TB__cmd.head.serial,
                                  (uint32_t)buf.TB__cmd.head.verb, bits(buf.TB__cmd.args.AHEAD.rpm)};
            for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
                digest = mix(digest, v[i]);
            }
        }
        if (trace) {
            printf("%" PRIu64 " %" PRIu32 " %d %d %d %d %d %" PRIu64 " %d %" PRIu32 " %d %016" PRIx64 "\n", cycle,
                   s->echo_serial, (int)s->status, (int)s->verb, (int)s->state, (int)s->rule, (int)s->error_code,
                   s->stamp, (int)buf.PR__status.f.tb_fault, buf.TB__cmd.head.serial, (int)buf.TB__cmd.head.verb,
                   bits(buf.TB__cmd.args.AHEAD.rpm));
        }
        world_after_step(&w, bufs, 1u, cycle);
    }
    world_print_counts(&w, steps);
    printf("final PR status: echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
           " tb_fault %d\n",
           buf.PR__status.head.echo_serial, (int)buf.PR__status.head.status, (int)buf.PR__status.head.verb,
           (int)buf.PR__status.head.state, (int)buf.PR__status.head.rule, (int)buf.PR__status.head.error_code,
           buf.PR__status.head.stamp, (int)buf.PR__status.f.tb_fault);
    printf("final TB cmd: serial %" PRIu32 " verb %d rpm %016" PRIx64 "\n", buf.TB__cmd.head.serial,
           (int)buf.TB__cmd.head.verb, bits(buf.TB__cmd.args.AHEAD.rpm));
    printf("digest %016" PRIx64 "\n", digest);
    return 0;
}
