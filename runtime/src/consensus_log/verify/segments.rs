//! The segment rule of [`verify`](super::verify): no segment but the last lost complete
//! records at its end.
//!
//! The reader already refuses a segment that is not the last and does not end on a record
//! boundary; a segment cut exactly between two records reads fine, so the rule is checked
//! against how [`LogWriter`](crate::consensus_log::LogWriter) rolls over: it starts segment
//! `i + 1` only before a record that would take segment `i` past its size limit `S`, and it
//! appends to a segment only while the result stays within `S` (a segment's first record
//! may exceed it). So for every segment `i` but the last, with `len(i)` its bytes and
//! `first(i + 1)` the bytes of the next segment's first record:
//!
//! - `len(i) + first(i + 1) > S`, and
//! - `len(i) <= S` when segment `i` holds more than one record.
//!
//! The limit is not written in the log, but it is the same for every segment of a run (it
//! is not a scenario setting), so the segments must agree on one `S`: the largest segment
//! holding more than one record bounds it from below, and each segment's end plus its
//! successor's first record bounds it from above. A segment whose bound falls below the
//! largest segment ended early: records are missing at its end. Rounds and their gaps
//! (`order`) catch the other case, a lost round record with too few segments to compare.

use super::VerifyReport;
use crate::consensus_log::frame::MAGIC;
use crate::consensus_log::reader::RecordPos;
use crate::consensus_log::segment::segment_name;

/// What the reader saw of one segment.
#[derive(Clone, Copy, Debug)]
struct Span {
    records: u64,
    end: u64,
    first_len: Option<u64>,
}

/// Collects the record positions of every segment while the log is read.
#[derive(Default)]
pub(super) struct SegmentCheck {
    spans: Vec<Span>,
}

impl SegmentCheck {
    /// Notes the next record's position (records arrive in log order).
    pub(super) fn record(&mut self, pos: RecordPos) {
        let segment = pos.segment as usize;
        while self.spans.len() <= segment {
            self.spans.push(Span {
                records: 0,
                end: MAGIC.len() as u64,
                first_len: None,
            });
        }
        let span = &mut self.spans[segment];
        span.records += 1;
        span.end = pos.end();
        span.first_len.get_or_insert(pos.len);
    }

    /// Adds a problem for each segment but the last that holds no record or ended before the
    /// writer would have rolled over. `segments` is the number of segment files; call only
    /// when the whole log was read.
    pub(super) fn finish(mut self, report: &mut VerifyReport, segments: usize) {
        while self.spans.len() < segments {
            self.spans.push(Span {
                records: 0,
                end: MAGIC.len() as u64,
                first_len: None,
            });
        }
        let spans = &self.spans[..segments];
        let Some(non_last) = spans.len().checked_sub(1) else {
            return;
        };
        for (i, s) in spans[..non_last].iter().enumerate() {
            if s.records == 0 {
                report.problems.push(format!(
                    "{} holds no record but is not the last segment",
                    segment_name(i as u32)
                ));
            }
        }
        let largest = spans[..non_last]
            .iter()
            .enumerate()
            .filter(|(_, s)| s.records > 1)
            .max_by_key(|(_, s)| s.end);
        let Some((big, largest)) = largest else {
            return;
        };
        for (i, pair) in spans.windows(2).enumerate() {
            let (s, next) = (pair[0], pair[1]);
            let Some(first) = next.first_len.filter(|_| s.records > 0) else {
                continue;
            };
            if s.end + first <= largest.end {
                report.problems.push(format!(
                    "{} ends after {} bytes although the next segment's first record \
                     ({first} bytes) would have fitted, as {} holds {} bytes: complete \
                     records are missing at its end",
                    segment_name(i as u32),
                    s.end,
                    segment_name(big as u32),
                    largest.end
                ));
            }
        }
    }
}
