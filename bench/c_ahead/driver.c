/* driver.c: runs PR's AHEAD plan, generated and hand-written, side by side.
 *
 *     driver [STEPS]        (default 10000)
 *
 * In the world of world.h (plant, supervisor, TB), the driver steps the
 * generated controller (submarine_PR__step) on one set of buffers and the
 * hand-written one (hand_pr_step) on another set, with identical inputs,
 * and compares what both wrote (PR's status buffer and TB's command buffer)
 * after every step.  The first difference stops the run with exit status 1:
 * that comparison is the proof that the hand-written version computes the
 * same thing.  The run prints how often each rule fired and how many steps
 * waited; bench/bench_c_step.py counts the instructions of the step
 * functions with callgrind (--toggle-collect).
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "handwritten_pr.h"
#include "submarine_PR.h"

#include "world.h"

static submarine_PR gen;          /* the generated controller's private state */
static submarine_buffers buf_gen; /* buffers of the generated controller */
static submarine_buffers buf_hand; /* buffers of the hand-written controller */

static int same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

static int compare(uint64_t cycle)
{
    const rcs_status_head *g = &buf_gen.PR__status.head;
    const rcs_status_head *h = &buf_hand.PR__status.head;
    int ok = g->echo_serial == h->echo_serial && g->status == h->status && g->verb == h->verb &&
             g->state == h->state && g->rule == h->rule && g->error_code == h->error_code &&
             g->stamp == h->stamp && buf_gen.PR__status.f.tb_fault == buf_hand.PR__status.f.tb_fault &&
             buf_gen.TB__cmd.head.serial == buf_hand.TB__cmd.head.serial &&
             buf_gen.TB__cmd.head.verb == buf_hand.TB__cmd.head.verb &&
             same_double(buf_gen.TB__cmd.args.AHEAD.rpm, buf_hand.TB__cmd.args.AHEAD.rpm);
    if (!ok) {
        fprintf(stderr,
                "MISMATCH at cycle %" PRIu64 ":\n"
                "  generated:    echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
                " tb_fault %d | TB cmd serial %" PRIu32 " verb %d rpm %.17g\n"
                "  hand-written: echo %" PRIu32 " status %d verb %d state %d rule %d err %d stamp %" PRIu64
                " tb_fault %d | TB cmd serial %" PRIu32 " verb %d rpm %.17g\n",
                cycle, g->echo_serial, (int)g->status, (int)g->verb, (int)g->state, (int)g->rule,
                (int)g->error_code, g->stamp, (int)buf_gen.PR__status.f.tb_fault, buf_gen.TB__cmd.head.serial,
                (int)buf_gen.TB__cmd.head.verb, buf_gen.TB__cmd.args.AHEAD.rpm, h->echo_serial, (int)h->status,
                (int)h->verb, (int)h->state, (int)h->rule, (int)h->error_code, h->stamp,
                (int)buf_hand.PR__status.f.tb_fault, buf_hand.TB__cmd.head.serial, (int)buf_hand.TB__cmd.head.verb,
                buf_hand.TB__cmd.args.AHEAD.rpm);
    }
    return ok;
}

int main(int argc, char **argv)
{
    const unsigned long steps = argc > 1 ? strtoul(argv[1], NULL, 10) : 10000ul;
    submarine_buffers *const bufs[] = {&buf_gen, &buf_hand};
    bench_world w;
    uint64_t cycle;

    world_init(&w);
    memset(&buf_gen, 0, sizeof buf_gen);
    memset(&buf_hand, 0, sizeof buf_hand);
    submarine_buffers_init(&buf_gen);
    submarine_buffers_init(&buf_hand);
    submarine_PR__init(&gen);
    hand_pr_init();

    for (cycle = 1u; cycle <= steps; cycle++) {
        world_before_step(&w, bufs, 2u, cycle);
        /* The two controllers, same inputs. */
        submarine_PR__step(&gen, &buf_gen, cycle);
        hand_pr_step(&buf_hand, cycle);
        if (!compare(cycle)) {
            return 1;
        }
        world_after_step(&w, bufs, 2u, cycle);
    }

    world_print_counts(&w, steps);
    printf("identical buffers after every step: yes\n");
    return 0;
}
