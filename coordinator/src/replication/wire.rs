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
