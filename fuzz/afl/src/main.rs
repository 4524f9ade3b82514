//! `hnav-fuzz-afl TARGET`: AFL++'s persistent-mode loop over one `hnav-fuzz` target. A failed
//! check panics, and AFL's panic hook turns the panic into the abort AFL++ records as a crash.

use hnav_fuzz::{Harness, Target};

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    let Some(target) = Target::from_name(&name) else {
        let names: Vec<&str> = Target::ALL.iter().map(|t| t.name()).collect();
        eprintln!(
            "usage: hnav-fuzz-afl TARGET (one of: {}), got {name:?}",
            names.join(", ")
        );
        std::process::exit(2);
    };
    let harness = match Harness::new() {
        Ok(h) => h,
        Err(e) => {
            eprintln!("hnav-fuzz-afl: cannot create a temporary directory: {e}");
            std::process::exit(2);
        }
    };
    afl::fuzz(true, |data: &[u8]| {
        harness.run(target, data);
    });
}
