//! Files that must survive a crash: one toolkit, so that every durable write in HNAV fails
//! the same way.
//!
//! | module | what it holds |
//! |---|---|
//! | [`replace`] | [`replace_file`]: a whole file replaced, old or new after a crash, never half of either |
//! | [`slot`] | [`SlotFile`], [`SlotPair`]: a checkpoint rewritten in place every control period, checksummed |
//! | [`read`] | [`FrameReader`]: the frames of an append-only file back, a [`Torn`] tail ("torn tail cut at offset N") told from corruption |
//! | [`append`] | [`Appender`]: frames appended with one write each, synced on demand, poisoned by a failed fsync |
//! | [`framed`] | [`FrameFormat`]: the consensus log's and `maps.bin`'s [`Checksummed`] frames, `trajectories.bin`'s [`Fixed`] records; [`FrameProblem`] |
//! | [`disk`] | [`Disk`], [`DiskFile`]: the file operations the writers make, [`RealDisk`] or a crash test's |
//!
//! An fsync that fails is data loss the kernel has already forgotten (the page may be clean
//! and wrong): it is reported as an error (the caller names the file), never retried; an
//! [`Appender`] refuses every later write until the file is reopened.
//!
//! # Which files use it
//!
//! | file | how |
//! |---|---|
//! | the consensus log's segments | [`Appender`] and [`FrameReader`] in [`Checksummed`] frames, synced by the run's fsync policy |
//! | `summary.json`, `invocation.json`, `rejected.json`, a replica's role file, the run registry's records | [`replace_file`] |
//! | `agents/N.ckpt` (agent checkpoint) | one [`SlotFile`] |
//! | `sim.ckpt.0`, `sim.ckpt.1` (sim checkpoint) | a [`SlotPair`] |
//! | `recording/maps.bin`, `recording/trajectories.bin` | [`Appender`] and [`FrameReader`] ([`Checksummed`], [`Fixed`]); synced once, when the recording finishes |
//!
//! Left as plain writes, because a crash loses nothing a later run needs and the file is
//! written again whole by whoever wants it: the report (`report.svg`, `report.html`), the MCAP
//! export, `scenario-report.json`, the run's map copy `map.map` (written before any process
//! starts; a crash there fails the run's start), and the events journal `events.jsonl`
//! (append-only lines for people, each one `write`; a torn last line is a torn last line).
//! `hnav` commands that write a map or a scenario file (`movingai`) write what the user asked
//! for, once.

pub mod append;
pub mod disk;
pub mod framed;
pub mod read;
pub mod replace;
pub mod slot;

pub use append::Appender;
pub use disk::{Disk, DiskFile, RealDisk};
pub use framed::{Checksummed, Fixed, FrameFormat, FrameProblem};
pub use read::{FrameError, FrameReader, Step, Torn};
pub use replace::{replace_file, replace_file_on};
pub use slot::{Newest, PairError, SlotFile, SlotLayout, SlotLen, SlotPair, SlotRead};

/// The error of a failed fsync: its kind kept (a full disk stays a full disk), its message
/// saying that the data written since the last sync may be lost.
fn sync_failed(e: std::io::Error) -> std::io::Error {
    std::io::Error::new(
        e.kind(),
        format!("fsync failed, so data written since the last sync may be lost: {e}"),
    )
}
