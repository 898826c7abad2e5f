/* driver.c: runs PR's AHEAD plan, generated and hand-written, side by side.
 *
 *     driver [STEPS]        (default 10000)
 *
 * Each cycle the driver moves a small plant (the shaft follows TB's
 * command, the ship follows the shaft, a slow sea disturbance on top),
 * gives a new AHEAD command every 1000 cycles, then steps the generated
 * controller (submarine_PR_step) on one set of buffers and the hand-written
 * one (hand_pr_step) on another set, with identical inputs, and compares
 * what both wrote (PR's status buffer and TB's command buffer) after every
 * step.  The first difference stops the run with exit status 1: that
 * comparison is the proof that the hand-written version computes the same
 * thing.  Then it plays TB: echoes the serial of TB's command, reports EXEC
 * while the shaft spools, DONE when it is there (ERROR on a trip).
 *
 * Scripted events: the ship is made to go astern before the 5th command
 * (E1, then E5), and the turbine trips once (E9; PR then idles until the
 * next command).  The run prints how often each rule fired and how many
 * steps waited; bench/bench_c_step.py counts the instructions of the step
 * functions with callgrind (--toggle-collect).
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "handwritten_pr.h"
#include "submarine_PR.h"

#define CMD_EVERY 1000u
#define BACK_CMD 4u          /* index of the command given while going astern */
#define TRIP_CYCLE 7800u     /* the turbine trips in this cycle */

static const double goals[] = {10.0, 14.0, 8.0, 16.0, 5.0, 12.0, 9.0, 18.0, 6.0, 11.0};
#define N_GOALS (sizeof goals / sizeof goals[0])

static submarine_PR gen;          /* the generated controller's private state */
static submarine_buffers buf_gen; /* buffers of the generated controller */
static submarine_buffers buf_hand; /* buffers of the hand-written controller */

enum { W_NEW, W_E0, W_E1, W_E2, W_E3, W_E4, W_E5, W_E9, W_WAIT_TB, W_WAIT_CLOSING, W_IDLE, W_N };
static const char *const what_names[W_N] = {"new", "E0", "E1", "E2", "E3", "E4", "E5", "E9", "wait_tb", "wait_closing", "idle"};
static unsigned long counts[W_N];

static int same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static int compare(uint64_t cycle)
{
    const rcs_status_head *g = &buf_gen.PR_status.head;
    const rcs_status_head *h = &buf_hand.PR_status.head;
    int ok = g->echo_serial == h->echo_serial && g->status == h->status && g->verb == h->verb &&
             g->state == h->state && g->rule == h->rule && g->error_code == h->error_code &&
             g->stamp == h->stamp && buf_gen.PR_status.f.tb_fault == buf_hand.PR_status.f.tb_fault &&
             buf_gen.TB_cmd.head.serial == buf_hand.TB_cmd.head.serial &&
             buf_gen.TB_cmd.head.verb == buf_hand.TB_cmd.head.verb &&
             same_double(buf_gen.TB_cmd.args.AHEAD.rpm, buf_hand.TB_cmd.args.AHEAD.rpm);
    if (!ok) {
        fprintf(stderr,
                "MISMATCH at cycle %" PRIu64 ":\n"
                "  generated:    echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
                " tb_fault %d | TB cmd serial %" PRIu32 " verb %d rpm %.17g\n"
                "  hand-written: echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
                " tb_fault %d | TB cmd serial %" PRIu32 " verb %d rpm %.17g\n",
                cycle, g->echo_serial, (int)g->status, (int)g->verb, (int)g->state, (int)g->rule,
                (int)g->error_code, g->stamp, (int)buf_gen.PR_status.f.tb_fault, buf_gen.TB_cmd.head.serial,
                (int)buf_gen.TB_cmd.head.verb, buf_gen.TB_cmd.args.AHEAD.rpm, h->echo_serial, (int)h->status,
                (int)h->verb, (int)h->state, (int)h->rule, (int)h->error_code, h->stamp,
                (int)buf_hand.PR_status.f.tb_fault, buf_hand.TB_cmd.head.serial, (int)buf_hand.TB_cmd.head.verb,
                buf_hand.TB_cmd.args.AHEAD.rpm);
    }
    return ok;
}

static double fabs_(double x) { return x < 0.0 ? -x : x; }

int main(int argc, char **argv)
{
    const unsigned long steps = argc > 1 ? strtoul(argv[1], NULL, 10) : 10000ul;
    /* plant and TB model */
    double ship_speed = 0.0, shaft_rpm = 0.0, rpm_goal = 0.0;
    uint32_t tb_echo = 0u;
    int32_t tb_status = RCS_UNINITIALIZED, tb_verb = 0, tb_error = 0;
    bool tripped = false;
    uint32_t pr_serial = 0u;
    unsigned n_cmd = 0u;
    uint64_t cycle;

    memset(&buf_gen, 0, sizeof buf_gen);
    memset(&buf_hand, 0, sizeof buf_hand);
    submarine_buffers_init(&buf_gen);
    submarine_buffers_init(&buf_hand);
    submarine_PR_init(&gen);
    hand_pr_init();

    for (cycle = 1u; cycle <= steps; cycle++) {
        /* Plant: ship speed from the shaft (SHIP_SIM's model, with a hull 5 times
         * lighter so that the trim rules fire often in 10000 steps) plus a sea
         * disturbance that changes sign every 150 cycles. */
        const double sea = ((cycle / 150u) % 2u == 0u) ? 0.001 : -0.001;
        int32_t ship_dir;
        int new_cmd = 0;
        uint32_t sent_before;
        int32_t state_before;
        double goal;
        ship_speed += (0.01 * shaft_rpm * fabs_(shaft_rpm) - ship_speed * fabs_(ship_speed)) / 60.0 * 0.03 + sea;
        if (n_cmd == BACK_CMD && cycle % CMD_EVERY == 0u) {
            ship_speed = -1.5; /* scripted: astern when the next AHEAD arrives (E1, E5) */
            shaft_rpm = -20.0;
        }
        ship_dir = ship_speed > 0.1 ? submarine_ShipDir_AHEAD
                   : ship_speed < -0.1 ? submarine_ShipDir_BACK
                                       : submarine_ShipDir_STOPPED;
        buf_gen.gm.ship_speed = buf_hand.gm.ship_speed = ship_speed;
        buf_gen.gm.ship_dir = buf_hand.gm.ship_dir = ship_dir;

        /* Supervisor: a new AHEAD command every CMD_EVERY cycles. */
        if (cycle % CMD_EVERY == 1u) {
            pr_serial = rcs_next_serial(pr_serial);
            buf_gen.PR_cmd.head.serial = buf_hand.PR_cmd.head.serial = pr_serial;
            buf_gen.PR_cmd.head.verb = buf_hand.PR_cmd.head.verb = submarine_PR_VERB_AHEAD;
            buf_gen.PR_cmd.args.AHEAD.speed = buf_hand.PR_cmd.args.AHEAD.speed = goals[n_cmd % N_GOALS];
            n_cmd++;
            new_cmd = 1;
        }

        /* The two controllers, same inputs. */
        sent_before = buf_gen.TB_cmd.head.serial;
        state_before = buf_gen.PR_status.head.state;
        submarine_PR_step(&gen, &buf_gen, cycle);
        hand_pr_step(&buf_hand, cycle);
        if (!compare(cycle)) {
            return 1;
        }

        /* Statistics: which rule fired (or why none did). */
        goal = buf_gen.PR_cmd.args.AHEAD.speed;
        if (new_cmd) {
            counts[W_NEW]++;
            counts[buf_gen.PR_status.head.rule == 10 ? W_E0 : W_E1]++;
        } else if (state_before != 4 && state_before != 5) {
            counts[W_IDLE]++;
        } else if (buf_gen.TB_cmd.head.serial != sent_before) {
            const int32_t r = buf_gen.PR_status.head.rule;
            counts[r == 13 ? W_E2 : r == 15 ? W_E4 : W_E5]++;
        } else if (buf_gen.PR_status.head.state == 3) {
            counts[W_E9]++;
        } else if (!(sent_before != 0u && tb_echo == sent_before && tb_status == RCS_DONE)) {
            counts[W_WAIT_TB]++;
        } else if (fabs_(ship_speed - goal) <= 0.25) {
            counts[W_E3]++;
        } else {
            counts[W_WAIT_CLOSING]++;
        }

        /* TB (scheduled after PR): take a new command, spool, report. */
        if (buf_gen.TB_cmd.head.serial != tb_echo) {
            tb_echo = buf_gen.TB_cmd.head.serial;
            tb_verb = buf_gen.TB_cmd.head.verb;
            rpm_goal = tb_verb == submarine_TB_VERB_AHEAD ? buf_gen.TB_cmd.args.AHEAD.rpm : 0.0;
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
        buf_gen.TB_status.head.echo_serial = buf_hand.TB_status.head.echo_serial = tb_echo;
        buf_gen.TB_status.head.status = buf_hand.TB_status.head.status = tb_status;
        buf_gen.TB_status.head.verb = buf_hand.TB_status.head.verb = tb_verb;
        buf_gen.TB_status.head.error_code = buf_hand.TB_status.head.error_code = tb_error;
        buf_gen.TB_status.head.stamp = buf_hand.TB_status.head.stamp = cycle;
        buf_gen.TB_status.f.shaft_rpm = buf_hand.TB_status.f.shaft_rpm = shaft_rpm;
        buf_gen.TB_status.f.tripped = buf_hand.TB_status.f.tripped = tripped;
    }

    printf("steps %lu\n", steps);
    for (int i = 0; i < W_N; i++) {
        printf("count %s %lu\n", what_names[i], counts[i]);
    }
    printf("identical buffers after every step: yes\n");
    return 0;
}
