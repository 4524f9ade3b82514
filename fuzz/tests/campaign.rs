//! The CI-sized fuzz campaign: every target replays its committed corpus (valid and
//! near-valid inputs and every minimised input that once crashed it), then a bounded number
//! of seeded mutations of it, so that a crash found once stays found. The long,
//! coverage-guided campaign is AFL++'s (`fuzz/run.sh TARGET SECONDS`).
//!
//! `HNAV_FUZZ_EXECS` (mutations per target, default 3000), `HNAV_FUZZ_SECONDS` (time cap per
//! target, default 5) and `HNAV_FUZZ_SEED` (default 12) size and vary the run. An input that
//! fails is written to `target/tmp/fuzz-crashes/` and named in the failure.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use hnav_fuzz::{corpus_files, Harness, Mutator, Outcome, Target};

fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn run_one(harness: &Harness, target: Target, data: &[u8]) -> Result<Outcome, String> {
    catch_unwind(AssertUnwindSafe(|| harness.run(target, data))).map_err(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "panic".into());
        // A failed assert_eq! can print a whole Commit; the saved input says the rest.
        message.chars().take(400).collect()
    })
}

fn save_crash(target: Target, n: usize, data: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-crashes");
    std::fs::create_dir_all(&dir).expect("creates the crash directory");
    let path = dir.join(format!("{}-{n}", target.name()));
    std::fs::write(&path, data).expect("writes the crashing input");
    path
}

#[test]
fn every_target_survives_its_corpus_and_seeded_mutations() {
    let execs = env_number("HNAV_FUZZ_EXECS", 3000) as usize;
    let cap = Duration::from_secs(env_number("HNAV_FUZZ_SECONDS", 5));
    let seed = env_number("HNAV_FUZZ_SEED", 12);
    let harness = Harness::new().expect("creates the harness directory");
    let mut failures = Vec::new();
    println!("target     corpus  mutations  classes");
    for (t, target) in Target::ALL.into_iter().enumerate() {
        let files = corpus_files(&target.corpus_dir()).expect("reads the corpus directory");
        assert!(!files.is_empty(), "{} has no corpus", target.name());
        let corpus: Vec<Vec<u8>> = files
            .iter()
            .map(|f| std::fs::read(f).expect("reads a corpus file"))
            .collect();
        let mut classes: BTreeMap<Outcome, u64> = BTreeMap::new();
        for (file, data) in files.iter().zip(&corpus) {
            match run_one(&harness, target, data) {
                Ok(o) => *classes.entry(o).or_default() += 1,
                Err(e) => failures.push(format!("{} {}: {e}", target.name(), file.display())),
            }
        }
        assert!(
            classes.keys().any(|o| o.as_str().starts_with("ok")),
            "{}'s corpus has no accepted input, so its round trip is never checked",
            target.name()
        );
        let mut mutator =
            Mutator::new(corpus.clone(), seed.wrapping_mul(31).wrapping_add(t as u64));
        let start = Instant::now();
        let mut done = 0;
        let failed_before = failures.len();
        // One bug fails most mutations; a few saved inputs are enough to find it.
        while done < execs && start.elapsed() < cap && failures.len() < failed_before + 10 {
            let input = mutator.next_input();
            match run_one(&harness, target, &input) {
                Ok(o) => *classes.entry(o).or_default() += 1,
                Err(e) => {
                    let path = save_crash(target, failures.len(), &input);
                    failures.push(format!(
                        "{} mutation {done} ({}): {e}",
                        target.name(),
                        path.display()
                    ));
                }
            }
            done += 1;
        }
        let names: Vec<&str> = classes.keys().map(Outcome::as_str).collect();
        println!(
            "{:<9} {:>7} {:>10} {:>8}  {}",
            target.name(),
            files.len(),
            done,
            classes.len(),
            names.join(" ")
        );
    }
    assert!(
        failures.is_empty(),
        "{} fuzz failures, the first ones:\n{}",
        failures.len(),
        failures[..failures.len().min(5)].join("\n")
    );
}
