//! Hammers the multi-CPU transport (host/shm.rs), as tests/c/shm_hammer.c
//! does the C one:
//!
//!   shm_hammer proc|thread free|lockstep N NAME
//!
//! CPU 0 writes samples 1..N (an odd-sized payload whose every byte is a
//! function of k), CPU 1 reads, in two processes (`proc`: the program runs
//! itself as the writer) or two threads.  `free`: the reader takes the
//! newest sample as fast as it can; every copy must be whole and k must
//! never go backwards.  `lockstep`: the reader, released at 1..N, must get
//! exactly each k with nothing missing.  Prints `ok READS`.

#[path = "../host/mod.rs"]
mod host;

use host::shm::{Shm, ShmCpu, FINISHED};
use std::process::{exit, Command};
use std::time::Duration;

const PAYLOAD: usize = 301;
static CPUS: [ShmCpu; 2] = [
    ShmCpu {
        period_ns: 1,
        payload_size: PAYLOAD,
        readers: 2,
    },
    ShmCpu {
        period_ns: 1,
        payload_size: 0,
        readers: 0,
    },
];

fn expected(k: u64, j: usize) -> u8 {
    (k.wrapping_mul(131).wrapping_add(j as u64 * 7) & 0xff) as u8
}

fn never() -> bool {
    false
}

fn open(name: &str, me: usize) -> Shm {
    let shm = Shm::open(name, &CPUS, me).unwrap_or_else(|e| {
        eprintln!("{e}");
        exit(1)
    });
    if shm
        .start(Duration::ZERO, Duration::from_secs(10), &never)
        .is_none()
    {
        eprintln!("no start");
        exit(1);
    }
    shm
}

fn writer(name: &str, lockstep: bool, n: u64) -> i32 {
    let shm = open(name, 0);
    let mut p = [0u8; PAYLOAD];
    for k in 1..=n {
        for (j, b) in p.iter_mut().enumerate() {
            *b = expected(k, j);
        }
        if lockstep && shm.wait_readers(k, &never).is_err() {
            eprintln!("writer: the reader went away at {k}");
            return 1;
        }
        shm.publish(k, &p);
    }
    shm.set_state(FINISHED);
    shm.unlink();
    0
}

fn check(p: &[u8], k: u64) -> bool {
    for (j, b) in p.iter().enumerate() {
        if *b != expected(k, j) {
            eprintln!("torn: sample {k} byte {j} is {b}");
            return false;
        }
    }
    true
}

fn reader(name: &str, lockstep: bool, n: u64) -> i32 {
    let mut shm = open(name, 1);
    let mut p = [0u8; PAYLOAD];
    let (mut have, mut reads) = (0u64, 0u64);
    if lockstep {
        for t in 1..=n {
            if shm.wait_published(0, t as i64, &never).is_err() {
                return 1;
            }
            let (k, missing) = shm.fetch(0, t as i64, have, &mut p);
            if k != t || missing || !check(&p, k) {
                eprintln!("lockstep: release {t} got {k} (missing {missing})");
                return 1;
            }
            have = k;
            reads += 1;
            shm.next_release(t as i64 + 1);
        }
    } else {
        while have < n {
            let (k, _) = shm.fetch(0, i64::MAX, have, &mut p);
            if k < have {
                eprintln!("out of order: {k} after {have}");
                return 1;
            }
            if k > have {
                if !check(&p, k) {
                    return 1;
                }
                have = k;
                reads += 1;
            }
        }
    }
    shm.set_state(FINISHED);
    shm.unlink();
    println!("ok {reads}");
    0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: shm_hammer proc|thread|writer free|lockstep N NAME");
        exit(2);
    }
    let lockstep = args[2] == "lockstep";
    let n: u64 = args[3].parse().unwrap_or(0);
    let name = args[4].clone();
    let status = match args[1].as_str() {
        "writer" => writer(&name, lockstep, n),
        "thread" => {
            let wname = name.clone();
            let w = std::thread::spawn(move || writer(&wname, lockstep, n));
            let r = reader(&name, lockstep, n);
            let w = w.join().unwrap_or(1);
            i32::from(r != 0 || w != 0)
        }
        _ => {
            let mut child = Command::new(&args[0])
                .args(["writer", &args[2], &args[3], &name])
                .spawn()
                .unwrap_or_else(|_| exit(1));
            let r = reader(&name, lockstep, n);
            let w = child.wait().map(|s| s.success()).unwrap_or(false);
            i32::from(r != 0 || !w)
        }
    };
    exit(status)
}
