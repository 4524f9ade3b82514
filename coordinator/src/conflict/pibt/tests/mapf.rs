//! The MAPF benchmark instances (MovingAI maps and `.scen` files in `maps/`) in the
//! discrete-time [`World`]: the fast model of `hnav-bench mapf`, without processes.

use std::path::PathBuf;

use hnav_runtime::grid::{read_map_file, read_scen_file, Cell};

use super::World;

fn maps_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../maps")
}

/// The rounds of a run of the model.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Rounds {
    Pibt,
    /// PIBT with the swap operation.
    PibtSwap,
    Lacam,
}

/// Runs the first `n` entries of `scen` on `map` for at most `limit` rounds; the rounds until
/// all were home at once, or the agents away at the end.
pub(crate) fn run(
    map: &str,
    scen: &str,
    n: usize,
    limit: u64,
    rounds: Rounds,
) -> Result<u64, Vec<usize>> {
    let grid = read_map_file(maps_dir().join(map)).unwrap();
    let scen = read_scen_file(maps_dir().join(scen)).unwrap();
    let (starts, goals): (Vec<Cell>, Vec<Cell>) =
        scen.entries[..n].iter().map(|e| (e.start, e.goal)).unzip();
    let mut w = match rounds {
        Rounds::Lacam => World::with_lacam(grid, &starts, &goals),
        _ => World::new(grid, &starts, &goals),
    };
    w.pibt.set_swap(rounds == Rounds::PibtSwap);
    let r = w.run(limit);
    if let Some(l) = &w.lacam {
        eprintln!("  {:?}", l.stats());
    }
    r.map_err(|_| {
        (0..n)
            .filter(|&i| w.rows[i].current != w.goals[i] || !w.rows[i].is_at_rest())
            .collect()
    })
}

/// Prints the table of the three benchmark maps: PIBT without and with the swap operation,
/// and LaCAM
/// (`cargo test -p hnav-coordinator --lib mapf_table -- --ignored --nocapture`).
#[test]
#[ignore = "a measurement: prints the sim-only table"]
fn mapf_table() {
    let sets = [
        ("random-32-32-10.map", "random-32-32-10-random-1.scen", 250),
        ("random-32-32-20.map", "random-32-32-20-random-1.scen", 200),
        (
            "warehouse-10-20-10-2-1.map",
            "warehouse-10-20-10-2-1-random-1.scen",
            200,
        ),
    ];
    for (map, scen, max) in sets {
        for n in [50, 100, 150, 200, 250].into_iter().filter(|&n| n <= max) {
            for rounds in [Rounds::Pibt, Rounds::PibtSwap, Rounds::Lacam] {
                let label = format!("{rounds:?}");
                match run(map, scen, n, 20_000, rounds) {
                    Ok(r) => eprintln!("{map} N={n} {label}: all home at round {r}"),
                    Err(away) => eprintln!("{map} N={n} {label}: {} away: {away:?}", away.len()),
                }
            }
        }
    }
}
