//! Fuzz targets for every HNAV reader of bytes that come from a file or from another process,
//! shared by the AFL++ harness (`fuzz/afl`, run by `fuzz/run.sh TARGET SECONDS`) and by the
//! CI-sized campaign (`cargo test -p hnav-fuzz`), which replays each target's committed corpus
//! and a bounded number of seeded mutations of it.
//!
//! Each [`Target`] feeds the input to one reader and checks what the reader promises: it never
//! panics, an error names its source (`<fuzz>`, the `source_name` the harness passes), and
//! accepted input round-trips where a writer exists. It returns an [`Outcome`], the class of
//! what happened (`ok`, or the error variant), which the campaigns count as their coverage.
//!
//! **Must not depend on**: any HNAV crate but `hnav-runtime`, whose readers it feeds, nor on
//! the AFL++ runtime (only `fuzz/afl`, outside the workspace, links it).
//!
//! Modules, highest first (a module uses only those below it in this table; imports never run
//! back up):
//!
//! | module | what it holds |
//! |---|---|
//! | `payload` | the `payload` target: every `msg` payload decoded from raw shared-memory bytes |
//! | `log` | the `record` and `log` targets: consensus-log payloads and segment directories |
//! | `text` | the `map`, `scen` and `scenario` targets: the text formats |
//! | `mutate` | [`Mutator`]: the campaign's seeded byte mutations of a corpus input |
//!
//! The targets:
//!
//! | target | reader | round trip |
//! |---|---|---|
//! | `map` | `grid::read_map` (MovingAI `.map`) | `write_map` then `read_map` gives the same grid |
//! | `scen` | `grid::read_scen`, then `validate_scen` against a committed 32x32 map | `write_scen` is a fixed point |
//! | `scenario` | `Scenario::from_str` (TOML), then `validate` and `scenario_hash` | none (no writer) |
//! | `record` | `consensus_log::frame::decode_payload` with the payload's own checksum, then `show` and `Tally` | `encode_frame` gives the same payload |
//! | `log` | a log directory (the input split into segments at each `HNAVLOG1`): `read_log`, `verify` | an intact log re-encodes to the input's bytes |
//! | `payload` | every `msg` payload as its raw bytes from shared memory: the `from_u8` decoders, `CommitView::decisions`, `TruthView::poses`, the bridge's `WireSlice` checks, `Lifecycle::period`, and their consensus-log records | `Decision` through `LoggedDecision` |

mod log;
mod mutate;
mod payload;
mod text;

use std::path::{Path, PathBuf};

pub use mutate::Mutator;

/// The source name every target passes to its reader, so that an error can be checked for
/// naming its file.
pub const SOURCE: &str = "<fuzz>";

/// One fuzz target: a reader and the properties checked on its result.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    /// The MovingAI `.map` reader.
    Map,
    /// The MovingAI `.scen` reader and its validation against a map.
    Scen,
    /// The scenario TOML reader.
    Scenario,
    /// One consensus-log record's payload decoder.
    Record,
    /// The consensus-log reader and verifier over segment files (framing, torn tails).
    Log,
    /// The shared-memory payload decoders of `msg`.
    Payload,
}

impl Target {
    /// Every target, in the order the campaigns run them.
    pub const ALL: [Target; 6] = [
        Target::Map,
        Target::Scen,
        Target::Scenario,
        Target::Record,
        Target::Log,
        Target::Payload,
    ];

    /// The target's name on the command line and as its corpus directory.
    pub fn name(self) -> &'static str {
        match self {
            Target::Map => "map",
            Target::Scen => "scen",
            Target::Scenario => "scenario",
            Target::Record => "record",
            Target::Log => "log",
            Target::Payload => "payload",
        }
    }

    /// The inverse of [`Target::name`].
    pub fn from_name(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The committed corpus of the target: valid and near-valid inputs, plus every minimised
    /// input that once crashed it (`crash-*`), kept as regression cases.
    pub fn corpus_dir(self) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("corpus")
            .join(self.name())
    }
}

/// What one input did: `ok`, or the class (variant) of the error the reader returned.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Outcome(String);

impl Outcome {
    /// The reader accepted the input.
    pub fn ok() -> Self {
        Outcome("ok".into())
    }

    /// A named class of rejected input.
    pub fn class(name: &str) -> Self {
        Outcome(name.into())
    }

    /// The class of `error`: its variant name, as its `Debug` form starts with it (so a
    /// variant added later is counted without a change here).
    pub fn of_error(prefix: &str, error: &impl std::fmt::Debug) -> Self {
        let debug = format!("{error:?}");
        let variant: String = debug
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        Outcome(format!("{prefix}{variant}"))
    }

    /// The class as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

/// What the targets need between inputs: a private directory for the log target's segment
/// files. Create one per process; [`Harness::run`] may then be called any number of times.
#[derive(Debug)]
pub struct Harness {
    dir: tempfile::TempDir,
}

impl Harness {
    /// A harness with a fresh temporary directory (removed when it is dropped).
    pub fn new() -> std::io::Result<Self> {
        Ok(Harness {
            dir: tempfile::Builder::new().prefix("hnav-fuzz-").tempdir()?,
        })
    }

    /// Feeds `data` to `target`'s reader and checks its properties; panics (the fuzzer's
    /// crash) when one fails, else returns what the reader made of the input.
    pub fn run(&self, target: Target, data: &[u8]) -> Outcome {
        match target {
            Target::Map => text::map(data),
            Target::Scen => text::scen(data),
            Target::Scenario => text::scenario(data),
            Target::Record => log::record(data),
            Target::Log => log::log(self.dir.path(), data),
            Target::Payload => payload::payload(data),
        }
    }
}

/// A user-facing message must be words, not a value's `Debug` form (`Variant { field: .. }`,
/// `Some(..)`), which names Rust types and fields.
pub(crate) fn check_not_debug(message: &str) {
    let struct_like = message.split(" { ").skip(1).any(|rest| {
        rest.split_once(": ").is_some_and(|(field, _)| {
            !field.is_empty() && field.chars().all(|c| c.is_ascii_lowercase() || c == '_')
        })
    });
    assert!(
        !struct_like && !message.contains("Some(") && !message.contains("None"),
        "error message looks like a debug dump: {message}"
    );
}

/// The files of a corpus directory, sorted by name (empty if it does not exist).
pub fn corpus_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    match std::fs::read_dir(dir) {
        Ok(entries) => {
            for entry in entries {
                let path = entry?.path();
                if path.is_file() {
                    files.push(path);
                }
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    files.sort();
    Ok(files)
}
