//! The consensus-log readers: one record's payload, and whole segment files.

use std::path::Path;

use hnav_runtime::consensus_log::frame::decode_payload;
use hnav_runtime::consensus_log::show::{describe, to_json};
use hnav_runtime::consensus_log::{
    encode_frame, read_log, segment_path, verify, Record, RecordPos, Tally, FRAME_HEADER_LEN, MAGIC,
};

use crate::Outcome;

/// Widths the renderings are tried with: unknown (0), a small grid, and the largest.
const WIDTHS: [u32; 3] = [0, 7, u32::MAX];

/// Everything `hnav log show` and the run summary do with a decoded record, which read its
/// fields without trusting them (agent indices, verdict and kind codes, cells).
fn render(pos: &RecordPos, record: &Record) {
    for width in WIDTHS {
        assert!(!describe(record, width).is_empty());
        assert!(to_json(pos, record, width).is_object());
    }
    match record {
        Record::Header(h) => {
            let tally = Tally::from_header(h);
            assert_eq!(tally.agents().len(), h.agents.len());
        }
        Record::Round(r) => {
            for width in WIDTHS {
                let mut tally = Tally::new(0..8, width);
                tally.fold_round(r);
                let _ = (tally.conflicts(), tally.replans());
            }
        }
        _ => {}
    }
}

/// `decode_payload` of the input under its own checksum (so that the fuzzer reaches the
/// decoder rather than the checksum); a decoded record re-encodes to a payload that decodes
/// to the same encoding again.
pub(crate) fn record(data: &[u8]) -> Outcome {
    match decode_payload(data, crc32c::crc32c(data)) {
        Ok(record) => {
            let mut frame = Vec::new();
            encode_frame(&record, &mut frame)
                .unwrap_or_else(|e| panic!("a decoded record does not encode: {e}"));
            let payload = &frame[FRAME_HEADER_LEN..];
            let again = decode_payload(payload, crc32c::crc32c(payload))
                .unwrap_or_else(|e| panic!("an encoded record does not decode: {e}"));
            let mut frame_again = Vec::new();
            encode_frame(&again, &mut frame_again).expect("it encoded once");
            assert_eq!(frame_again, frame, "record round trip is not a fixed point");
            let pos = RecordPos {
                segment: 0,
                offset: MAGIC.len() as u64,
                len: frame.len() as u64,
            };
            render(&pos, &record);
            Outcome::class(&format!("ok:{}", record.kind()))
        }
        Err(e) => {
            crate::check_not_debug(&e.to_string());
            Outcome::of_error("", &e)
        }
    }
}

/// The input as segment files: a new segment starts at every `HNAVLOG1` after the first byte,
/// so that the corpus can hold logs of several segments.
fn segments(data: &[u8]) -> Vec<&[u8]> {
    let mut starts = vec![0];
    starts.extend(
        data.windows(MAGIC.len())
            .enumerate()
            .skip(1)
            .filter(|(_, w)| *w == MAGIC)
            .map(|(i, _)| i),
    );
    starts.push(data.len());
    starts.windows(2).map(|w| &data[w[0]..w[1]]).collect()
}

/// Writes the input into `dir` as a log and reads it with `read_log` and `verify`: both agree
/// on whether it can be read, errors name the file, and a log read without a torn tail
/// re-encodes to exactly the input's bytes.
pub(crate) fn log(dir: &Path, data: &[u8]) -> Outcome {
    for entry in std::fs::read_dir(dir).expect("the harness directory is readable") {
        std::fs::remove_file(entry.expect("directory entry").path()).expect("clears a segment");
    }
    let segments = segments(data);
    for (i, bytes) in segments.iter().enumerate() {
        std::fs::write(segment_path(dir, i as u32), bytes).expect("writes a segment");
    }
    let report = verify(dir);
    assert!(!report.render().is_empty());
    let dir_name = dir.display().to_string();
    match read_log(dir) {
        Ok(contents) => {
            assert!(
                report.error.is_none(),
                "verify fails where read_log does not"
            );
            let mut positions = contents.positions.iter();
            for (record, pos) in contents.records.iter().zip(&mut positions) {
                render(pos, record);
            }
            if let Some(torn) = &contents.torn {
                assert!(torn.path.starts_with(dir), "a torn tail outside the log");
                crate::check_not_debug(&torn.problem.to_string());
                return Outcome::of_error("torn:", &torn.problem);
            }
            let mut rebuilt: Vec<Vec<u8>> = vec![MAGIC.to_vec(); segments.len()];
            for (record, pos) in contents.records.iter().zip(&contents.positions) {
                encode_frame(record, &mut rebuilt[pos.segment as usize]).expect("encodes");
            }
            for (i, (rebuilt, read)) in rebuilt.iter().zip(&segments).enumerate() {
                assert_eq!(rebuilt, read, "segment {i} does not re-encode to its bytes");
            }
            if report.is_intact() {
                Outcome::ok()
            } else {
                Outcome::class("read-but-not-intact")
            }
        }
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.contains(&dir_name),
                "error names no file: {message}"
            );
            crate::check_not_debug(&message);
            assert!(
                report.error.is_some(),
                "read_log fails where verify does not"
            );
            Outcome::of_error("", &e)
        }
    }
}
