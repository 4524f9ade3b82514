//! A Raft message on the wire: protobuf, Raft's own encoding.

use protobuf::Message as _;
use raft::eraftpb::Message;

use super::error::ReplicaError;

/// A message as bytes for the wire (protobuf, Raft's own encoding).
pub fn encode(message: &Message) -> Result<Vec<u8>, ReplicaError> {
    message
        .write_to_bytes()
        .map_err(|e| ReplicaError::Encode(e.to_string()))
}

/// A message from the wire.
pub fn decode(bytes: &[u8]) -> Result<Message, ReplicaError> {
    Message::parse_from_bytes(bytes).map_err(|e| ReplicaError::Decode(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raft::eraftpb::MessageType;

    /// The tag of field 100, which no Raft message has, with wire type `wire` (3 opens a
    /// group, 4 closes it), as protobuf's varint.
    fn unknown_tag(wire: u32) -> [u8; 2] {
        let tag = (100 << 3) | wire;
        [(tag & 0x7f) as u8 | 0x80, (tag >> 7) as u8]
    }

    /// `depth` unknown groups, each inside the one before.
    fn nested_groups(depth: usize) -> Vec<u8> {
        let mut bytes = Vec::with_capacity(4 * depth);
        (0..depth).for_each(|_| bytes.extend(unknown_tag(3)));
        (0..depth).for_each(|_| bytes.extend(unknown_tag(4)));
        bytes
    }

    /// RUSTSEC-2024-0437 (protobuf before 3.7.2): a parser that skips an unknown group by
    /// recursing into the groups nested in it overflows the stack on deep nesting. The
    /// protobuf 2.28 that Raft's messages are parsed with skips a group in a loop and refuses
    /// a group inside one, so a sample from a hostile writer of a `raft/<i>` topic is an
    /// error (counted and dropped by `RaftLink::receive`), at any depth and in an entry too.
    #[test]
    fn nested_unknown_groups_are_an_error_not_a_stack_overflow() {
        let mut heartbeat = Message::default();
        heartbeat.set_msg_type(MessageType::MsgHeartbeat);
        heartbeat.to = 2;
        // One unknown group is skipped: the parser does reach the code the advisory is about.
        let mut one = encode(&heartbeat).unwrap();
        one.extend(nested_groups(1));
        assert_eq!(decode(&one).unwrap(), heartbeat);

        let mut deep = encode(&heartbeat).unwrap();
        deep.extend(nested_groups(1_000_000));
        let e = decode(&deep).unwrap_err();
        assert!(e.to_string().contains("does not decode"), "{e}");

        // Field 7 (`entries`), length-delimited: an entry of nested groups.
        let entry = nested_groups(100_000);
        let mut in_entry = vec![(7 << 3) | 2];
        let mut len = entry.len();
        while len >= 0x80 {
            in_entry.push((len & 0x7f) as u8 | 0x80);
            len >>= 7;
        }
        in_entry.push(len as u8);
        in_entry.extend(entry);
        let e = decode(&in_entry).unwrap_err();
        assert!(e.to_string().contains("does not decode"), "{e}");
    }
}
