//! One MAPF instance: the first N entries of a MovingAI `.scen` on its map (Stern et al.
//! 2019), and the scenario file that runs it.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use hnav_runtime::grid::{read_map_file, read_scen_file, validate_scen, Cell, Grid, ScenEntry};

/// Why an instance cannot be built; every message names the files and lines involved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InstanceError {
    /// The map or the `.scen` could not be read or does not fit the map.
    #[error("{0}")]
    Grid(#[from] hnav_runtime::grid::GridError),
    /// More agents asked for than the `.scen` has entries.
    #[error("{scen}: {agents} agents asked for, but the file has only {entries} entries")]
    TooFewEntries {
        /// The `.scen` file.
        scen: String,
        /// Agents asked for.
        agents: usize,
        /// Entries in the file.
        entries: usize,
    },
    /// Two of the first N entries start (or end) on one cell: no MAPF instance, since two
    /// robots cannot stand on one cell.
    #[error("{scen}:{line}: {endpoint} {cell} is also the {endpoint} of line {first}; the first {agents} entries are no MAPF instance")]
    SharedCell {
        /// The `.scen` file.
        scen: String,
        /// The later line.
        line: usize,
        /// The line that has the cell first.
        first: usize,
        /// `start` or `goal`.
        endpoint: &'static str,
        /// The cell, `[x, y]`.
        cell: String,
        /// The instance size.
        agents: usize,
    },
}

/// A `.scen` loaded against its map, from which instances of any size are taken.
#[derive(Debug, Clone)]
pub struct Benchmark {
    /// The map file, absolute, as the scenario files name it (they run in another
    /// directory).
    pub map: PathBuf,
    /// The map file as given, for reports (like [`Benchmark::scen`]).
    pub map_given: String,
    /// The map.
    pub grid: Grid,
    /// The `.scen` file as given.
    pub scen: String,
    /// Its entries, in file order.
    pub entries: Vec<ScenEntry>,
}

impl Benchmark {
    /// Reads `map` and `scen` and validates every entry against the map.
    pub fn load(map: &Path, scen: &Path) -> Result<Benchmark, InstanceError> {
        let grid = read_map_file(map)?;
        let file = read_scen_file(scen)?;
        if let Some(e) = validate_scen(&grid, &file).into_iter().next() {
            return Err(e.into());
        }
        let map_given = map.display().to_string();
        let map = std::fs::canonicalize(map).unwrap_or_else(|_| map.to_path_buf());
        Ok(Benchmark {
            map,
            map_given,
            grid,
            scen: file.source_name,
            entries: file.entries,
        })
    }

    /// The instance of the first `agents` entries. Shared starts or goals among them are
    /// an error naming both lines.
    pub fn instance(&self, agents: usize) -> Result<Instance<'_>, InstanceError> {
        let entries = self
            .entries
            .get(..agents)
            .ok_or_else(|| InstanceError::TooFewEntries {
                scen: self.scen.clone(),
                agents,
                entries: self.entries.len(),
            })?;
        for (endpoint, of) in [
            ("start", (|e: &ScenEntry| e.start) as fn(&ScenEntry) -> Cell),
            ("goal", |e: &ScenEntry| e.goal),
        ] {
            let mut first: HashMap<Cell, usize> = HashMap::with_capacity(agents);
            for e in entries {
                if let Some(&line) = first.get(&of(e)) {
                    return Err(InstanceError::SharedCell {
                        scen: self.scen.clone(),
                        line: e.line,
                        first: line,
                        endpoint,
                        cell: of(e).to_string(),
                        agents,
                    });
                }
                first.insert(of(e), e.line);
            }
        }
        Ok(Instance {
            benchmark: self,
            entries,
        })
    }
}

/// The first N entries of a [`Benchmark`].
#[derive(Debug, Clone, Copy)]
pub struct Instance<'a> {
    /// Where the entries come from.
    pub benchmark: &'a Benchmark,
    /// The entries, agent `i` being entry `i`.
    pub entries: &'a [ScenEntry],
}

/// How an instance is run, beside its agents.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// `lockstep` or `realtime`.
    pub mode: String,
    /// The coordinator's rules (`dissertation`, `pibt`, `lacam`); `None` writes no `rules` key, for a
    /// runtime that has only the dissertation's rules.
    pub rules: Option<String>,
    /// `[coordinator] time_limit_s`: simulated seconds in lockstep.
    pub time_limit_s: f64,
    /// `[run] agents_per_process`: robots hosted by one agent process.
    pub agents_per_process: u32,
    /// `[sim] odometry_hz`, the control rate (one lockstep round a period); `None` leaves
    /// the scenario's default, 100.
    pub odometry_hz: Option<u32>,
}

/// Hang deadline of every process in a benchmark run (ms). Hundreds of processes share the
/// cores, and a false hang would kill a healthy process and write its death into the log:
/// the benchmark measures the rules, not hang detection.
pub const HANG_MS: u32 = 30_000;

/// `[run] startup_timeout_s` of a benchmark run of `agents`: 60 s plus 2 s an agent. The
/// default (60 s plus the neural-map builds, a few ms on these maps) was too short for 200
/// debug-build processes opening their ports on two loaded cores; every process of a run
/// waits for the supervisor's `Start`, so a slow start costs nothing but its own time.
pub fn startup_timeout_s(agents: usize) -> f64 {
    60.0 + 2.0 * agents as f64
}

impl Instance<'_> {
    /// Agents in it.
    pub fn agents(&self) -> usize {
        self.entries.len()
    }

    /// The `.scen`'s lower bound: the sum of the entries' optimal lengths.
    pub fn optimal_sum(&self) -> f64 {
        self.entries.iter().map(|e| e.optimal_length).sum()
    }

    /// The longest optimal length among the entries.
    pub fn longest(&self) -> f64 {
        self.entries
            .iter()
            .map(|e| e.optimal_length)
            .fold(0.0, f64::max)
    }

    /// The scenario file that runs it: the map without corner cutting (the rule of the
    /// `.scen`'s optimal lengths), every agent at the default speed, the log synced in
    /// batches (the runs are not killed, and the shared disk is spared an fdatasync a round).
    pub fn scenario_toml(&self, settings: &RunSettings) -> String {
        let stem = self
            .benchmark
            .map
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "map".into());
        let mut out = String::new();
        let _ = writeln!(
            out,
            "# {} agents: the first {} entries of {}",
            self.agents(),
            self.agents(),
            self.benchmark.scen
        );
        let _ = writeln!(out, "name = \"mapf-{stem}-{}\"\n", self.agents());
        let _ = writeln!(
            out,
            "[map]\nfile = {:?}\ncorner_cutting = false\n",
            self.benchmark.map.display().to_string()
        );
        let _ = writeln!(out, "[sim]\nclock = {:?}\nseed = 1", settings.mode);
        if let Some(hz) = settings.odometry_hz {
            let _ = writeln!(out, "odometry_hz = {hz}");
        }
        out.push('\n');
        let _ = writeln!(
            out,
            "[coordinator]\nfsync = \"batched\"\ntime_limit_s = {:?}",
            settings.time_limit_s
        );
        if let Some(rules) = &settings.rules {
            let _ = writeln!(out, "rules = {rules:?}");
        }
        let _ = writeln!(
            out,
            "\n[run]\nstartup_timeout_s = {:?}\nagents_per_process = {}",
            startup_timeout_s(self.agents()),
            settings.agents_per_process
        );
        let _ = writeln!(
            out,
            "\n[health]\nagent_hang_ms = {HANG_MS}\ncoordinator_hang_ms = {HANG_MS}\nsim_hang_ms = {HANG_MS}"
        );
        for e in self.entries {
            let _ = writeln!(
                out,
                "\n[[agents]]   # line {}, optimal {}\nstart = [{}, {}]\ngoal = [{}, {}]",
                e.line,
                e.optimal_length_text(),
                e.start.x,
                e.start.y,
                e.goal.x,
                e.goal.y
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hnav_runtime::scenario::Scenario;

    fn files(dir: &Path, scen: &str) -> (PathBuf, PathBuf) {
        let map = dir.join("m.map");
        let path = dir.join("m.scen");
        std::fs::write(&map, "type octile\nheight 2\nwidth 4\nmap\n....\n.@..\n").unwrap();
        std::fs::write(&path, scen).unwrap();
        (map, path)
    }

    const SCEN: &str =
        "version 1\n0\tm.map\t4\t2\t0\t0\t3\t0\t3\n0\tm.map\t4\t2\t3\t1\t0\t1\t3.41421356\n\
                        0\tm.map\t4\t2\t2\t1\t3\t0\t1.41421356\n0\tm.map\t4\t2\t1\t0\t0\t1\t2\n";

    #[test]
    fn the_first_n_entries_make_a_scenario_hnav_accepts() {
        let dir = tempfile::tempdir().unwrap();
        let (map, scen) = files(dir.path(), SCEN);
        let b = Benchmark::load(&map, &scen).unwrap();
        let i = b.instance(2).unwrap();
        assert_eq!(i.agents(), 2);
        assert!((i.optimal_sum() - 6.41421356).abs() < 1e-9);
        assert_eq!(i.longest(), 3.41421356);
        let settings = RunSettings {
            mode: "lockstep".into(),
            rules: None,
            time_limit_s: 90.0,
            agents_per_process: 2,
            odometry_hz: Some(20),
        };
        let s = Scenario::from_str(&i.scenario_toml(&settings), "i.toml", dir.path()).unwrap();
        assert_eq!(s.agents.len(), 2);
        assert_eq!(
            (s.agents[1].start, s.agents[1].goal),
            (Cell::new(3, 1), Cell::new(0, 1))
        );
        assert_eq!(s.coordinator.time_limit_s, 90.0);
        assert_eq!(s.run.agents_per_process, 2);
        assert_eq!(s.sim.odometry_hz, 20);
        assert_eq!(s.map.grid, b.grid);
    }

    #[test]
    fn reports_name_the_map_and_the_scen_as_given() {
        // Relative to this crate's directory, where `cargo test` runs.
        let (map, scen) = (
            Path::new("../maps/random-32-32-10.map"),
            Path::new("../maps/random-32-32-10-random-1.scen"),
        );
        let b = Benchmark::load(map, scen).unwrap();
        assert_eq!(b.map_given, "../maps/random-32-32-10.map");
        assert_eq!(b.scen, "../maps/random-32-32-10-random-1.scen");
        assert!(
            b.map.is_absolute(),
            "the scenario needs {:?} absolute",
            b.map
        );
    }

    #[test]
    fn shared_starts_or_goals_and_short_files_are_errors_naming_the_lines() {
        let dir = tempfile::tempdir().unwrap();
        let (map, scen) = files(dir.path(), SCEN);
        let b = Benchmark::load(&map, &scen).unwrap();
        // Entries 1 and 3 (lines 2 and 4) both end at [3, 0] once the third is in.
        assert_eq!(
            b.instance(3).unwrap_err().to_string(),
            format!(
                "{}:4: goal [3, 0] is also the goal of line 2; the first 3 entries are no MAPF instance",
                scen.display()
            )
        );
        assert_eq!(
            b.instance(5).unwrap_err().to_string(),
            format!(
                "{}: 5 agents asked for, but the file has only 4 entries",
                scen.display()
            )
        );
        let shared_start = SCEN.replace("\t2\t1\t3\t0\t", "\t0\t0\t3\t1\t");
        let (map, scen) = files(dir.path(), &shared_start);
        let b = Benchmark::load(&map, &scen).unwrap();
        assert!(b
            .instance(3)
            .unwrap_err()
            .to_string()
            .ends_with(":4: start [0, 0] is also the start of line 2; the first 3 entries are no MAPF instance"));
    }
}
