//! driver.rs: the generated Rust PR running its AHEAD plan, for bench/bench_rust_step.py.
//!
//!     driver_rust [STEPS [trace]]        (default 10000)
//!
//! A faithful port of bench/c_ahead/driver.c's plant, TB model and command
//! sequence (a new AHEAD command every 1000 cycles, the ship astern before
//! the 5th, a turbine trip at cycle 7800), stepping only the generated Rust
//! controller through `bench_rust_pr_step` (never inlined, unmangled:
//! callgrind's --toggle-collect target).  The twin of driver_c.c: same rule
//! mix, same FNV-1a digest of what PR wrote after every step (its status
//! head, tb_fault, and TB's command head and rpm), same `trace` lines; the
//! script requires the two outputs to be identical.
//!
//! The script builds it in a Cargo crate of its own with a path dependency
//! on the generated library crate (release: opt-level 3, overflow checks
//! on as in the generated Cargo.toml, debug info for callgrind_annotate).

use submarine::ctrl_PR::PR;
use submarine::num;
use submarine::types::*;

const CMD_EVERY: u64 = 1000;
const BACK_CMD: u32 = 4; // index of the command given while going astern
const TRIP_CYCLE: u64 = 7800; // the turbine trips in this cycle

const GOALS: [f64; 10] = [10.0, 14.0, 8.0, 16.0, 5.0, 12.0, 9.0, 18.0, 6.0, 11.0];

const W_NEW: usize = 0;
const W_E0: usize = 1;
const W_E1: usize = 2;
const W_E2: usize = 3;
const W_E3: usize = 4;
const W_E4: usize = 5;
const W_E5: usize = 6;
const W_E9: usize = 7;
const W_WAIT_TB: usize = 8;
const W_WAIT_CLOSING: usize = 9;
const W_IDLE: usize = 10;
const WHAT_NAMES: [&str; 11] = [
    "new", "E0", "E1", "E2", "E3", "E4", "E5", "E9", "wait_tb", "wait_closing", "idle",
];

/// The measured call: one step of the generated controller.
#[no_mangle]
#[inline(never)]
pub fn bench_rust_pr_step(pr: &mut PR, buf: &mut Buffers, cycle: u64) {
    pr.step(buf, cycle);
}

fn mix(mut h: u64, x: u64) -> u64 {
    for i in 0..8 {
        h ^= (x >> (8 * i)) & 0xff;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

fn fabs_(x: f64) -> f64 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let steps: u64 = args.get(1).map_or(10000, |s| s.parse().expect("STEPS: a number"));
    let trace = args.get(2).map(String::as_str) == Some("trace");
    let mut ship_speed = 0.0f64;
    let mut shaft_rpm = 0.0f64;
    let mut rpm_goal = 0.0f64;
    let mut tb_echo: u32 = 0;
    let mut tb_status: i32 = num::UNINITIALIZED;
    let mut tb_verb: i32 = 0;
    let mut tb_error: i32 = 0;
    let mut tripped: bool;
    let mut pr_serial: u32 = 0;
    let mut n_cmd: u32 = 0;
    let mut digest: u64 = 0xcbf29ce484222325;
    let mut counts = [0u64; 11];

    let mut buf = Buffers::new();
    let mut pr = PR::new();

    for cycle in 1..=steps {
        let sea = if (cycle / 150) % 2 == 0 { 0.001 } else { -0.001 };
        let mut new_cmd = false;
        ship_speed += (0.01 * shaft_rpm * fabs_(shaft_rpm) - ship_speed * fabs_(ship_speed)) / 60.0 * 0.03 + sea;
        if n_cmd == BACK_CMD && cycle % CMD_EVERY == 0 {
            ship_speed = -1.5;
            shaft_rpm = -20.0;
        }
        let ship_dir = if ship_speed > 0.1 {
            ShipDir::AHEAD
        } else if ship_speed < -0.1 {
            ShipDir::BACK
        } else {
            ShipDir::STOPPED
        };
        buf.gm.ship_speed = ship_speed;
        buf.gm.ship_dir = ship_dir;

        if cycle % CMD_EVERY == 1 {
            pr_serial = num::next_serial(pr_serial);
            buf.PR__cmd.head.serial = pr_serial;
            buf.PR__cmd.head.verb = PR__VERB__AHEAD;
            buf.PR__cmd.args.AHEAD.speed = GOALS[n_cmd as usize % GOALS.len()];
            n_cmd += 1;
            new_cmd = true;
        }

        let sent_before = buf.TB__cmd.head.serial;
        let state_before = buf.PR__status.head.state;
        bench_rust_pr_step(&mut pr, &mut buf, cycle);

        {
            let s = &buf.PR__status.head;
            let w: [u64; 11] = [
                s.echo_serial as u64,
                s.status as u32 as u64,
                s.verb as u32 as u64,
                s.state as u32 as u64,
                s.rule as u32 as u64,
                s.error_code as u32 as u64,
                s.stamp,
                buf.PR__status.f.tb_fault as u32 as u64,
                buf.TB__cmd.head.serial as u64,
                buf.TB__cmd.head.verb as u32 as u64,
                buf.TB__cmd.args.AHEAD.rpm.to_bits(),
            ];
            for x in w {
                digest = mix(digest, x);
            }
            if trace {
                println!(
                    "{} {} {} {} {} {} {} {} {} {} {} {:016x}",
                    cycle,
                    s.echo_serial,
                    s.status,
                    s.verb,
                    s.state,
                    s.rule,
                    s.error_code,
                    s.stamp,
                    buf.PR__status.f.tb_fault,
                    buf.TB__cmd.head.serial,
                    buf.TB__cmd.head.verb,
                    buf.TB__cmd.args.AHEAD.rpm.to_bits()
                );
            }
        }

        let goal = buf.PR__cmd.args.AHEAD.speed;
        if new_cmd {
            counts[W_NEW] += 1;
            counts[if buf.PR__status.head.rule == 10 { W_E0 } else { W_E1 }] += 1;
        } else if state_before != 4 && state_before != 5 {
            counts[W_IDLE] += 1;
        } else if buf.TB__cmd.head.serial != sent_before {
            let r = buf.PR__status.head.rule;
            counts[if r == 13 {
                W_E2
            } else if r == 15 {
                W_E4
            } else {
                W_E5
            }] += 1;
        } else if buf.PR__status.head.state == 3 {
            counts[W_E9] += 1;
        } else if !(sent_before != 0 && tb_echo == sent_before && tb_status == num::DONE) {
            counts[W_WAIT_TB] += 1;
        } else if fabs_(ship_speed - goal) <= 0.25 {
            counts[W_E3] += 1;
        } else {
            counts[W_WAIT_CLOSING] += 1;
        }

        if buf.TB__cmd.head.serial != tb_echo {
            tb_echo = buf.TB__cmd.head.serial;
            tb_verb = buf.TB__cmd.head.verb;
            rpm_goal = if tb_verb == TB__VERB__AHEAD { buf.TB__cmd.args.AHEAD.rpm } else { 0.0 };
            tb_status = num::EXEC;
            tb_error = 0;
        }
        tripped = cycle == TRIP_CYCLE;
        if tripped {
            rpm_goal = 0.0;
            if tb_status == num::EXEC || tb_status == num::DONE {
                tb_status = num::ERROR;
                tb_error = ERR_TRIP;
            }
        }
        shaft_rpm += if rpm_goal - shaft_rpm > 0.6 {
            0.6
        } else if rpm_goal - shaft_rpm < -0.6 {
            -0.6
        } else {
            rpm_goal - shaft_rpm
        };
        if tb_status == num::EXEC && fabs_(shaft_rpm - rpm_goal) <= 1.0 {
            tb_status = num::DONE;
        }
        buf.TB__status.head.echo_serial = tb_echo;
        buf.TB__status.head.status = tb_status;
        buf.TB__status.head.verb = tb_verb;
        buf.TB__status.head.error_code = tb_error;
        buf.TB__status.head.stamp = cycle;
        buf.TB__status.f.shaft_rpm = shaft_rpm;
        buf.TB__status.f.tripped = tripped;
    }

    println!("steps {}", steps);
    for (name, n) in WHAT_NAMES.iter().zip(counts.iter()) {
        println!("count {} {}", name, n);
    }
    let s = &buf.PR__status.head;
    println!(
        "final PR status: echo {} status {} verb {} state {} rule {} err {} stamp {} tb_fault {}",
        s.echo_serial, s.status, s.verb, s.state, s.rule, s.error_code, s.stamp, buf.PR__status.f.tb_fault
    );
    println!(
        "final TB cmd: serial {} verb {} rpm {:016x}",
        buf.TB__cmd.head.serial,
        buf.TB__cmd.head.verb,
        buf.TB__cmd.args.AHEAD.rpm.to_bits()
    );
    println!("digest {:016x}", digest);
}
