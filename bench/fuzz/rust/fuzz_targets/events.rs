//! libFuzzer (cargo-fuzz) target for the Rust event reader, `Scenario::parse`,
//! against the fixture design of tests/rust_fixture (the twin of
//! bench/fuzz/events_fuzz.c).  The oracle, besides "no panic, no overflow"
//! (overflow checks are on): a refusal names a line of the file (1 to the
//! line count + 1) and is one line of printable ASCII; an accepted file has
//! 1..2^32-1 cycles; two readings agree.  Whether the C reader agrees is the
//! replay step's job (bench/fuzz_events.py).  With RCSC_FUZZ_PLANT_BUG set
//! (`fuzz_events.py --plant-bug`) the oracle also rejects the refusal of a
//! malformed version number, as the C harness does: a planted finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

// The fixture's tables; fuzz_events.py makes `DESIGN` and `host` public in its copy.
#[allow(dead_code)]
#[path = "../../src/bin/fixture.rs"]
mod fixture_bin;

use fixture_bin::host::Scenario;

static PLANT_BUG: std::sync::OnceLock<bool> = std::sync::OnceLock::new();

fn outcome(data: &[u8]) -> Result<u64, (usize, String)> {
    Scenario::parse(data, &fixture_bin::DESIGN)
        .map(|s| s.cycles())
        .map_err(|e| (e.line, e.message))
}

fuzz_target!(|data: &[u8]| {
    let first = outcome(data);
    assert_eq!(
        first,
        outcome(data),
        "two readings of the same bytes differ"
    );
    match first {
        Ok(cycles) => assert!(
            (1..=u64::from(u32::MAX)).contains(&cycles),
            "cycles {cycles}"
        ),
        Err((line, message)) => {
            let lines = 1 + data.iter().filter(|&&b| b == b'\n').count();
            assert!(
                (1..=lines).contains(&line),
                "line {line} of {lines}: {message}"
            );
            assert!(
                message.bytes().all(|b| (0x20..=0x7e).contains(&b)),
                "{message:?}"
            );
            let planted =
                *PLANT_BUG.get_or_init(|| std::env::var_os("RCSC_FUZZ_PLANT_BUG").is_some());
            assert!(
                !(planted && line == 1 && message.ends_with("is not a decimal number")),
                "FINDING: planted: a malformed version number"
            );
        }
    }
});
