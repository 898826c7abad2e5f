/* runtime_fixture.c: a hand-made design for tests/test_c_runtime.py.
 *
 * It fills the tables of rcs_runtime.h the way generated code does, with a
 * tiny design:
 *
 *   enum Mode { IDLE, RUN, HALT }        enum Color { RED, GREEN }
 *   record Pose { x: f64, y: f64, mode: Mode }
 *   const MAX_SPEED: f64 = 12.5, LIMIT_K: i32 = 7, STEP_T: duration = 250 ms,
 *         FAST: Mode = Mode.RUN, HOME: Pose = Pose(1.0, 2.0, Mode.RUN), NEG_U: u32 = 5
 *   gm pose: Pose, mode: Mode              (written by TOP)
 *   gm door: bool from env, limit: i32 from env, gain: f64 from env
 *   controller TOP (top): verbs INIT(), MOVE(speed: f64, dt: duration, mode: Mode, to: Pose),
 *                         SET(n: u32, big: i64); reports AT_GOAL
 *   controller SUB (has a supervisor): verb GO(); counts its steps
 *   schedule SUB, TOP
 *
 * TOP's step is a stand-in for a compiled controller: on a new command it
 * echoes the serial, takes the verb, fires rule N0, copies the arguments
 * into its status fields and sets error_code to gm.limit (which shows that a
 * cycle's inputs are applied before its commands); MOVE enters MOVING, and
 * in the next cycle puts the target into gm.pose and reports AT_GOAL by rule
 * "Q\"1\\\001" (a label that needs escaping in JSON).
 */
#include <math.h>
#include <stddef.h>

#include "rcs_runtime.h"

typedef struct {
    double x;
    double y;
    int32_t mode;
} Pose;

typedef struct {
    Pose pose;
    int32_t mode;
    bool door;
    int32_t limit;
    double gain;
} Gm;

typedef struct {
    double speed;
    int64_t dt;
    int32_t mode;
    Pose to;
} MoveArgs;

typedef struct {
    uint32_t n;
    int64_t big;
} SetArgs;

typedef struct {
    rcs_command_head head;
    union {
        MoveArgs move;
        SetArgs set;
    } args;
} TopCmd;

typedef struct {
    double speed;
    int64_t dt;
    Pose target;
    uint32_t n;
    int64_t big;
    double ratio;
    bool door_seen;
} TopFields;

typedef struct {
    rcs_status_head head;
    TopFields f;
} TopStatus;

typedef struct {
    rcs_command_head head;
    int32_t unused;
} SubCmd;

typedef struct {
    rcs_status_head head;
    struct {
        int32_t ticks;
    } f;
} SubStatus;

static Gm gm;
static TopCmd top_cmd;
static TopStatus top_status;
static SubCmd sub_cmd;
static SubStatus sub_status;

static const char *const mode_members[] = {"IDLE", "RUN", "HALT"};
static const rcs_type mode_type = {RCS_T_ENUM, "Mode", mode_members, 3, NULL, 0};
static const char *const color_members[] = {"RED", "GREEN"};
static const rcs_type color_type = {RCS_T_ENUM, "Color", color_members, 2, NULL, 0};
static const rcs_field pose_fields[] = {
    {"x", offsetof(Pose, x), &rcs_type_f64},
    {"y", offsetof(Pose, y), &rcs_type_f64},
    {"mode", offsetof(Pose, mode), &mode_type},
};
static const rcs_type pose_type = {RCS_T_RECORD, "Pose", NULL, 0, pose_fields, 3};
static const rcs_type *const types[] = {&mode_type, &color_type, &pose_type};

static const double c_max_speed = 12.5;
static const int32_t c_limit_k = 7;
static const int64_t c_step_t = 250000000;
static const int32_t c_fast = 1;
static const Pose c_home = {1.0, 2.0, 1};
static const uint32_t c_neg_u = 5;
static const rcs_const consts[] = {
    {"MAX_SPEED", &rcs_type_f64, &c_max_speed}, {"LIMIT_K", &rcs_type_i32, &c_limit_k},
    {"STEP_T", &rcs_type_duration, &c_step_t},  {"FAST", &mode_type, &c_fast},
    {"HOME", &pose_type, &c_home},              {"NEG_U", &rcs_type_u32, &c_neg_u},
};

static const rcs_field gm_fields[] = {
    {"pose", offsetof(Gm, pose), &pose_type},    {"mode", offsetof(Gm, mode), &mode_type},
    {"door", offsetof(Gm, door), &rcs_type_bool}, {"limit", offsetof(Gm, limit), &rcs_type_i32},
    {"gain", offsetof(Gm, gain), &rcs_type_f64},
};
static const unsigned char gm_from_env[] = {0, 0, 1, 1, 1};

static const rcs_field move_params[] = {
    {"speed", offsetof(MoveArgs, speed), &rcs_type_f64},
    {"dt", offsetof(MoveArgs, dt), &rcs_type_duration},
    {"mode", offsetof(MoveArgs, mode), &mode_type},
    {"to", offsetof(MoveArgs, to), &pose_type},
};
static const rcs_field set_params[] = {
    {"n", offsetof(SetArgs, n), &rcs_type_u32},
    {"big", offsetof(SetArgs, big), &rcs_type_i64},
};
static const rcs_verb top_verbs[] = {{"INIT", NULL, 0}, {"MOVE", move_params, 4}, {"SET", set_params, 2}};
static const rcs_field top_fields[] = {
    {"speed", offsetof(TopFields, speed), &rcs_type_f64}, {"dt", offsetof(TopFields, dt), &rcs_type_duration},
    {"target", offsetof(TopFields, target), &pose_type},  {"n", offsetof(TopFields, n), &rcs_type_u32},
    {"big", offsetof(TopFields, big), &rcs_type_i64},     {"ratio", offsetof(TopFields, ratio), &rcs_type_f64},
    {"door_seen", offsetof(TopFields, door_seen), &rcs_type_bool},
};
static const char *const top_states[] = {"", "new", "done", "error", "MOVING"};
static const char *const top_rules[] = {"", "N0", "Q\"1\\\001"};
static const rcs_status_name top_extra[] = {{"AT_GOAL", 4}};

static const rcs_verb sub_verbs[] = {{"GO", NULL, 0}};
static const rcs_field sub_fields[] = {{"ticks", 0, &rcs_type_i32}};
static const char *const sub_states[] = {"", "new", "done", "error"};
static const char *const sub_rules[] = {""};

static void top_step(uint64_t cycle) {
    rcs_status_head *h = &top_status.head;
    TopFields *f = &top_status.f;
    h->stamp = cycle;
    if (top_cmd.head.serial != h->echo_serial) {
        h->echo_serial = top_cmd.head.serial;
        h->verb = top_cmd.head.verb;
        h->rule = 1;
        h->error_code = gm.limit;
        switch (h->verb) {
        case 1:
            h->status = RCS_DONE;
            h->state = 2;
            break;
        case 2:
            f->speed = top_cmd.args.move.speed;
            f->dt = top_cmd.args.move.dt;
            f->target = top_cmd.args.move.to;
            gm.mode = top_cmd.args.move.mode;
            h->status = RCS_EXEC;
            h->state = 4;
            break;
        case 3:
            f->n = top_cmd.args.set.n;
            f->big = top_cmd.args.set.big;
            h->status = RCS_DONE;
            h->state = 2;
            break;
        default: break;
        }
    } else if (h->state == 4 && h->status == RCS_EXEC) {
        gm.pose = f->target;
        h->status = 4;
        h->rule = 2;
    }
    f->ratio = f->speed > 0.0 ? 1.0 / f->speed : f->speed < 0.0 ? -INFINITY : NAN;
    f->door_seen = gm.door;
}

static void sub_step(uint64_t cycle) {
    sub_status.head.stamp = cycle;
    sub_status.f.ticks = rcs_add_i32(sub_status.f.ticks, 1);
}

static const rcs_ctrl ctrls[] = {
    {"TOP", 1, 0, 1000000, top_step, &top_cmd.head, &top_cmd.args, sizeof top_cmd.args, top_verbs, 3,
     &top_status.head, &top_status.f, top_fields, 7, top_states, 5, top_rules, 3, top_extra, 1, 1},
    {"SUB", 0, 0, 0, sub_step, &sub_cmd.head, &sub_cmd.unused, sizeof sub_cmd.unused, sub_verbs, 1,
     &sub_status.head, &sub_status.f, sub_fields, 1, sub_states, 4, sub_rules, 1, NULL, 0, 1},
};
static const size_t schedule[] = {1, 0};

static const rcs_design design = {
    "fixture", "MAIN", 1000000, &gm, gm_fields, gm_from_env, 5, consts, 6, types, 3, ctrls, 2, schedule, 2, NULL, NULL, NULL, NULL, NULL,
    "fb17482bafd2da03", /* the interface hash of tests/event_cases.py FIXTURE_RCS */
};

int main(int argc, char **argv) {
    top_status.head.status = RCS_UNINITIALIZED;
    sub_status.head.status = RCS_UNINITIALIZED;
    return rcs_main(argc, argv, &design);
}
