//! The extern functions of callorder.rcs in Rust: the journal of callorder_impl.py.

use crate::Externs;
use crate::num;
use crate::types::*;
use core::cell::Cell;

#[derive(Debug, Default)]
pub struct ExternsImpl {
    s: Cell<i64>,
}

impl ExternsImpl {
    fn mix(&self, v: i64) -> i64 {
        self.s.set((self.s.get() * 31 + v) % 1000003);
        self.s.get()
    }
}

impl Externs for ExternsImpl {
    fn t_i32(&self, k: i32) -> i32 {
        self.mix(i64::from(k)) as i32
    }

    fn t_f64(&self, x: f64, k: i32) -> f64 {
        x + self.mix(i64::from(k)) as f64
    }

    fn t_bool(&self, k: i32) -> bool {
        self.mix(i64::from(k)) % 2 == 1
    }

    fn t_mode(&self, m: Mode, k: i32) -> Mode {
        match self.mix(i64::from(k) * 4 + m as i64) % 3 {
            0 => Mode::A,
            1 => Mode::B,
            _ => Mode::C,
        }
    }

    fn t_pt(&self, p: Pt, k: i32) -> Pt {
        let v = self.mix(i64::from(k) * 7 + i64::from(p.a & 1023));
        Pt { a: (v % 100) as i32, b: p.b + 1.0 }
    }

    fn t_dur(&self, d: i64, k: i32) -> i64 {
        d + self.mix(i64::from(k)) * 1_000_000
    }

    fn t_u32(&self, u: u32, k: i32) -> u32 {
        u.wrapping_add(self.mix(i64::from(k)) as u32)
    }

    fn t_i64(&self, v: i64, k: i32) -> i64 {
        self.mix(i64::from(k)) * 1024 + (v & 1023)
    }

    fn t_arr(&self, xs: num::Arr<i32, 3>, k: i32) -> i32 {
        self.mix(i64::from(k));
        for x in xs.0 {
            self.mix(i64::from(x & 1023));
        }
        self.s.get() as i32
    }

    fn pair(&self, a: i32, b: i32) -> i32 {
        self.mix(i64::from(a & 1023));
        self.mix(i64::from(b & 1023)) as i32
    }

    fn peek(&self) -> i32 {
        self.s.get() as i32
    }
}
