//! Raft messages between replicas over the HNAV transport.
//!
//! Replica `i` reads the slice topic `raft/<i>` and writes to `raft/<j>` for every other
//! voter `j`: one topic per replica, so that the same code runs between hosts once a bridge
//! carries topics there. A message is Raft's own protobuf, encoded straight into the loaned
//! shared memory (its size is computed first) and decoded in place on the other side.
//!
//! Raft tolerates lost messages (it resends), but a leader must never wait for a dead
//! follower, so the topics overwrite the oldest unread message of a slow reader instead of
//! holding the writer ([`topics::raft_qos`]).
//!
//! A sample has no user header: the message names its sender and addressee itself.

use protobuf::{CodedOutputStream, Message as _};
use raft::eraftpb::Message;

use hnav_runtime::topics;
use hnav_runtime::transport::{SliceReceiver, SliceSender, Transport, TransportError};

use super::error::ReplicaError;
use super::wire::decode;

/// The largest encoded message a topic carries. [`MAX_ENTRIES_BYTES`] keeps Raft's appends
/// well below it; a round record is a few KiB at 256 agents.
pub const MAX_MESSAGE_BYTES: usize = topics::RAFT_MAX_BYTES;

/// What Raft may put into one append message (`Config::max_size_per_msg`); Raft always sends
/// at least one entry, so a single record must stay below [`MAX_MESSAGE_BYTES`].
pub const MAX_ENTRIES_BYTES: u64 = 16 * 1024;

/// The topic replica `id` reads.
pub fn topic(id: u64) -> String {
    topics::raft(id)
}

/// One replica's end of the Raft topics.
pub struct RaftLink {
    id: u64,
    inbox: SliceReceiver<u8, ()>,
    /// Senders to every other voter, by id.
    peers: Vec<(u64, SliceSender<u8, ()>)>,
}

impl RaftLink {
    /// Opens replica `id`'s inbox and a sender to every other voter.
    pub fn open(transport: &Transport, id: u64, voters: &[u64]) -> Result<Self, ReplicaError> {
        let qos = topics::raft_qos(voters.len());
        let inbox = transport.slice_receiver(&topic(id), qos)?;
        let peers = voters
            .iter()
            .filter(|&&v| v != id)
            .map(|&v| {
                Ok((
                    v,
                    transport.slice_sender(&topic(v), MAX_MESSAGE_BYTES, qos)?,
                ))
            })
            .collect::<Result<Vec<_>, TransportError>>()?;
        Ok(RaftLink { id, inbox, peers })
    }

    /// The inbox, to attach to the process's [`Waiter`](hnav_runtime::transport::Waiter).
    pub fn inbox(&self) -> &SliceReceiver<u8, ()> {
        &self.inbox
    }

    /// Sends `message` to its addressee (`Message::to`), encoded in place in shared memory.
    pub fn send(&self, message: &Message) -> Result<(), ReplicaError> {
        let Some((_, sender)) = self.peers.iter().find(|(v, _)| *v == message.to) else {
            return Err(ReplicaError::Encode(format!(
                "a message to {}, who is no other voter of replica {}",
                message.to, self.id
            )));
        };
        let len = message.compute_size() as usize;
        if len > sender.max_len() {
            return Err(ReplicaError::Encode(format!(
                "a {len}-byte message, over the topic's {} bytes",
                sender.max_len()
            )));
        }
        sender.loan(len)?.fill_with(0u8, |bytes| {
            let mut out = CodedOutputStream::bytes(bytes);
            message
                .write_to_with_cached_sizes(&mut out)
                .and_then(|()| out.flush())
                .map_err(|e| ReplicaError::Encode(e.to_string()))
        })?;
        Ok(())
    }

    /// Hands every message waiting in the inbox to `f`, decoded; a sample that does not
    /// decode, or is addressed to another replica, is counted in the returned
    /// [`Inbox::dropped`] and skipped.
    pub fn receive(&self, mut f: impl FnMut(Message)) -> Result<Inbox, ReplicaError> {
        let mut inbox = Inbox::default();
        self.inbox.drain_pending(|(), bytes| match decode(bytes) {
            Ok(m) if m.to == self.id => {
                inbox.messages += 1;
                f(m);
            }
            _ => inbox.dropped += 1,
        })?;
        Ok(inbox)
    }
}

/// What one [`RaftLink::receive`] found.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Inbox {
    /// Messages handed on.
    pub messages: usize,
    /// Samples dropped: not a Raft message, or not for this replica.
    pub dropped: usize,
}
