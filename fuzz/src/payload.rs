//! The shared-memory payloads of `msg`: a sample is whatever bytes another process (or a rogue
//! one) put there, so the target builds each payload type from raw bytes and runs every
//! decoder a receiver runs on it.

use std::mem::size_of;

use hnav_runtime::consensus_log::show::{describe, to_json};
use hnav_runtime::consensus_log::{
    LifecycleRecord, LoggedDecision, Record, RecordPos, RoundRecord,
};
use hnav_runtime::msg::{
    ActivationKind, Candidate, CommitHeader, CommitView, ConflictKind, Decision, Lifecycle,
    LifecycleEvent, MapHeader, Odometry, Pose, Progress, Role, StartupPhase, StopReason,
    TruthHeader, TruthView, Verdict, WheelCommand, WireSlice,
};

use crate::Outcome;

/// A payload type whose every bit pattern is a valid value.
///
/// # Safety
///
/// The type must be `#[repr(C)]` with only integer and float fields (or arrays of such types)
/// and no padding, which the layout tests of `msg` assert for every type implementing this.
unsafe trait Plain: Copy + Default {}

// SAFETY: each is `#[repr(C)]`, made of integers, floats and arrays of them, without padding
// (asserted by the layout tests in `hnav_runtime::msg`).
unsafe impl Plain for Candidate {}
// SAFETY: as above.
unsafe impl Plain for Decision {}
// SAFETY: as above.
unsafe impl Plain for CommitHeader {}
// SAFETY: as above.
unsafe impl Plain for Progress {}
// SAFETY: as above.
unsafe impl Plain for WheelCommand {}
// SAFETY: as above.
unsafe impl Plain for Odometry {}
// SAFETY: as above.
unsafe impl Plain for TruthHeader {}
// SAFETY: as above.
unsafe impl Plain for Pose {}
// SAFETY: as above.
unsafe impl Plain for Lifecycle {}
// SAFETY: as above.
unsafe impl Plain for MapHeader {}

/// A `T` holding `data`'s bytes (zero-padded or cut to its size), as a subscriber would see a
/// sample of those bytes.
fn from_bytes<T: Plain>(data: &[u8]) -> T {
    let mut value = T::default();
    let n = data.len().min(size_of::<T>());
    // SAFETY: `value` is a valid `T` of `size_of::<T>()` bytes and `n` bytes fit in it; any
    // bytes written form a valid `T` (`Plain`); the regions cannot overlap.
    unsafe {
        std::ptr::copy_nonoverlapping(data.as_ptr(), (&raw mut value).cast::<u8>(), n);
    }
    value
}

/// A slice sample of `data`'s bytes: the header `H` (zero-padded or cut), then as many whole
/// elements `E` as the rest holds, as a subscriber of a slice topic would see them.
fn slice_from_bytes<H: Plain, E: Plain>(data: &[u8]) -> (H, Vec<E>) {
    let n = data.len().min(size_of::<H>());
    let elements = data[n..].chunks_exact(size_of::<E>()).map(from_bytes);
    (from_bytes(data), elements.collect())
}

/// The bridge's check of a slice sample from another host, over the same bytes: refused or
/// taken, never a panic; what it takes must be what a local reader sees.
fn wire_check<H: WireSlice + PartialEq>(data: &[u8], local: &[H::Element]) -> bool
where
    H::Element: Plain + PartialEq,
{
    let Ok((h, rest)) = H::from_wire(data) else {
        return false;
    };
    let mut out = vec![H::Element::default(); rest.len() / size_of::<H::Element>().max(1)];
    let taken = h.elements_from_wire(rest, &mut out).is_ok();
    if taken {
        assert_eq!(
            out, local,
            "the wire reads the elements a local reader reads"
        );
    }
    taken
}

/// A record's renderings, as `hnav log show` prints what the coordinator logged from the
/// payload.
fn render(record: &Record) {
    let pos = RecordPos {
        segment: 0,
        offset: 8,
        len: 0,
    };
    for width in [0, 7] {
        assert!(!describe(record, width).is_empty());
        assert!(to_json(&pos, record, width).is_object());
    }
}

fn decision(d: &Decision) -> Outcome {
    let logged = LoggedDecision::from(d);
    let back = Decision::from(&logged);
    assert_eq!(
        Decision { reserved: 0, ..*d },
        Decision {
            reserved: 0,
            ..back
        },
        "a decision changes through the log's form"
    );
    match (Verdict::from_u8(d.verdict), ConflictKind::from_u8(d.kind)) {
        (Some(v), Some(k)) => Outcome::class(&format!("ok:decision:{}:{}", v.name(), k.name())),
        (None, _) => Outcome::class("unknown:decision-verdict"),
        (Some(_), None) => Outcome::class("unknown:decision-kind"),
    }
}

fn lifecycle(l: &Lifecycle) -> Outcome {
    let period = l.period();
    assert_eq!(period as u32, l.index);
    assert_eq!((period >> 32) as u32, l.restarts);
    render(&Record::Lifecycle(LifecycleRecord::new(period, l)));
    let (Some(role), Some(event)) = (Role::from_u8(l.role), LifecycleEvent::from_u8(l.event))
    else {
        return Outcome::class("unknown:lifecycle-role-or-event");
    };
    assert_eq!(Role::from_name(role.name()), Some(role));
    assert!(!role.node_name(l.index).is_empty());
    let detail = match event {
        LifecycleEvent::Stop => StopReason::from_u8(l.reason).map_or("unknown-reason", |_| "known"),
        LifecycleEvent::Phase => match StartupPhase::from_u8(l.reason) {
            Some(p) => {
                assert!(!p.describe(l.restarts).is_empty());
                "known"
            }
            None => "unknown-phase",
        },
        _ => "known",
    };
    Outcome::class(&format!("ok:lifecycle:{}:{detail}", event.name()))
}

/// The first byte picks the payload type, the rest are its bytes.
pub(crate) fn payload(data: &[u8]) -> Outcome {
    let Some((&kind, bytes)) = data.split_first() else {
        return Outcome::class("empty");
    };
    match kind % 9 {
        0 => {
            let c: Candidate = from_bytes(bytes);
            let round = RoundRecord::new(c.round, &[c], &[]);
            assert_eq!(round.candidates, 1);
            render(&Record::Round(round));
            Outcome::class(if c.priority.is_finite() {
                "ok:candidate"
            } else {
                "ok:candidate-non-finite-priority"
            })
        }
        1 => decision(&from_bytes(bytes)),
        2 => {
            let (h, slice): (CommitHeader, Vec<Decision>) = slice_from_bytes(bytes);
            let c = CommitView::new(&h, &slice);
            let decisions = c.decisions();
            assert_eq!(decisions.len(), (h.count as usize).min(slice.len()));
            let logged = RoundRecord {
                round: c.round(),
                candidates: h.count,
                candidates_digest: 0,
                decisions: decisions.iter().map(LoggedDecision::from).collect(),
            };
            let back = logged.commit();
            assert!(
                back.decisions()
                    .iter()
                    .map(LoggedDecision::from)
                    .eq(logged.decisions.iter().copied()),
                "a commit changes through the log's form"
            );
            for d in decisions {
                decision(d);
            }
            let wire = wire_check::<CommitHeader>(bytes, decisions);
            render(&Record::Round(logged));
            Outcome::class(match (h.count as usize > slice.len(), wire) {
                (true, _) => "ok:commit-count-past-slice",
                (false, true) => "ok:commit",
                (false, false) => "ok:commit-refused-on-the-wire",
            })
        }
        3 => {
            let (h, slice): (TruthHeader, Vec<Pose>) = slice_from_bytes(bytes);
            let t = TruthView::new(&h, &slice);
            assert_eq!(t.poses().len(), (h.robots as usize).min(slice.len()));
            Outcome::class(if wire_check::<TruthHeader>(bytes, t.poses()) {
                "ok:truth"
            } else {
                "ok:truth-refused-on-the-wire"
            })
        }
        4 => lifecycle(&from_bytes(bytes)),
        5 => {
            let p: Progress = from_bytes(bytes);
            Outcome::class(match p.done {
                0 => "ok:progress",
                Progress::ALL_AT_GOAL | Progress::TIME_LIMIT => "ok:progress-done",
                _ => "unknown:progress-done",
            })
        }
        6 => {
            let h: MapHeader = from_bytes(bytes);
            Outcome::class(match ActivationKind::from_u8(h.activation) {
                Some(_) => "ok:map-header",
                None => "unknown:map-header-activation",
            })
        }
        7 => {
            let _: WheelCommand = from_bytes(bytes);
            Outcome::class("ok:wheel-command")
        }
        _ => {
            let _: Odometry = from_bytes(bytes);
            Outcome::class("ok:odometry")
        }
    }
}
