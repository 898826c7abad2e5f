/* handwritten_pr.c: PR's AHEAD plan written by hand, in the style of the
 * RCS methodology paper (Appendix A template, Appendix C state table).
 *
 * The baseline for bench/bench_c_step.py: what a programmer following the
 * paper would write for submarine.rcs's PR AHEAD plan, with the echo-serial
 * protocol of rcsc's cycle semantics added (the paper's template compares
 * command numbers but never checks that the subordinate's status answers the
 * command last sent).  It works on the generated buffers (submarine.h) so
 * that the driver can compare both versions buffer for buffer after every
 * step; the state, rule and verb numbers written to the status buffer are
 * those of the generated tables, for the same reason.
 *
 * Only the AHEAD plan is written out (as in Appendix C); the other plans
 * would be more `else if` branches of pr_decision_process.
 */
#include "submarine.h"
#include "handwritten_pr.h"

/* Current states (numbered as the generated controller numbers them). */
#define S0 1      /* new command */
#define S_DONE 2  /* NOP: done */
#define S_ERROR 3 /* NOP: error */
#define S1 4
#define S2 5

/* Rules of the AHEAD plan (numbered as in the generated rule table). */
#define RULE_E0 10
#define RULE_E1 11
#define RULE_E9 12
#define RULE_E2 13
#define RULE_E3 14
#define RULE_E4 15
#define RULE_E5 16

/* Private state: own status out, command out to TB, world model. */
static submarine_PR__status pr_so; /* status out (PR_STATUS of the template) */
static submarine_TB__cmd tb_co;    /* command out to TB; tb_co.head.serial = serial last sent */
static bool tb_new;               /* a command to TB was issued this cycle */
static double prop_speed;         /* rpm ordered from TB */
static double last_speed;         /* knots, previous cycle */
static double ship_accel;         /* knots/s, filtered */

void hand_pr_init(void)
{
    pr_so.head.echo_serial = 0u;
    pr_so.head.status = RCS_UNINITIALIZED;
    pr_so.head.verb = 0;
    pr_so.head.state = 0;
    pr_so.head.rule = 0;
    pr_so.head.error_code = 0;
    pr_so.head.stamp = 0u;
    pr_so.f.tb_fault = 0;
    tb_co.head.serial = 0u;
    tb_co.head.verb = 0;
    tb_co.args.AHEAD.rpm = 0.0;
    tb_new = false;
    prop_speed = 0.0;
    last_speed = 0.0;
    ship_accel = 0.0;
}

/* Appendix C: PROPULSION CONTROL: AHEAD, AT DESIRED SPEED. */
static void pr_ahead(const submarine_buffers *G)
{
    const submarine_TB__status *tb_si = &G->TB__status;
    const int32_t ship_dir = G->gm.ship_dir;
    const int32_t state = pr_so.head.state;
    const bool tb_current = tb_co.head.serial != 0u && tb_si->head.echo_serial == tb_co.head.serial;
    const bool tb_done = tb_current && tb_si->head.status == RCS_DONE;

    if (state == S0 && (ship_dir == submarine_ShipDir__AHEAD || ship_dir == submarine_ShipDir__STOPPED)) {
        /* E0 */
        pr_so.head.status = RCS_EXEC;
        pr_so.head.rule = RULE_E0;
        pr_so.head.state = S1;
        prop_speed = G->PR__cmd.args.AHEAD.speed * submarine_RPM_PER_KNOT;
        if (prop_speed < 0.0) {
            prop_speed = 0.0;
        } else if (prop_speed > submarine_MAX_AHEAD_RPM) {
            prop_speed = submarine_MAX_AHEAD_RPM;
        }
        tb_co.head.verb = submarine_TB__VERB__AHEAD;
        tb_co.args.AHEAD.rpm = prop_speed;
        tb_new = true;
    } else if (state == S0 && ship_dir == submarine_ShipDir__BACK) {
        /* E1 */
        pr_so.head.status = RCS_EXEC;
        pr_so.head.rule = RULE_E1;
        pr_so.head.state = S2;
        tb_co.head.verb = submarine_TB__VERB__STOP;
        tb_new = true;
    } else if ((state == S0 || state == S1 || state == S2) &&
               ((tb_current && tb_si->head.status == RCS_ERROR) || tb_si->f.tripped)) {
        /* E9 */
        pr_so.head.status = RCS_ERROR;
        pr_so.head.rule = RULE_E9;
        pr_so.head.state = S_ERROR;
        pr_so.head.error_code = submarine_ERR_TURBINE;
        pr_so.f.tb_fault = tb_si->f.tripped ? submarine_ERR_TRIP : tb_si->head.error_code;
    } else if (state == S1 && tb_done) {
        /* sub_speed_status (WM), then E2, E3, E4 */
        const double speed = G->gm.ship_speed;
        const double goal = G->PR__cmd.args.AHEAD.speed;
        const double diff = speed - goal;
        if (diff <= submarine_SPEED_TOL && diff >= -submarine_SPEED_TOL) {
            /* E3: at speed */
            pr_so.head.status = submarine_PR__STATUS__AT_GOAL;
            pr_so.head.rule = RULE_E3;
        } else if (speed < goal) {
            if (!(ship_accel > submarine_SETTLED_ACCEL)) {
                /* E2: below speed (not still closing) */
                pr_so.head.status = RCS_EXEC;
                pr_so.head.rule = RULE_E2;
                prop_speed = prop_speed + submarine_RPM_STEP;
                if (prop_speed > submarine_MAX_AHEAD_RPM) {
                    prop_speed = submarine_MAX_AHEAD_RPM;
                }
                tb_co.head.verb = submarine_TB__VERB__AHEAD;
                tb_co.args.AHEAD.rpm = prop_speed;
                tb_new = true;
            }
        } else {
            if (!(ship_accel < -submarine_SETTLED_ACCEL)) {
                /* E4: above speed (not still closing) */
                pr_so.head.status = RCS_EXEC;
                pr_so.head.rule = RULE_E4;
                prop_speed = prop_speed - submarine_RPM_STEP;
                if (prop_speed < 0.0) {
                    prop_speed = 0.0;
                }
                tb_co.head.verb = submarine_TB__VERB__AHEAD;
                tb_co.args.AHEAD.rpm = prop_speed;
                tb_new = true;
            }
        }
    } else if (state == S2 && tb_done) {
        /* E5 */
        pr_so.head.status = RCS_EXEC;
        pr_so.head.rule = RULE_E5;
        pr_so.head.state = S1;
        prop_speed = G->PR__cmd.args.AHEAD.speed * submarine_RPM_PER_KNOT;
        if (prop_speed < 0.0) {
            prop_speed = 0.0;
        } else if (prop_speed > submarine_MAX_AHEAD_RPM) {
            prop_speed = submarine_MAX_AHEAD_RPM;
        }
        tb_co.head.verb = submarine_TB__VERB__AHEAD;
        tb_co.args.AHEAD.rpm = prop_speed;
        tb_new = true;
    } else {
        /* DEFAULT: no rule fires (waiting for TB, or the hull settling) */
    }
}

void hand_pr_step(submarine_buffers *G, uint64_t cycle)
{
    /* Pre-process (SP/WM): acceleration from the speed log, low-pass filtered. */
    const double ship_speed = G->gm.ship_speed;
    ship_accel = ship_accel + (submarine_DT / (submarine_ACCEL_TAU + submarine_DT)) *
                                  ((ship_speed - last_speed) / submarine_DT - ship_accel);
    last_speed = ship_speed;
    tb_new = false;

    /* Check if new command. */
    if (G->PR__cmd.head.serial != pr_so.head.echo_serial) {
        pr_so.head.echo_serial = G->PR__cmd.head.serial;
        pr_so.head.status = RCS_EXEC;
        pr_so.head.verb = G->PR__cmd.head.verb;
        pr_so.head.state = S0;
        pr_so.head.rule = 0;
        pr_so.head.error_code = 0;
        if (pr_so.head.verb != submarine_PR__VERB__AHEAD) {
            /* only AHEAD is written out here: any other verb is refused */
            pr_so.head.status = RCS_ERROR;
        }
    }

    /* Decision process: select the state table of the command. */
    if (pr_so.head.verb == submarine_PR__VERB__AHEAD) {
        pr_ahead(G);
    }

    /* Post-process: write status every cycle, the command to TB when issued. */
    pr_so.head.stamp = cycle;
    G->PR__status = pr_so;
    if (tb_new) {
        tb_co.head.serial = tb_co.head.serial == UINT32_MAX ? 1u : tb_co.head.serial + 1u;
        G->TB__cmd = tb_co;
    }
}
