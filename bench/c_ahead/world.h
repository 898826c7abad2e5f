/* world.h: the world PR's AHEAD benchmark runs in, shared by the C drivers.
 *
 * Each cycle: world_before_step moves a small plant (the ship follows the
 * shaft, with a hull 5 times lighter than SHIP_SIM's so that the trim rules
 * fire often, plus a sea disturbance that changes sign every 150 cycles)
 * and plays PR's supervisor (a new AHEAD command every CMD_EVERY cycles);
 * then the driver steps PR; then world_after_step counts which rule fired
 * (or why none did) and plays TB, scheduled after PR: it echoes the serial
 * of TB's command, reports EXEC while the shaft spools, DONE when it is
 * there, ERROR on the scripted trip.  Scripted events: the ship goes astern
 * before the 5th command (E1, then E5) and the turbine trips at TRIP_CYCLE
 * (E9; PR then idles until the next command).  Every buffer set given gets
 * the same inputs; the statistics read the first.  bench/rust_ahead/driver.rs
 * is the Rust twin of this file: keep the two in step.
 */
#ifndef BENCH_WORLD_H
#define BENCH_WORLD_H

#include <stdio.h>
#include <string.h>

#include "submarine_PR.h"

#define CMD_EVERY 1000u
#define BACK_CMD 4u      /* index of the command given while going astern */
#define TRIP_CYCLE 7800u /* the turbine trips in this cycle */

static const double goals[] = {10.0, 14.0, 8.0, 16.0, 5.0, 12.0, 9.0, 18.0, 6.0, 11.0};
#define N_GOALS (sizeof goals / sizeof goals[0])

enum { W_NEW, W_E0, W_E1, W_E2, W_E3, W_E4, W_E5, W_E9, W_WAIT_TB, W_WAIT_CLOSING, W_IDLE, W_N };
static const char *const what_names[W_N] = {"new", "E0", "E1", "E2", "E3", "E4", "E5", "E9", "wait_tb", "wait_closing", "idle"};

typedef struct {
    double ship_speed, shaft_rpm, rpm_goal;
    uint32_t tb_echo;
    int32_t tb_status, tb_verb, tb_error;
    bool tripped;
    uint32_t pr_serial;
    unsigned n_cmd;
    /* this cycle, for the statistics */
    int new_cmd;
    uint32_t sent_before;
    int32_t state_before;
    unsigned long counts[W_N];
} bench_world;

static double fabs_(double x) { return x < 0.0 ? -x : x; }

static void world_init(bench_world *w)
{
    memset(w, 0, sizeof *w);
    w->tb_status = RCS_UNINITIALIZED;
}

static void world_before_step(bench_world *w, submarine_buffers *const *bufs, size_t n, uint64_t cycle)
{
    const double sea = ((cycle / 150u) % 2u == 0u) ? 0.001 : -0.001;
    int32_t ship_dir;
    w->ship_speed += (0.01 * w->shaft_rpm * fabs_(w->shaft_rpm) - w->ship_speed * fabs_(w->ship_speed)) / 60.0 * 0.03 + sea;
    if (w->n_cmd == BACK_CMD && cycle % CMD_EVERY == 0u) {
        w->ship_speed = -1.5; /* scripted: astern when the next AHEAD arrives (E1, E5) */
        w->shaft_rpm = -20.0;
    }
    ship_dir = w->ship_speed > 0.1 ? submarine_ShipDir__AHEAD
               : w->ship_speed < -0.1 ? submarine_ShipDir__BACK
                                      : submarine_ShipDir__STOPPED;
    w->new_cmd = cycle % CMD_EVERY == 1u;
    if (w->new_cmd) {
        w->pr_serial = rcs_next_serial(w->pr_serial);
    }
    for (size_t i = 0; i < n; i++) {
        bufs[i]->gm.ship_speed = w->ship_speed;
        bufs[i]->gm.ship_dir = ship_dir;
        if (w->new_cmd) {
            bufs[i]->PR__cmd.head.serial = w->pr_serial;
            bufs[i]->PR__cmd.head.verb = submarine_PR__VERB__AHEAD;
            bufs[i]->PR__cmd.args.AHEAD.speed = goals[w->n_cmd % N_GOALS];
        }
    }
    if (w->new_cmd) {
        w->n_cmd++;
    }
    w->sent_before = bufs[0]->TB__cmd.head.serial;
    w->state_before = bufs[0]->PR__status.head.state;
}

static void world_after_step(bench_world *w, submarine_buffers *const *bufs, size_t n, uint64_t cycle)
{
    const submarine_buffers *b = bufs[0];
    /* Statistics: which rule fired (or why none did). */
    if (w->new_cmd) {
        w->counts[W_NEW]++;
        w->counts[b->PR__status.head.rule == 10 ? W_E0 : W_E1]++;
    } else if (w->state_before != 4 && w->state_before != 5) {
        w->counts[W_IDLE]++;
    } else if (b->TB__cmd.head.serial != w->sent_before) {
        const int32_t r = b->PR__status.head.rule;
        w->counts[r == 13 ? W_E2 : r == 15 ? W_E4 : W_E5]++;
    } else if (b->PR__status.head.state == 3) {
        w->counts[W_E9]++;
    } else if (!(w->sent_before != 0u && w->tb_echo == w->sent_before && w->tb_status == RCS_DONE)) {
        w->counts[W_WAIT_TB]++;
    } else if (fabs_(w->ship_speed - b->PR__cmd.args.AHEAD.speed) <= 0.25) {
        w->counts[W_E3]++;
    } else {
        w->counts[W_WAIT_CLOSING]++;
    }

    /* TB (scheduled after PR): take a new command, spool, report. */
    if (b->TB__cmd.head.serial != w->tb_echo) {
        w->tb_echo = b->TB__cmd.head.serial;
        w->tb_verb = b->TB__cmd.head.verb;
        w->rpm_goal = w->tb_verb == submarine_TB__VERB__AHEAD ? b->TB__cmd.args.AHEAD.rpm : 0.0;
        w->tb_status = RCS_EXEC;
        w->tb_error = 0;
    }
    w->tripped = cycle == TRIP_CYCLE;
    if (w->tripped) {
        w->rpm_goal = 0.0;
        if (w->tb_status == RCS_EXEC || w->tb_status == RCS_DONE) {
            w->tb_status = RCS_ERROR;
            w->tb_error = submarine_ERR_TRIP;
        }
    }
    {
        const double d = w->rpm_goal - w->shaft_rpm;
        w->shaft_rpm += d > 0.6 ? 0.6 : d < -0.6 ? -0.6 : d;
    }
    if (w->tb_status == RCS_EXEC && fabs_(w->shaft_rpm - w->rpm_goal) <= 1.0) {
        w->tb_status = RCS_DONE;
    }
    for (size_t i = 0; i < n; i++) {
        bufs[i]->TB__status.head.echo_serial = w->tb_echo;
        bufs[i]->TB__status.head.status = w->tb_status;
        bufs[i]->TB__status.head.verb = w->tb_verb;
        bufs[i]->TB__status.head.error_code = w->tb_error;
        bufs[i]->TB__status.head.stamp = cycle;
        bufs[i]->TB__status.f.shaft_rpm = w->shaft_rpm;
        bufs[i]->TB__status.f.tripped = w->tripped;
    }
}

static void world_print_counts(const bench_world *w, unsigned long steps)
{
    printf("steps %lu\n", steps);
    for (int i = 0; i < W_N; i++) {
        printf("count %s %lu\n", what_names[i], w->counts[i]);
    }
}

#endif /* BENCH_WORLD_H */
