/* driver_c.c: the generated C PR running its AHEAD plan, for bench/bench_rust_step.py.
 *
 *     driver_c [STEPS [trace]]        (default 10000)
 *
 * The same plant, TB model and command sequence as bench/c_ahead/driver.c
 * (a new AHEAD command every 1000 cycles, the ship astern before the 5th,
 * a turbine trip at cycle 7800), but only the generated controller is
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

#define CMD_EVERY 1000u
#define BACK_CMD 4u      /* index of the command given while going astern */
#define TRIP_CYCLE 7800u /* the turbine trips in this cycle */

static const double goals[] = {10.0, 14.0, 8.0, 16.0, 5.0, 12.0, 9.0, 18.0, 6.0, 11.0};
#define N_GOALS (sizeof goals / sizeof goals[0])

static submarine_PR pr;
static submarine_buffers buf;

enum { W_NEW, W_E0, W_E1, W_E2, W_E3, W_E4, W_E5, W_E9, W_WAIT_TB, W_WAIT_CLOSING, W_IDLE, W_N };
static const char *const what_names[W_N] = {"new", "E0", "E1", "E2", "E3", "E4", "E5", "E9", "wait_tb", "wait_closing", "idle"};
static unsigned long counts[W_N];

/* The measured call: one step of the generated controller. */
__attribute__((noinline)) void bench_c_pr_step(submarine_PR *self, submarine_buffers *b, uint64_t cycle)
{
    submarine_PR_step(self, b, cycle);
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

static double fabs_(double x) { return x < 0.0 ? -x : x; }

int main(int argc, char **argv)
{
    const unsigned long steps = argc > 1 ? strtoul(argv[1], NULL, 10) : 10000ul;
    const int trace = argc > 2 && strcmp(argv[2], "trace") == 0;
    double ship_speed = 0.0, shaft_rpm = 0.0, rpm_goal = 0.0;
    uint32_t tb_echo = 0u;
    int32_t tb_status = RCS_UNINITIALIZED, tb_verb = 0, tb_error = 0;
    bool tripped = false;
    uint32_t pr_serial = 0u;
    unsigned n_cmd = 0u;
    uint64_t cycle;
    uint64_t digest = UINT64_C(0xcbf29ce484222325);

    memset(&buf, 0, sizeof buf);
    submarine_buffers_init(&buf);
    submarine_PR_init(&pr);

    for (cycle = 1u; cycle <= steps; cycle++) {
        const double sea = ((cycle / 150u) % 2u == 0u) ? 0.001 : -0.001;
        int32_t ship_dir;
        int new_cmd = 0;
        uint32_t sent_before;
        int32_t state_before;
        double goal;
        ship_speed += (0.01 * shaft_rpm * fabs_(shaft_rpm) - ship_speed * fabs_(ship_speed)) / 60.0 * 0.03 + sea;
        if (n_cmd == BACK_CMD && cycle % CMD_EVERY == 0u) {
            ship_speed = -1.5;
            shaft_rpm = -20.0;
        }
        ship_dir = ship_speed > 0.1 ? submarine_ShipDir_AHEAD
                   : ship_speed < -0.1 ? submarine_ShipDir_BACK
                                       : submarine_ShipDir_STOPPED;
        buf.gm.ship_speed = ship_speed;
        buf.gm.ship_dir = ship_dir;

        if (cycle % CMD_EVERY == 1u) {
            pr_serial = rcs_next_serial(pr_serial);
            buf.PR_cmd.head.serial = pr_serial;
            buf.PR_cmd.head.verb = submarine_PR_VERB_AHEAD;
            buf.PR_cmd.args.AHEAD.speed = goals[n_cmd % N_GOALS];
            n_cmd++;
            new_cmd = 1;
        }

        sent_before = buf.TB_cmd.head.serial;
        state_before = buf.PR_status.head.state;
        bench_c_pr_step(&pr, &buf, cycle);

        {
            const rcs_status_head *s = &buf.PR_status.head;
            const uint64_t w[] = {s->echo_serial, (uint32_t)s->status, (uint32_t)s->verb, (uint32_t)s->state,
                                  (uint32_t)s->rule, (uint32_t)s->error_code, s->stamp,
                                  (uint32_t)buf.PR_status.f.tb_fault, buf.TB_cmd.head.serial,
                                  (uint32_t)buf.TB_cmd.head.verb, bits(buf.TB_cmd.args.AHEAD.rpm)};
            for (size_t i = 0; i < sizeof w / sizeof w[0]; i++) {
                digest = mix(digest, w[i]);
            }
            if (trace) {
                printf("%" PRIu64 " %" PRIu32 " %d %d %d %d %d %" PRIu64 " %d %" PRIu32 " %d %016" PRIx64 "\n", cycle,
                       s->echo_serial, (int)s->status, (int)s->verb, (int)s->state, (int)s->rule, (int)s->error_code,
                       s->stamp, (int)buf.PR_status.f.tb_fault, buf.TB_cmd.head.serial, (int)buf.TB_cmd.head.verb,
                       bits(buf.TB_cmd.args.AHEAD.rpm));
            }
        }

        goal = buf.PR_cmd.args.AHEAD.speed;
        if (new_cmd) {
            counts[W_NEW]++;
            counts[buf.PR_status.head.rule == 10 ? W_E0 : W_E1]++;
        } else if (state_before != 4 && state_before != 5) {
            counts[W_IDLE]++;
        } else if (buf.TB_cmd.head.serial != sent_before) {
            const int32_t r = buf.PR_status.head.rule;
            counts[r == 13 ? W_E2 : r == 15 ? W_E4 : W_E5]++;
        } else if (buf.PR_status.head.state == 3) {
            counts[W_E9]++;
        } else if (!(sent_before != 0u && tb_echo == sent_before && tb_status == RCS_DONE)) {
            counts[W_WAIT_TB]++;
        } else if (fabs_(ship_speed - goal) <= 0.25) {
            counts[W_E3]++;
        } else {
            counts[W_WAIT_CLOSING]++;
        }

        if (buf.TB_cmd.head.serial != tb_echo) {
            tb_echo = buf.TB_cmd.head.serial;
            tb_verb = buf.TB_cmd.head.verb;
            rpm_goal = tb_verb == submarine_TB_VERB_AHEAD ? buf.TB_cmd.args.AHEAD.rpm : 0.0;
            tb_status = RCS_EXEC;
            tb_error = 0;
        }
        tripped = cycle == TRIP_CYCLE;
        if (tripped) {
            rpm_goal = 0.0;
            if (tb_status == RCS_EXEC || tb_status == RCS_DONE) {
                tb_status = RCS_ERROR;
                tb_error = submarine_ERR_TRIP;
            }
        }
        shaft_rpm += rpm_goal - shaft_rpm > 0.6 ? 0.6 : rpm_goal - shaft_rpm < -0.6 ? -0.6 : rpm_goal - shaft_rpm;
        if (tb_status == RCS_EXEC && fabs_(shaft_rpm - rpm_goal) <= 1.0) {
            tb_status = RCS_DONE;
        }
        buf.TB_status.head.echo_serial = tb_echo;
        buf.TB_status.head.status = tb_status;
        buf.TB_status.head.verb = tb_verb;
        buf.TB_status.head.error_code = tb_error;
        buf.TB_status.head.stamp = cycle;
        buf.TB_status.f.shaft_rpm = shaft_rpm;
        buf.TB_status.f.tripped = tripped;
    }

    printf("steps %lu\n", steps);
    for (int i = 0; i < W_N; i++) {
        printf("count %s %lu\n", what_names[i], counts[i]);
    }
    printf("final PR status: echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
           " tb_fault %d\n",
           buf.PR_status.head.echo_serial, (int)buf.PR_status.head.status, (int)buf.PR_status.head.verb,
           (int)buf.PR_status.head.state, (int)buf.PR_status.head.rule, (int)buf.PR_status.head.error_code,
           buf.PR_status.head.stamp, (int)buf.PR_status.f.tb_fault);
    printf("final TB cmd: serial %" PRIu32 " verb %d rpm %016" PRIx64 "\n", buf.TB_cmd.head.serial,
           (int)buf.TB_cmd.head.verb, bits(buf.TB_cmd.args.AHEAD.rpm));
    printf("digest %016" PRIx64 "\n", digest);
    return 0;
}
