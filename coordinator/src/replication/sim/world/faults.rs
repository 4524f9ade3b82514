//! The nemesis's actions on the run, their ends, and the heal. A fault that finds nothing
//! to hit (a replica that is down already) is not counted.

use super::super::super::peer::Role;
use super::super::clock::Rate;
use super::super::disk::Fired;
use super::super::nemesis::{Action, ClockFault, NetFault, Target};
use super::super::network::Mode;
use super::{Ev, Undo, World};

impl World {
    /// The replica `t` names now (0-based): the leader of the highest term if it names the
    /// leader and there is one, else a replica picked by the time.
    fn resolve(&self, t: Target) -> usize {
        match t {
            Target::Id(id) => id as usize - 1,
            Target::Leader => self
                .nodes
                .iter()
                .enumerate()
                .filter_map(|(i, n)| match n.role()? {
                    (Role::Leader, term) => Some((term, i)),
                    _ => None,
                })
                .max()
                .map_or(
                    (self.now.as_ms() % self.nodes.len() as u64) as usize,
                    |(_, i)| i,
                ),
        }
    }

    /// Starts an episode that `undo` ends `ms` from now.
    fn episode(&mut self, ms: u64, undo: Undo) {
        self.next_episode += 1;
        let e = self.next_episode;
        self.episodes.insert(e, undo);
        self.push(self.now.after(ms * 1000), Ev::End(e));
    }

    pub(super) fn apply(&mut self, action: Action) {
        if self.healed {
            return;
        }
        let hit = match action {
            Action::Kill(t) => {
                let i = self.resolve(t);
                self.nodes[i].process.is_some() && {
                    self.crash(i, None, "killed (nemesis)");
                    true
                }
            }
            Action::Stop(t, ms) => {
                let i = self.resolve(t);
                let until = self.now.after(ms * 1000);
                self.nodes[i].stopped_until = Some(until);
                self.push(until, Ev::Restart(i));
                self.nodes[i].process.is_some() && {
                    self.note(|| format!("n{} stopped for {ms} ms (nemesis)", i + 1));
                    self.crashes += 1;
                    self.nodes[i].crash(None);
                    true
                }
            }
            Action::Pause(t, ms) => self.pause(self.resolve(t), ms),
            Action::Partition(a, b, ms) => {
                let links = a
                    .iter()
                    .flat_map(|&x| b.iter().flat_map(move |&y| [(x, y), (y, x)]))
                    .collect();
                self.cut(links, ms)
            }
            Action::Cut(a, b, ms) => {
                let (a, b) = (self.resolve(a) as u64 + 1, self.resolve(b) as u64 + 1);
                a != b && self.cut(vec![(a, b)], ms)
            }
            Action::Mute(t, ms) => {
                let x = self.resolve(t) as u64 + 1;
                let links = self.others(x).map(|y| (x, y)).collect();
                self.cut(links, ms)
            }
            Action::Deafen(t, ms) => {
                let x = self.resolve(t) as u64 + 1;
                let links = self.others(x).map(|y| (y, x)).collect();
                self.cut(links, ms)
            }
            Action::Isolate(t, ms) => {
                let x = self.resolve(t) as u64 + 1;
                let links = self.others(x).flat_map(|y| [(x, y), (y, x)]).collect();
                self.cut(links, ms)
            }
            Action::Bridge(t, ms) => {
                let x = self.resolve(t) as u64 + 1;
                let others: Vec<u64> = self.others(x).collect();
                let (a, b) = others.split_at(others.len() / 2);
                let links = a
                    .iter()
                    .flat_map(|&p| b.iter().flat_map(move |&q| [(p, q), (q, p)]))
                    .collect();
                self.cut(links, ms)
            }
            Action::Ring(ms) => {
                let n = self.nodes.len() as u64;
                let links: Vec<(u64, u64)> = (1..=n)
                    .flat_map(|x| (1..=n).map(move |y| (x, y)))
                    .filter(|&(x, y)| {
                        let d = (x + n - y) % n;
                        x != y && d != 1 && d != n - 1
                    })
                    .collect();
                !links.is_empty() && self.cut(links, ms)
            }
            Action::Net(f, ms) => {
                self.episode(ms, Undo::Net);
                self.nets.insert(self.next_episode, f);
                self.set_mode();
                true
            }
            Action::Clock(t, f) => self.clock(self.resolve(t), f),
            Action::Disk(t, fault, nth) => {
                self.nodes[self.resolve(t)].disk().arm(fault, nth);
                false // counted when it fires
            }
            Action::Power(t) => {
                let i = self.resolve(t);
                if self.nodes[i].process.is_some() {
                    self.crash(i, Some(Fired::Power), "power lost (nemesis)");
                } else {
                    self.nodes[i].crash(Some(Fired::Power));
                    self.note(|| format!("n{} power lost while down (nemesis)", i + 1));
                }
                true
            }
        };
        self.faults += u64::from(hit);
    }

    fn others(&self, x: u64) -> impl Iterator<Item = u64> {
        (1..=self.nodes.len() as u64).filter(move |&y| y != x)
    }

    fn cut(&mut self, links: Vec<(u64, u64)>, ms: u64) -> bool {
        for &(a, b) in &links {
            self.network.cut(a, b);
        }
        self.note(|| format!("links cut for {ms} ms: {links:?}"));
        self.episode(ms, Undo::Links(links));
        true
    }

    fn pause(&mut self, i: usize, ms: u64) -> bool {
        if !self.nodes[i].running() {
            return false;
        }
        self.note(|| format!("n{} paused for {ms} ms (nemesis)", i + 1));
        self.nodes[i].paused = true;
        self.nodes[i].clock.stop();
        self.episode(ms, Undo::Resume(i));
        true
    }

    fn clock(&mut self, i: usize, f: ClockFault) -> bool {
        self.note(|| format!("n{} clock {f:?} (nemesis)", i + 1));
        let (rate, ms) = match f {
            ClockFault::Jump(k) => {
                for _ in 0..k {
                    self.tick_now(i);
                }
                return self.nodes[i].running();
            }
            ClockFault::Fast(k, ms) => (Rate::Fast(k), ms),
            ClockFault::Stall(ms) => (Rate::Stalled, ms),
        };
        self.set_rate(i, rate);
        self.episode(ms, Undo::ClockNormal(i));
        true
    }

    fn set_rate(&mut self, i: usize, rate: Rate) {
        let node = &mut self.nodes[i];
        let next = node.clock.set_rate(rate, self.now);
        if !node.running() {
            node.clock.stop();
        } else if let Some(at) = next {
            self.push(at, Ev::Tick(i));
        }
    }

    fn set_mode(&mut self) {
        let mut mode = Mode::default();
        for f in self.nets.values() {
            match *f {
                NetFault::Slow => mode.slow = true,
                NetFault::Lossy(p) => mode.loss = mode.loss.max(p),
                NetFault::Dup(p) => mode.dup = mode.dup.max(p),
                NetFault::Reorder => mode.reorder = true,
            }
        }
        self.network.set_mode(mode);
    }

    /// Episode `e` ends (unless the heal ended it).
    pub(super) fn end(&mut self, e: u64) {
        let Some(undo) = self.episodes.remove(&e) else {
            return;
        };
        match undo {
            Undo::Links(links) => {
                for (a, b) in links {
                    self.network.uncut(a, b);
                }
            }
            Undo::Net => {
                self.nets.remove(&e);
                self.set_mode();
            }
            Undo::Resume(i) => self.resume(i),
            Undo::ClockNormal(i) => self.set_rate(i, Rate::Normal),
        }
    }

    /// A paused process runs again: what arrived meanwhile first, then the tick that came
    /// due (one, as the coordinator's loop ticks a late replica once).
    fn resume(&mut self, i: usize) {
        if !self.nodes[i].paused {
            return;
        }
        self.nodes[i].paused = false;
        for m in self.nodes[i].take_held() {
            self.step(i, m);
        }
        if self.nodes[i].running() {
            self.tick_now(i);
            if self.nodes[i].running() {
                if let Some(at) = self.nodes[i].clock.start(self.now) {
                    self.push(at, Ev::Tick(i));
                }
            }
        }
    }

    /// Every fault ends: links restored, the network healthy, paused processes resumed,
    /// stopped ones started, clocks normal, armed disk faults disarmed.
    pub(super) fn heal(&mut self) {
        self.note(|| "heal".to_string());
        self.healed = true;
        self.network.heal();
        self.nets.clear();
        let episodes = std::mem::take(&mut self.episodes);
        for i in 0..self.nodes.len() {
            self.nodes[i].disk().disarm();
            if self.nodes[i].clock.rate() != Rate::Normal {
                self.set_rate(i, Rate::Normal);
            }
            if self.nodes[i].stopped_until.take().is_some() {
                self.push(self.now, Ev::Restart(i));
            }
        }
        for undo in episodes.into_values() {
            if let Undo::Resume(i) = undo {
                self.resume(i);
            }
        }
    }
}
