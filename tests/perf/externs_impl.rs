//! The extern functions of design perf (tests/test_perfstat.py): spin
//! busy-waits n iterations and returns 0, as the simulator's stub does.
//!
//! Written once by rcsc as a starting point; this file is yours. rcsc never
//! overwrites it (delete it to get a fresh stub).  Each stub returns the
//! zero value of its type, as the reference simulator does, so traces of the
//! compiled program and of `rcsc sim` agree until you fill these in.  This
//! file is part of the no_std library: no heap, no I/O, bounded time.

use crate::Externs;

/// Your implementation of the extern functions (add state as fields).
#[derive(Debug, Default)]
pub struct ExternsImpl {}

impl Externs for ExternsImpl {
    // perf.rcs:7, budget 1 us
    fn spin(&self, n: i32) -> i32 {
        let mut k = 0_i32;
        for _ in 0..n {
            k = core::hint::black_box(k.wrapping_add(1));
        }
        let _ = k;
        0_i32
    }
}
