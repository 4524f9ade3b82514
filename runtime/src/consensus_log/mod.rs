//! The durable consensus log of a run: its record types, on-disk format, writer, reader,
//! verifier, and the [`Tally`] its decisions add up to.
//!
//! The coordinator appends one [`Record::Round`] per decision round with a [`LogWriter`] and
//! publishes the round's [`Commit`](crate::msg::Commit) only after the record is durable.
//! After a restart it rebuilds its state from the records; `hnav log verify|show DIR` inspects
//! a log, and the run summary is read from it.
//!
//! # Format (version [`FORMAT_VERSION`])
//!
//! A log is a directory of segment files `seg-00000000.hlog`, `seg-00000001.hlog`, ... numbered
//! without gaps. Each segment starts with the 8-byte [`MAGIC`] `HNAVLOG1`, followed by records:
//!
//! ```text
//! u32 LE payload length | u32 LE crc32c(payload) | payload
//! ```
//!
//! The payload is a [`Record`] in bincode 2's standard configuration (via serde), at most
//! [`MAX_RECORD_LEN`] bytes. The first record of a log is a [`Record::Header`]. The writer
//! starts a new segment before a record that would take the current one past its size limit
//! ([`DEFAULT_SEGMENT_BYTES`]). Only the end of the last segment can be torn by a crash; see
//! [`reader`] for what counts as torn and what as corruption.
//!
//! A coordinator replica's log (version [`REPLICATED_VERSION`], a run with `replicas = 3|5`)
//! is the same segments and frames; after its header every record is a Raft entry, which
//! carries its term and index around an encoded record, or a Raft hard state
//! ([`replicated`]). Readers of decisions take them through [`read_decided`].
//!
//! | module | what it holds |
//! |---|---|
//! | [`record`] | [`Record`] and its parts; conversions from `msg`; [`candidates_digest`] |
//! | [`frame`] | encoding and checking one record's frame |
//! | [`segment`] | segment file names and listing |
//! | [`writer`] | [`LogWriter`]: appends durably by [`FsyncPolicy`](crate::scenario::FsyncPolicy), cuts a torn tail on open, poisons itself after a failed fsync |
//! | [`reader`] | [`LogReader`], [`read_log`]: records in order, torn tail vs corruption |
//! | [`verify`](mod@verify) | [`verify()`]: a [`VerifyReport`] on whether a log is intact |
//! | [`show`] | one-line text and JSON renderings of records |
//! | [`filter`] | [`RecordFilter`]: which records `hnav log show` prints, by round, agent and kind |
//! | [`tally`] | [`Tally`]: per-agent steps, octile length, conflicts, rounds waited for the plan and replans of the decisions |
//! | [`snapshot`] | [`SnapshotRecord`], [`AppliedState`]: what a replica's compacted prefix adds up to |
//! | [`replicated`] | a replica's log (version [`REPLICATED_VERSION`]): Raft entries and hard state in the same frames; [`resolve`], [`read_decided`] |
//! | [`compare`](mod@compare) | [`compare()`]: two logs record by record, the first [`Divergence`] in words (`hnav log replay`) |
//! | [`error`] | [`LogError`], [`FrameProblem`] |

pub mod compare;
pub mod error;
pub mod filter;
pub mod frame;
pub mod reader;
pub mod record;
pub mod replicated;
pub mod segment;
pub mod show;
pub mod snapshot;
pub mod tally;
pub mod verify;
pub mod writer;

pub use compare::{compare, Comparison, Divergence};
pub use error::{FrameProblem, LogError};
pub use filter::RecordFilter;
pub use frame::{
    decode_record, encode_frame, encode_record, FRAME_HEADER_LEN, MAGIC, MAX_RECORD_LEN,
};
pub use reader::{read_log, LogContents, LogReader, RecordPos, TornTail};
pub use record::{
    candidates_digest, AgentEntry, EndReason, EndRecord, LifecycleRecord, LoggedDecision,
    MapChangeRecord, RaftEntryRecord, RaftStateRecord, Record, ReplanRecord, RoundRecord,
    RunHeader, SnapshotRecord, TaskRecord, UnreachableRecord,
};
pub use replicated::{
    is_replicated, read_decided, replica_dirs, resolve, Decided, ReplicaRole, Resolved, ROLE_FILE,
};
pub use segment::{list_segments, segment_name, segment_path, DEFAULT_SEGMENT_BYTES};
pub use snapshot::{AgentLife, AppliedState};
pub use tally::{AgentTally, Counted, Tally};
pub use verify::{verify, KindCounts, VerifyReport, VerifyStatus};
pub use writer::{
    LogWriter, Recovered, WriterOptions, BATCH_INTERVAL, BATCH_RECORDS, REPLACE_READY, REPLACE_TMP,
    WRITER_LOCK,
};

/// The format version of a single coordinator's log, in its [`RunHeader::version`].
pub const FORMAT_VERSION: u32 = 1;

/// The format version of a coordinator replica's log: after the header only Raft entries
/// (each with its term and index) and hard states ([`replicated`]). A build reads both.
pub const REPLICATED_VERSION: u32 = 2;
