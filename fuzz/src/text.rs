//! The text readers: MovingAI `.map` and `.scen`, and scenario TOML.

use std::path::Path;
use std::sync::OnceLock;

use hnav_runtime::grid::{read_map, read_scen, validate_scen, write_map, write_scen, Grid};
use hnav_runtime::scenario::Scenario;

use crate::{Outcome, SOURCE};

/// Text targets see bytes; a reader takes `&str`, so what is not UTF-8 is its own class.
fn utf8(data: &[u8]) -> Result<&str, Outcome> {
    std::str::from_utf8(data).map_err(|_| Outcome::class("not-utf8"))
}

/// An error must name the input it is about and must not be a debug dump.
fn check_message(message: &str) {
    assert!(
        message.contains(SOURCE),
        "error does not name its source: {message}"
    );
    crate::check_not_debug(message);
}

/// `read_map`; an accepted map is written and read back to the same grid.
pub(crate) fn map(data: &[u8]) -> Outcome {
    let text = match utf8(data) {
        Ok(t) => t,
        Err(o) => return o,
    };
    match read_map(text, SOURCE) {
        Ok(grid) => {
            let written = write_map(&grid);
            let again = read_map(&written, SOURCE)
                .unwrap_or_else(|e| panic!("a written map does not read back: {e}"));
            assert_eq!(again, grid, "map round trip changed the grid");
            Outcome::ok()
        }
        Err(e) => {
            check_message(&e.to_string());
            assert_eq!(e.source_name(), Some(SOURCE));
            Outcome::of_error("", &e)
        }
    }
}

/// The map `.scen` entries are validated against (committed beside the scen corpus).
fn scen_grid() -> &'static Grid {
    static GRID: OnceLock<Grid> = OnceLock::new();
    GRID.get_or_init(|| {
        read_map(
            include_str!("../../maps/random-32-32-10.map"),
            "random-32-32-10.map",
        )
        .expect("the committed map reads")
    })
}

/// `read_scen`, then `validate_scen`; an accepted file's written form is a fixed point.
pub(crate) fn scen(data: &[u8]) -> Outcome {
    let text = match utf8(data) {
        Ok(t) => t,
        Err(o) => return o,
    };
    match read_scen(text, SOURCE) {
        Ok(scen) => {
            let written = write_scen(&scen);
            let again = read_scen(&written, SOURCE)
                .unwrap_or_else(|e| panic!("a written scen does not read back: {e}"));
            assert_eq!(write_scen(&again), written, "scen round trip changed it");
            let problems = validate_scen(scen_grid(), &scen);
            for p in &problems {
                check_message(&p.to_string());
            }
            match problems.first() {
                Some(p) => Outcome::of_error("valid:", p),
                None => Outcome::ok(),
            }
        }
        Err(e) => {
            check_message(&e.to_string());
            assert_eq!(e.source_name(), Some(SOURCE));
            Outcome::of_error("", &e)
        }
    }
}

/// `Scenario::from_str` (a map `file` resolves against the committed `scenarios/`); an
/// accepted scenario passes its own re-validation and hashes the same twice.
pub(crate) fn scenario(data: &[u8]) -> Outcome {
    let text = match utf8(data) {
        Ok(t) => t,
        Err(o) => return o,
    };
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    match Scenario::from_str(text, SOURCE, &base) {
        Ok(s) => {
            if let Err(e) = s.validate() {
                panic!("an accepted scenario fails its re-validation: {e}");
            }
            assert_eq!(s.scenario_hash(), s.scenario_hash());
            Outcome::ok()
        }
        Err(e) => {
            check_message(&e.to_string());
            Outcome::of_error("", &e)
        }
    }
}
