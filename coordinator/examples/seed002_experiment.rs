//! Seed 002's §4 experiment beside the thesis's Table 3.1.
//!
//! ```text
//! cargo run --release -p hnav-coordinator --example seed002_experiment [-- --trials 100 --seed 2 --repeats 3]
//! ```

use hnav_coordinator::experiment::seed002::{run, Seed002Config};

fn arg<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::args()
        .skip_while(|a| a != name)
        .nth(1)
        .and_then(|v| v.parse().ok())
}

fn main() {
    let mut config = Seed002Config::default();
    if let Some(t) = arg("--trials") {
        config.trials = t;
    }
    if let Some(s) = arg("--seed") {
        config.seed = s;
    }
    config.timing_repeats = arg("--repeats").unwrap_or(3);
    match run(&config) {
        Ok(report) => print!("{}", report.render()),
        Err(e) => {
            eprintln!("seed002_experiment: {e}");
            std::process::exit(2);
        }
    }
}
