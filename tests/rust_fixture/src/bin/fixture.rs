//! The Main Program of a tiny hand-made design, in the shape rcsc generates
//! (tables describing the design, `HostDesign` over its state, `host::run`):
//! the Rust twin of tests/c/runtime_fixture.c, so that both Main Programs
//! can be run on the same scenarios and compared byte for byte.
//!
//!   enum Mode { IDLE, RUN, HALT }        enum Color { RED, GREEN }
//!   record Pose { x: f64, y: f64, mode: Mode }
//!   const MAX_SPEED: f64 = 12.5, LIMIT_K: i32 = 7, STEP_T: duration = 250 ms,
//!         FAST: Mode = Mode.RUN, HOME: Pose = Pose(1.0, 2.0, Mode.RUN), NEG_U: u32 = 5
//!   gm pose: Pose, mode: Mode              (written by TOP)
//!   gm door: bool from env, limit: i32 from env, gain: f64 from env
//!   controller TOP (top): verbs INIT(), MOVE(speed: f64, dt: duration, mode: Mode, to: Pose),
//!                         SET(n: u32, big: i64); reports AT_GOAL
//!   controller SUB (has a supervisor): verb GO(); counts its steps
//!   schedule SUB, TOP; heartbeat 1 ms
//!
//! TOP's step is a stand-in for a compiled controller: on a new command it
//! echoes the serial, takes the verb, fires rule N0, copies the arguments
//! into its status fields and sets error_code to gm.limit; MOVE enters
//! MOVING, and in the next cycle puts the target into gm.pose and reports
//! AT_GOAL by rule "Q\"1\\\001" (a label that needs escaping in JSON).
//!
//! Two test modes come before the Main Program: `--fmt` prints, for each
//! line of standard input (an f64 as 16 hex digits of its bits), the trace's
//! text of it; `--num` prints num.rs results on edge cases.

#[path = "../../host/mod.rs"]
mod host;

use fixture::num;
use host::{
    ConstDesc, CtrlDesc, DesignDesc, FieldDesc, GmDesc, HostDesign, Kind, StatusView, TypeDesc,
    Value, VerbDesc,
};
use std::io::{BufRead, Write};

static MODE: TypeDesc = TypeDesc {
    name: "Mode",
    kind: Kind::Enum(&["IDLE", "RUN", "HALT"]),
};
static COLOR: TypeDesc = TypeDesc {
    name: "Color",
    kind: Kind::Enum(&["RED", "GREEN"]),
};
static POSE: TypeDesc = TypeDesc {
    name: "Pose",
    kind: Kind::Record(&[
        FieldDesc {
            name: "x",
            ty: &host::F64,
        },
        FieldDesc {
            name: "y",
            ty: &host::F64,
        },
        FieldDesc {
            name: "mode",
            ty: &MODE,
        },
    ]),
};

static DESIGN: DesignDesc = DesignDesc {
    design: "fixture",
    cpu: "MAIN",
    period_ns: 1_000_000,
    gm: &[
        GmDesc {
            name: "pose",
            ty: &POSE,
            from_env: false,
        },
        GmDesc {
            name: "mode",
            ty: &MODE,
            from_env: false,
        },
        GmDesc {
            name: "door",
            ty: &host::BOOL,
            from_env: true,
        },
        GmDesc {
            name: "limit",
            ty: &host::I32,
            from_env: true,
        },
        GmDesc {
            name: "gain",
            ty: &host::F64,
            from_env: true,
        },
    ],
    consts: &[
        ConstDesc {
            name: "MAX_SPEED",
            ty: &host::F64,
        },
        ConstDesc {
            name: "LIMIT_K",
            ty: &host::I32,
        },
        ConstDesc {
            name: "STEP_T",
            ty: &host::DURATION,
        },
        ConstDesc {
            name: "FAST",
            ty: &MODE,
        },
        ConstDesc {
            name: "HOME",
            ty: &POSE,
        },
        ConstDesc {
            name: "NEG_U",
            ty: &host::U32,
        },
    ],
    types: &[&MODE, &COLOR, &POSE],
    ctrls: &[
        CtrlDesc {
            name: "TOP",
            top: true,
            simulator: false,
            budget_ns: 1_000_000,
            verbs: &[
                VerbDesc {
                    name: "INIT",
                    params: &[],
                },
                VerbDesc {
                    name: "MOVE",
                    params: &[
                        FieldDesc {
                            name: "speed",
                            ty: &host::F64,
                        },
                        FieldDesc {
                            name: "dt",
                            ty: &host::DURATION,
                        },
                        FieldDesc {
                            name: "mode",
                            ty: &MODE,
                        },
                        FieldDesc {
                            name: "to",
                            ty: &POSE,
                        },
                    ],
                },
                VerbDesc {
                    name: "SET",
                    params: &[
                        FieldDesc {
                            name: "n",
                            ty: &host::U32,
                        },
                        FieldDesc {
                            name: "big",
                            ty: &host::I64,
                        },
                    ],
                },
            ],
            fields: &[
                FieldDesc {
                    name: "speed",
                    ty: &host::F64,
                },
                FieldDesc {
                    name: "dt",
                    ty: &host::DURATION,
                },
                FieldDesc {
                    name: "target",
                    ty: &POSE,
                },
                FieldDesc {
                    name: "n",
                    ty: &host::U32,
                },
                FieldDesc {
                    name: "big",
                    ty: &host::I64,
                },
                FieldDesc {
                    name: "ratio",
                    ty: &host::F64,
                },
                FieldDesc {
                    name: "door_seen",
                    ty: &host::BOOL,
                },
            ],
            extra_statuses: &[("AT_GOAL", 4)],
            divider: 1,
        },
        CtrlDesc {
            name: "SUB",
            top: false,
            simulator: false,
            budget_ns: 0,
            verbs: &[VerbDesc {
                name: "GO",
                params: &[],
            }],
            fields: &[FieldDesc {
                name: "ticks",
                ty: &host::I32,
            }],
            extra_statuses: &[],
            divider: 1,
        },
    ],
    schedule: &[1, 0],
    multi: None,
    // The interface hash of tests/event_cases.py FIXTURE_RCS.
    events_hash: "fb17482bafd2da03",
};

const TOP_STATES: [&str; 5] = ["", "new", "done", "error", "MOVING"];
const TOP_RULES: [&str; 3] = ["", "N0", "Q\"1\\\u{1}"];

#[derive(Clone, Copy, Default)]
struct Pose {
    x: f64,
    y: f64,
    mode: usize,
}

impl Pose {
    fn value(&self) -> Value {
        Value::Record(vec![
            Value::F64(self.x),
            Value::F64(self.y),
            Value::Enum(self.mode),
        ])
    }

    fn from_value(v: &Value) -> Pose {
        match v {
            Value::Record(f) => match f.as_slice() {
                [Value::F64(x), Value::F64(y), Value::Enum(mode)] => Pose {
                    x: *x,
                    y: *y,
                    mode: *mode,
                },
                _ => Pose::default(),
            },
            _ => Pose::default(),
        }
    }
}

#[derive(Default)]
struct Head {
    echo: u32,
    status: i32,
    verb: usize,
    state: usize,
    rule: usize,
    error_code: i32,
}

impl Head {
    fn view(
        &self,
        states: &[&'static str],
        rules: &[&'static str],
        fields: Vec<Value>,
    ) -> StatusView {
        StatusView {
            echo: self.echo,
            status: self.status,
            verb: self.verb,
            state: states.get(self.state).copied().unwrap_or("?"),
            rule: rules.get(self.rule).copied().unwrap_or("?"),
            error_code: self.error_code,
            fields,
        }
    }
}

#[derive(Default)]
struct Fixture {
    // Global Memory
    pose: Pose,
    mode: usize,
    door: bool,
    limit: i32,
    gain: f64,
    // TOP's command buffer
    serial: u32,
    cmd_verb: usize,
    move_speed: f64,
    move_dt: i64,
    move_mode: usize,
    move_to: Pose,
    set_n: u32,
    set_big: i64,
    // TOP's status
    top: Head,
    speed: f64,
    dt: i64,
    target: Pose,
    n: u32,
    big: i64,
    ratio: f64,
    door_seen: bool,
    // SUB's status
    sub: Head,
    ticks: i32,
}

impl Fixture {
    fn new() -> Fixture {
        let mut f = Fixture::default();
        f.top.status = num::UNINITIALIZED;
        f.sub.status = num::UNINITIALIZED;
        f
    }

    fn top_step(&mut self) {
        if self.serial != self.top.echo {
            self.top.echo = self.serial;
            self.top.verb = self.cmd_verb;
            self.top.rule = 1;
            self.top.error_code = self.limit;
            match self.top.verb {
                1 => {
                    self.top.status = num::DONE;
                    self.top.state = 2;
                }
                2 => {
                    self.speed = self.move_speed;
                    self.dt = self.move_dt;
                    self.target = self.move_to;
                    self.mode = self.move_mode;
                    self.top.status = num::EXEC;
                    self.top.state = 4;
                }
                3 => {
                    self.n = self.set_n;
                    self.big = self.set_big;
                    self.top.status = num::DONE;
                    self.top.state = 2;
                }
                _ => {}
            }
        } else if self.top.state == 4 && self.top.status == num::EXEC {
            self.pose = self.target;
            self.top.status = 4;
            self.top.rule = 2;
        }
        self.ratio = if self.speed > 0.0 {
            1.0 / self.speed
        } else if self.speed < 0.0 {
            f64::NEG_INFINITY
        } else {
            f64::NAN
        };
        self.door_seen = self.door;
    }
}

impl HostDesign for Fixture {
    fn desc(&self) -> &'static DesignDesc {
        &DESIGN
    }

    fn constant(&self, index: usize) -> Value {
        match index {
            0 => Value::F64(12.5),
            1 => Value::I32(7),
            2 => Value::Duration(250_000_000),
            3 => Value::Enum(1),
            4 => Pose {
                x: 1.0,
                y: 2.0,
                mode: 1,
            }
            .value(),
            _ => Value::U32(5),
        }
    }

    fn step(&mut self, ctrl: usize, _cycle: u64) {
        if ctrl == 0 {
            self.top_step();
        } else {
            self.ticks = self.ticks.wrapping_add(1);
        }
    }

    fn command(&mut self, ctrl: usize, verb: usize, args: &[Value]) {
        if ctrl != 0 {
            return;
        }
        match args {
            [Value::F64(speed), Value::Duration(dt), Value::Enum(mode), to] => {
                self.move_speed = *speed;
                self.move_dt = *dt;
                self.move_mode = *mode;
                self.move_to = Pose::from_value(to);
            }
            [Value::U32(n), Value::I64(big)] => {
                self.set_n = *n;
                self.set_big = *big;
            }
            _ => {}
        }
        self.cmd_verb = verb + 1;
        self.serial = num::next_serial(self.serial);
    }

    fn input(&mut self, gm: usize, value: &Value) {
        match (gm, value) {
            (2, Value::Bool(b)) => self.door = *b,
            (3, Value::I32(x)) => self.limit = *x,
            (4, Value::F64(x)) => self.gain = *x,
            _ => {}
        }
    }

    fn gm_value(&self, gm: usize) -> Value {
        match gm {
            0 => self.pose.value(),
            1 => Value::Enum(self.mode),
            2 => Value::Bool(self.door),
            3 => Value::I32(self.limit),
            _ => Value::F64(self.gain),
        }
    }

    fn status(&self, ctrl: usize) -> StatusView {
        if ctrl == 0 {
            self.top.view(
                &TOP_STATES,
                &TOP_RULES,
                vec![
                    Value::F64(self.speed),
                    Value::Duration(self.dt),
                    self.target.value(),
                    Value::U32(self.n),
                    Value::I64(self.big),
                    Value::F64(self.ratio),
                    Value::Bool(self.door_seen),
                ],
            )
        } else {
            self.sub.view(
                &["", "new", "done", "error"],
                &[""],
                vec![Value::I32(self.ticks)],
            )
        }
    }
}

/// `--fmt`: the trace's text of each f64 (bits in hex) on standard input.
fn fmt_mode() -> i32 {
    let stdin = std::io::stdin();
    let mut out = std::io::BufWriter::new(std::io::stdout());
    let mut text = String::new();
    for line in stdin.lock().lines() {
        let Ok(line) = line else { return 2 };
        let Ok(bits) = u64::from_str_radix(line.trim(), 16) else {
            return 2;
        };
        text.clear();
        host::fmt_f64(&mut text, f64::from_bits(bits));
        if writeln!(out, "{text}").is_err() {
            return 2;
        }
    }
    i32::from(out.flush().is_err())
}

/// `--num`: `name args... = result` for num.rs on edge cases.
fn num_mode() {
    use std::fmt::Write as _;
    let mut out = String::new();
    let i32s = [
        i32::MIN,
        i32::MIN + 1,
        -7,
        -2,
        -1,
        0,
        1,
        2,
        7,
        i32::MAX - 1,
        i32::MAX,
    ];
    let i64s = [i64::MIN, i64::MIN + 1, -7, -2, -1, 0, 1, 2, 7, i64::MAX];
    let u32s = [0, 1, 2, 7, u32::MAX - 1, u32::MAX];
    for &a in &i32s {
        let _ = writeln!(out, "abs_i32 {a} = {}", num::abs_i32(a));
        for &b in &i32s {
            let _ = writeln!(out, "div_i32 {a} {b} = {}", num::div_i32(a, b));
            let _ = writeln!(out, "rem_i32 {a} {b} = {}", num::rem_i32(a, b));
        }
    }
    for &a in &i64s {
        let _ = writeln!(out, "abs_i64 {a} = {}", num::abs_i64(a));
        for &b in &i64s {
            let _ = writeln!(out, "div_i64 {a} {b} = {}", num::div_i64(a, b));
            let _ = writeln!(out, "rem_i64 {a} {b} = {}", num::rem_i64(a, b));
        }
    }
    for &a in &u32s {
        for &b in &u32s {
            let _ = writeln!(out, "div_u32 {a} {b} = {}", num::div_u32(a, b));
            let _ = writeln!(out, "rem_u32 {a} {b} = {}", num::rem_u32(a, b));
        }
        let _ = writeln!(out, "next_serial {a} = {}", num::next_serial(a));
    }
    let f64s = [
        f64::NAN,
        f64::NEG_INFINITY,
        -1.5,
        -0.0,
        0.0,
        5e-324,
        2.5,
        f64::INFINITY,
    ];
    for &a in &f64s {
        let _ = writeln!(
            out,
            "fabs {:016x} = {:016x}",
            a.to_bits(),
            num::fabs(a).to_bits()
        );
        for &b in &f64s {
            let (lo, hi) = (num::min_f64(a, b), num::max_f64(a, b));
            let _ = writeln!(
                out,
                "min_f64 {:016x} {:016x} = {:016x}",
                a.to_bits(),
                b.to_bits(),
                lo.to_bits()
            );
            let _ = writeln!(
                out,
                "max_f64 {:016x} {:016x} = {:016x}",
                a.to_bits(),
                b.to_bits(),
                hi.to_bits()
            );
        }
    }
    for (now, since, period) in [
        (10u64, 4u64, 10_000_000i64),
        (4, 10, 10_000_000),
        (u64::MAX, 0, 3),
        (1 << 62, 0, 1 << 20),
        (5, 5, i64::MIN),
    ] {
        let _ = writeln!(
            out,
            "cycles_ns {now} {since} {period} = {}",
            num::cycles_ns(now, since, period)
        );
    }
    let _ = writeln!(
        out,
        "statuses = {} {} {} {}",
        num::UNINITIALIZED,
        num::DONE,
        num::EXEC,
        num::ERROR
    );
    let _ = std::io::stdout().write_all(out.as_bytes());
}

fn main() {
    match std::env::args().nth(1).as_deref() {
        Some("--fmt") => std::process::exit(fmt_mode()),
        Some("--num") => num_mode(),
        _ => std::process::exit(host::run(&mut Fixture::new())),
    }
}
