//! The controller library of the runtime test fixture: as a generated
//! crate's, `no_std` and without `unsafe`; here it holds only `num`.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used)]

pub mod num;
