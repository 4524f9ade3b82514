//! The simulated network ([`Network`]): which links are cut, and when a message sent now
//! arrives, if it does. The messages themselves travel in the scheduler's queue.
//!
//! Normally a message takes 0.1 to 2 ms and the messages of one link arrive in the order
//! they were sent (the `raft/<i>` topics are queues). The nemesis cuts links (one way or
//! both) and sets the network's mode: slow (up to 400 ms more, in order), lossy (a share
//! of the messages dropped), duplicating (a share delivered twice, the copy up to 100 ms
//! later) and reordering (up to 60 ms more each, in any order).

use super::clock::Time;
use super::rng::Rng;

/// What the nemesis set the network to do; all off is a healthy network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Mode {
    /// Up to 400 ms more per message, in order.
    pub slow: bool,
    /// Percent of the messages dropped.
    pub loss: u8,
    /// Percent of the messages delivered twice.
    pub dup: u8,
    /// Up to 60 ms more per message, in any order.
    pub reorder: bool,
}

/// What the network did to the messages, for the fault count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Messages dropped by a lossy network (not those a cut link dropped).
    pub lost: u64,
    /// Copies delivered.
    pub duplicated: u64,
    /// Messages delayed past a tick by a slow network.
    pub slowed: u64,
    /// Messages that arrive before one sent earlier on their link.
    pub reordered: u64,
}

impl Tally {
    /// All of them.
    pub fn total(&self) -> u64 {
        self.lost + self.duplicated + self.slowed + self.reordered
    }
}

/// The links between `n` replicas.
#[derive(Debug)]
pub struct Network {
    n: usize,
    /// `cut[from * n + to]` (0-based): the faults that cut the link from `from` to `to` now;
    /// its messages are dropped while there is one.
    cut: Vec<u32>,
    /// The latest arrival scheduled on each link, to keep a link in order.
    last: Vec<Time>,
    mode: Mode,
    tally: Tally,
    rng: Rng,
}

impl Network {
    /// A healthy network between replicas `1..=n`.
    pub fn new(n: usize, rng: Rng) -> Self {
        Network {
            n,
            cut: vec![0; n * n],
            last: vec![Time::default(); n * n],
            mode: Mode::default(),
            tally: Tally::default(),
            rng,
        }
    }

    fn link(&self, from: u64, to: u64) -> usize {
        (from as usize - 1) * self.n + (to as usize - 1)
    }

    /// Whether messages from `from` to `to` are dropped.
    pub fn is_cut(&self, from: u64, to: u64) -> bool {
        self.cut[self.link(from, to)] > 0
    }

    /// One more fault cuts the link from `from` to `to`.
    pub fn cut(&mut self, from: u64, to: u64) {
        let l = self.link(from, to);
        self.cut[l] += 1;
    }

    /// One fault less cuts the link from `from` to `to`.
    pub fn uncut(&mut self, from: u64, to: u64) {
        let l = self.link(from, to);
        self.cut[l] = self.cut[l].saturating_sub(1);
    }

    /// Restores every link and the healthy mode.
    pub fn heal(&mut self) {
        self.cut.iter_mut().for_each(|c| *c = 0);
        self.mode = Mode::default();
    }

    /// Sets the mode.
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
    }

    /// What it did so far.
    pub fn tally(&self) -> Tally {
        self.tally
    }

    /// When a message sent from `from` to `to` at `now` arrives: none (cut, or lost), one
    /// arrival, or two (a duplicate).
    pub fn route(&mut self, now: Time, from: u64, to: u64) -> Vec<Time> {
        if self.is_cut(from, to) {
            return Vec::new();
        }
        if self.mode.loss > 0 && self.rng.chance(u64::from(self.mode.loss)) {
            self.tally.lost += 1;
            return Vec::new();
        }
        let mut delay = self.rng.range(100, 2_000);
        if self.mode.slow {
            let more = self.rng.range(0, 400_000);
            self.tally.slowed += u64::from(more >= 50_000);
            delay += more;
        }
        let l = self.link(from, to);
        let mut at = now.after(delay);
        if self.mode.reorder {
            at = at.after(self.rng.range(0, 60_000));
            self.tally.reordered += u64::from(at < self.last[l]);
        } else {
            at = at.max(self.last[l]);
        }
        self.last[l] = self.last[l].max(at);
        let mut out = vec![at];
        if self.mode.dup > 0 && self.rng.chance(u64::from(self.mode.dup)) {
            self.tally.duplicated += 1;
            out.push(at.after(self.rng.range(0, 100_000)));
        }
        out
    }
}
