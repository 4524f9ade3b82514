//! Hostile or malformed input: the classes a receiver drops a message for, and the counts of
//! them that reach the run summary.
//!
//! Any process that knows a run's id can open its services and publish (there is no
//! authentication in shared memory), so a receiver checks every sample before it acts on it
//! and drops what no real peer would send. Dropping is counted per class; the first drop of
//! each class is logged once, never a line per message, so a flood cannot fill the disk with
//! warnings. The coordinator keeps its counts in `DIR/rejected.json` ([`Rejections::store`],
//! at exit, and read back by a restarted coordinator), where the supervisor picks them up for
//! `summary.json`'s `rejected`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The file in the run directory holding the coordinator's counts.
pub const FILE: &str = "rejected.json";

/// Why a candidate was dropped. The checks run in this order and a candidate counts for the
/// first that fails.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Rejected {
    /// The agent index is not one of the run's agents.
    Agent,
    /// Flag bits no agent sets, or a nonzero reserved field.
    Flags,
    /// Priority or speed other than the scenario's for that agent (NaN, infinite and negative
    /// values included): a real agent sends exactly the scenario's.
    PrioritySpeed,
    /// A cell off the map, a `next` that is neither `current` nor its neighbour, or a
    /// `probable` that is not a neighbour.
    Cell,
    /// A round after the open one.
    FutureRound,
    /// A round already decided (or round 0). It is dropped and answered with the last commit,
    /// as for a restarted agent catching up, which looks the same.
    PastRound,
}

impl Rejected {
    /// Every class, in check order.
    pub const ALL: [Rejected; 6] = [
        Rejected::Agent,
        Rejected::Flags,
        Rejected::PrioritySpeed,
        Rejected::Cell,
        Rejected::FutureRound,
        Rejected::PastRound,
    ];

    /// The class's name in logs and in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Rejected::Agent => "agent",
            Rejected::Flags => "flags",
            Rejected::PrioritySpeed => "priority-speed",
            Rejected::Cell => "cell",
            Rejected::FutureRound => "future-round",
            Rejected::PastRound => "past-round",
        }
    }

    /// The class named `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }

    fn slot(self) -> usize {
        self as usize
    }
}

/// A count per [`Rejected`] class; counting allocates nothing.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct Rejections {
    counts: [u64; Rejected::ALL.len()],
}

/// `DIR/rejected.json` could not be read back.
#[derive(Debug, thiserror::Error)]
pub enum RejectedFileError {
    /// The file exists but cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a map of class names to counts.
    #[error("{path}: not a map of rejection classes to counts: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

impl Rejections {
    /// Counts one dropped message of `class`; true if it is the first of its class.
    pub fn note(&mut self, class: Rejected) -> bool {
        let c = &mut self.counts[class.slot()];
        *c = c.saturating_add(1);
        *c == 1
    }

    /// Messages of `class` dropped so far.
    pub fn count(&self, class: Rejected) -> u64 {
        self.counts[class.slot()]
    }

    /// Messages dropped so far, every class together.
    pub fn total(&self) -> u64 {
        self.counts.iter().fold(0, |a, c| a.saturating_add(*c))
    }

    /// Every class by name with its count (zeros included, so the set of keys is fixed).
    pub fn to_map(&self) -> BTreeMap<String, u64> {
        Rejected::ALL
            .into_iter()
            .map(|c| (c.name().to_string(), self.count(c)))
            .collect()
    }

    /// The counts in `dir/rejected.json`; none (all zero) when the file does not exist.
    pub fn load(dir: &Path) -> Result<Self, RejectedFileError> {
        let path = dir.join(FILE);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Self::default()),
            Err(source) => return Err(RejectedFileError::Read { path, source }),
        };
        let format = |reason: String| RejectedFileError::Format {
            path: path.clone(),
            reason,
        };
        let map: BTreeMap<String, u64> =
            serde_json::from_str(&text).map_err(|e| format(e.to_string()))?;
        let mut out = Self::default();
        for (name, count) in map {
            let class = Rejected::from_name(&name)
                .ok_or_else(|| format(format!("unknown class {name}")))?;
            out.counts[class.slot()] = count;
        }
        Ok(out)
    }

    /// Writes the counts to `dir/rejected.json` whole or not at all
    /// ([`replace_file`](crate::durable::replace_file)): a reader never sees half a file, and
    /// a coordinator restarted after a crash finds the counts of before.
    pub fn store(&self, dir: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(&self.to_map()).map_err(std::io::Error::other)?;
        crate::durable::replace_file(&dir.join(FILE), (text + "\n").as_bytes())
    }
}

impl std::fmt::Display for Rejections {
    /// `agent=3 cell=0 ...`, every class in check order.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, c) in Rejected::ALL.into_iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{}={}", c.name(), self.count(c))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for c in Rejected::ALL {
            assert_eq!(Rejected::from_name(c.name()), Some(c));
        }
        assert_eq!(Rejected::from_name("nope"), None);
    }

    #[test]
    fn note_says_first_once_per_class() {
        let mut r = Rejections::default();
        assert!(r.note(Rejected::Cell));
        assert!(!r.note(Rejected::Cell));
        assert!(r.note(Rejected::Agent));
        assert_eq!(r.count(Rejected::Cell), 2);
        assert_eq!(r.total(), 3);
        assert_eq!(
            r.to_string(),
            "agent=1 flags=0 priority-speed=0 cell=2 future-round=0 past-round=0"
        );
    }

    #[test]
    fn the_file_round_trips_and_a_missing_one_is_empty() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(Rejections::load(dir.path()).unwrap(), Rejections::default());
        let mut r = Rejections::default();
        r.note(Rejected::FutureRound);
        r.note(Rejected::PastRound);
        r.store(dir.path()).unwrap();
        assert_eq!(Rejections::load(dir.path()).unwrap(), r);
    }

    #[test]
    fn a_bad_file_names_itself_and_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(FILE), "{\"teleport\": 3}").unwrap();
        let e = Rejections::load(dir.path()).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "rejected.json: not a map of rejection classes to counts: unknown class teleport"
            ),
            "{e}"
        );
    }
}
