//! Record framing: `u32 LE payload length | u32 LE crc32c(payload) | payload`, the payload
//! being the [`Record`] in bincode 2's standard configuration (through serde).

use super::error::{FrameProblem, LogError};
use super::record::Record;
use crate::durable::framed::seal_checksummed;
use crate::durable::{Checksummed, FrameFormat};

/// The first 8 bytes of every segment file.
pub const MAGIC: [u8; 8] = *b"HNAVLOG1";

/// Bytes before a record's payload: its length and its checksum.
pub const FRAME_HEADER_LEN: usize = 8;

/// The largest payload a record may have (16 MiB). A stored length above it is garbage.
pub const MAX_RECORD_LEN: u32 = 16 << 20;

type Standard = bincode::config::Configuration;
type Limited = bincode::config::Configuration<
    bincode::config::LittleEndian,
    bincode::config::Varint,
    bincode::config::Limit<{ MAX_RECORD_LEN as usize }>,
>;

fn standard() -> Standard {
    bincode::config::standard()
}

/// The standard configuration with a decode limit, so that a garbage collection length in a
/// payload cannot make the decoder allocate more than a record may hold. Same wire format.
fn limited() -> Limited {
    bincode::config::standard().with_limit::<{ MAX_RECORD_LEN as usize }>()
}

/// Appends one complete frame (header and payload) for `record` to `buf`.
///
/// On error `buf` is left as it was. Encoding into a reused `buf` allocates nothing once the
/// buffer has grown to the largest record.
pub fn encode_frame(record: &Record, buf: &mut Vec<u8>) -> Result<(), LogError> {
    let start = buf.len();
    buf.extend_from_slice(&[0; FRAME_HEADER_LEN]);
    if let Err(e) = bincode::serde::encode_into_std_write(record, buf, standard()) {
        buf.truncate(start);
        return Err(LogError::Encode(e));
    }
    let len = buf.len() - start - FRAME_HEADER_LEN;
    if len > MAX_RECORD_LEN as usize {
        buf.truncate(start);
        return Err(LogError::TooLarge {
            len,
            max: MAX_RECORD_LEN,
        });
    }
    seal_checksummed(buf, start);
    Ok(())
}

/// The segments' frame format, as the durable toolkit reads it.
pub type LogFormat = Checksummed<fn(&[u8]) -> Result<Record, FrameProblem>>;

/// The segments' frames: a payload of 1 to [`MAX_RECORD_LEN`] bytes, one [`Record`].
pub fn format() -> LogFormat {
    Checksummed {
        min_len: 1,
        max_len: MAX_RECORD_LEN,
        decode: decode_record,
    }
}

/// Splits a record header into (payload length, stored checksum).
pub fn parse_frame_header(header: &[u8; FRAME_HEADER_LEN]) -> (u32, u32) {
    let len = u32::from_le_bytes([header[0], header[1], header[2], header[3]]);
    let crc = u32::from_le_bytes([header[4], header[5], header[6], header[7]]);
    (len, crc)
}

/// Checks `payload` against its stored checksum and decodes it; the whole payload must be
/// one record.
pub fn decode_payload(payload: &[u8], stored_crc: u32) -> Result<Record, FrameProblem> {
    let mut header = [0u8; FRAME_HEADER_LEN];
    header[4..].copy_from_slice(&stored_crc.to_le_bytes());
    format().decode(&header, payload)
}

/// A record's payload encoding (a frame's payload without the frame): what a replicated log
/// carries inside a Raft entry. On error `buf` is left as it was.
pub fn encode_record(record: &Record, buf: &mut Vec<u8>) -> Result<(), LogError> {
    let start = buf.len();
    bincode::serde::encode_into_std_write(record, buf, standard())
        .map(|_| ())
        .map_err(|e| {
            buf.truncate(start);
            LogError::Encode(e)
        })
}

/// Decodes one record's payload encoding; the whole of `payload` must be the record.
pub fn decode_record(payload: &[u8]) -> Result<Record, FrameProblem> {
    match bincode::serde::decode_from_slice::<Record, _>(payload, limited()) {
        Ok((record, used)) if used == payload.len() => Ok(record),
        Ok((_, used)) => Err(FrameProblem::Undecodable {
            detail: format!("{} trailing bytes", payload.len() - used),
        }),
        Err(e) => Err(FrameProblem::Undecodable {
            detail: describe_decode_error(&e),
        }),
    }
}

/// What is wrong with a payload, in words: bincode's own `Display` is its `Debug` form
/// (`InvalidIntegerType { expected: U32, found: Reserved }`), which `hnav log verify` must not
/// print.
fn describe_decode_error(e: &bincode::error::DecodeError) -> String {
    use bincode::error::DecodeError as E;
    match e {
        E::UnexpectedEnd { additional } => {
            let s = if *additional == 1 { "" } else { "s" };
            format!("the payload ends {additional} byte{s} early")
        }
        E::LimitExceeded => {
            format!("a length in it exceeds the {MAX_RECORD_LEN} bytes of a record")
        }
        E::InvalidIntegerType { .. } => "a malformed integer".into(),
        E::UnexpectedVariant { found, .. } => format!("unknown variant {found}"),
        E::Utf8 { .. } => "a text field is not UTF-8".into(),
        E::InvalidBooleanValue(v) => format!("a boolean of value {v}"),
        E::OutsideUsizeRange(v) => format!("a length of {v}, too large for this machine"),
        // Serde's own wording, e.g. "invalid value: integer `9`, expected variant index
        // 0 <= i < 8" for an unknown record kind.
        E::OtherString(s) => s.clone(),
        E::Other(s) => (*s).into(),
        _ => "not a record of this format".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::consensus_log::{EndReason, EndRecord};

    #[test]
    fn frame_layout_and_round_trip() {
        let r = Record::End(EndRecord {
            round: 7,
            at_goal: 3,
            reason: EndReason::TimeLimit,
        });
        let mut buf = vec![0xAA];
        encode_frame(&r, &mut buf).unwrap();
        let header: [u8; 8] = buf[1..9].try_into().unwrap();
        let (len, crc) = parse_frame_header(&header);
        assert_eq!(len as usize, buf.len() - 9);
        assert_eq!(crc, crc32c::crc32c(&buf[9..]));
        assert_eq!(decode_payload(&buf[9..], crc).unwrap(), r);
        assert!(matches!(
            decode_payload(&buf[9..], crc ^ 1),
            Err(FrameProblem::BadChecksum { .. })
        ));
    }

    /// Found by the `record` fuzz target: the detail was bincode's `Debug` form.
    #[test]
    fn an_undecodable_payload_is_described_in_words() {
        let detail = |payload: &[u8]| match decode_payload(payload, crc32c::crc32c(payload)) {
            Err(FrameProblem::Undecodable { detail }) => detail,
            other => panic!("{other:?}"),
        };
        assert_eq!(detail(&[4]), "the payload ends 1 byte early");
        assert_eq!(detail(&[1, 0xFF]), "a malformed integer");
        assert_eq!(
            detail(&[11]),
            "invalid value: integer `11`, expected variant index 0 <= i < 11"
        );
    }

    #[test]
    fn garbage_with_a_valid_checksum_is_undecodable() {
        let payload = [0xFF; 12];
        let crc = crc32c::crc32c(&payload);
        assert!(matches!(
            decode_payload(&payload, crc),
            Err(FrameProblem::Undecodable { .. })
        ));
    }
}
