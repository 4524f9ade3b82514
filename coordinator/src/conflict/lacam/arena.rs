//! The search's configurations, stored once: one arena of `n` cells (u32 each) per
//! configuration, and an open-addressing table from a configuration's hash to its index, so
//! that "was this configuration seen?" costs one hash and one comparison, and a configuration
//! costs `4 n` bytes plus 12 bytes of table (at most half full, so up to 24 on average).
//!
//! LaCAM's reference code (Kei18/lacam2, lacam3) keeps an `unordered_map<Config, HNode*>`: one
//! heap vector per configuration and one per map node. Here nothing is allocated per
//! configuration; the arena and the table grow by doubling.

/// A slot of the table: the configuration's hash and its index, [`EMPTY`] when free.
#[derive(Clone, Copy)]
struct Slot {
    hash: u64,
    index: u32,
}

const EMPTY: u32 = u32::MAX;

/// Configurations of `n` agents, each one a slice of the arena; see the [module docs](self).
pub(super) struct Configs {
    n: usize,
    cells: Vec<u32>,
    table: Vec<Slot>,
    len: usize,
}

/// The hash of a configuration: a multiply-rotate over its cells (deterministic on every
/// machine, unlike std's seeded hasher).
fn hash(config: &[u32]) -> u64 {
    let mut h = 0x243F_6A88_85A3_08D3u64 ^ config.len() as u64;
    for &c in config {
        h = (h ^ u64::from(c))
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(29);
    }
    // A final mix: the table indexes by the low bits.
    h ^= h >> 32;
    h.wrapping_mul(0xBF58_476D_1CE4_E5B9)
}

impl Configs {
    /// An empty set of configurations of `n` agents.
    pub fn new(n: usize) -> Self {
        Configs {
            n,
            cells: Vec::new(),
            table: vec![
                Slot {
                    hash: 0,
                    index: EMPTY
                };
                64
            ],
            len: 0,
        }
    }

    /// Configurations stored.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Configuration `index`.
    pub fn get(&self, index: u32) -> &[u32] {
        let at = index as usize * self.n;
        &self.cells[at..at + self.n]
    }

    /// Bytes held (arena and table), for the report.
    pub fn bytes(&self) -> usize {
        self.cells.capacity() * 4 + self.table.capacity() * std::mem::size_of::<Slot>()
    }

    /// The index of `config` if it is stored.
    pub fn find(&self, config: &[u32]) -> Option<u32> {
        let h = hash(config);
        let mask = self.table.len() - 1;
        let mut k = h as usize & mask;
        loop {
            let s = self.table[k];
            if s.index == EMPTY {
                return None;
            }
            if s.hash == h && self.get(s.index) == config {
                return Some(s.index);
            }
            k = (k + 1) & mask;
        }
    }

    /// Stores `config` (not stored yet: call [`Configs::find`] first) as the next index.
    pub fn push(&mut self, config: &[u32]) -> u32 {
        debug_assert_eq!(config.len(), self.n);
        if 2 * (self.len + 1) > self.table.len() {
            self.grow();
        }
        let index = self.len as u32;
        self.cells.extend_from_slice(config);
        self.len += 1;
        self.insert(hash(config), index);
        index
    }

    fn insert(&mut self, hash: u64, index: u32) {
        let mask = self.table.len() - 1;
        let mut k = hash as usize & mask;
        while self.table[k].index != EMPTY {
            k = (k + 1) & mask;
        }
        self.table[k] = Slot { hash, index };
    }

    fn grow(&mut self) {
        let size = self.table.len() * 2;
        let old = std::mem::replace(
            &mut self.table,
            vec![
                Slot {
                    hash: 0,
                    index: EMPTY
                };
                size
            ],
        );
        for s in old.into_iter().filter(|s| s.index != EMPTY) {
            self.insert(s.hash, s.index);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_configuration_is_found_once_and_only_its_own() {
        let mut c = Configs::new(3);
        let mut stored = Vec::new();
        for a in 0..40u32 {
            for b in 0..40u32 {
                let config = [a, b, a ^ b];
                assert_eq!(c.find(&config), None);
                stored.push(c.push(&config));
            }
        }
        assert_eq!(c.len(), 1600);
        for a in 0..40u32 {
            for b in 0..40u32 {
                let i = c.find(&[a, b, a ^ b]).expect("stored");
                assert_eq!(i, a * 40 + b);
                assert_eq!(c.get(i), &[a, b, a ^ b]);
            }
        }
        assert_eq!(c.find(&[1, 2, 4]), None);
        // Half full at most, and 4 bytes a cell in the arena.
        assert!(c.table.len() >= 2 * c.len());
        assert!(c.bytes() >= 1600 * 3 * 4);
    }

    #[test]
    fn equal_hashes_are_told_apart_by_the_cells() {
        // A table of 64 slots and many configurations: probes cross each other's runs.
        let mut c = Configs::new(1);
        for x in 0..31u32 {
            c.push(&[x * 64]);
        }
        for x in 0..31u32 {
            assert_eq!(c.find(&[x * 64]), Some(x));
            assert_eq!(c.find(&[x * 64 + 1]), None);
        }
    }
}
