//! A seeded bytes mutator over a corpus, for the CI-sized campaign: AFL-style havoc (bit
//! flips, interesting bytes and words, deletions, duplications, splices of another input)
//! plus two structure-aware moves, one for text (a number token replaced by a boundary
//! number) and one for binary frames (a little-endian length or checksum word replaced).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Bytes that change how a reader branches: ends of lines and fields, signs, digits, TOML
/// punctuation and the extremes of a byte.
const INTERESTING_BYTES: &[u8] = b"\0\n\r\t =[]\"',.-+019eE@.GTSWO#\x7f\x80\xff";

/// Numbers at the edges of what the readers accept.
const INTERESTING_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1",
    "255",
    "256",
    "257",
    "65535",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "1e308",
    "1e-320",
    "nan",
    "inf",
    "-0",
    "0.5",
    "99999999999999999999999",
];

/// 32-bit words at the edges of the log's frame fields.
const INTERESTING_WORDS: &[u32] = &[
    0,
    1,
    7,
    8,
    0x7f,
    0x80,
    0xff,
    0xffff,
    16 << 20,
    (16 << 20) + 1,
    u32::MAX,
];

/// Seeded mutations of the inputs of one corpus.
#[derive(Debug)]
pub struct Mutator {
    rng: ChaCha8Rng,
    corpus: Vec<Vec<u8>>,
}

impl Mutator {
    /// A mutator over `corpus` (which must not be empty), the same sequence for the same
    /// seed.
    pub fn new(corpus: Vec<Vec<u8>>, seed: u64) -> Self {
        assert!(!corpus.is_empty(), "a mutator needs a corpus");
        Mutator {
            rng: ChaCha8Rng::seed_from_u64(seed),
            corpus,
        }
    }

    /// The next input: a corpus entry with one to eight mutations stacked on it.
    pub fn next_input(&mut self) -> Vec<u8> {
        let base = self.rng.gen_range(0..self.corpus.len());
        let mut data = self.corpus[base].clone();
        let stack = 1 << self.rng.gen_range(0..4);
        for _ in 0..stack {
            self.mutate(&mut data);
        }
        data
    }

    fn mutate(&mut self, data: &mut Vec<u8>) {
        if data.is_empty() {
            data.push(self.pick_byte());
            return;
        }
        let at = self.rng.gen_range(0..data.len());
        match self.rng.gen_range(0..9) {
            0 => data[at] ^= 1 << self.rng.gen_range(0..8),
            1 => data[at] = self.pick_byte(),
            2 => {
                let end = (at + self.rng.gen_range(1..=16)).min(data.len());
                data.drain(at..end);
            }
            3 => {
                let end = (at + self.rng.gen_range(1..=64)).min(data.len());
                let chunk = data[at..end].to_vec();
                let to = self.rng.gen_range(0..=data.len());
                data.splice(to..to, chunk);
            }
            4 => {
                let other = &self.corpus[self.rng.gen_range(0..self.corpus.len())];
                if !other.is_empty() {
                    let from = self.rng.gen_range(0..other.len());
                    let end = (from + self.rng.gen_range(1..=256)).min(other.len());
                    let chunk = other[from..end].to_vec();
                    data.splice(at..at, chunk);
                }
            }
            5 => data.truncate(at),
            6 => self.replace_number(data, at),
            7 => self.replace_word(data, at),
            _ => self.swap_lines(data, at),
        }
    }

    fn pick_byte(&mut self) -> u8 {
        if self.rng.gen_bool(0.5) {
            INTERESTING_BYTES[self.rng.gen_range(0..INTERESTING_BYTES.len())]
        } else {
            self.rng.gen()
        }
    }

    /// Replaces the run of digits around `at` (or inserts, if there is none) by a boundary
    /// number.
    fn replace_number(&mut self, data: &mut Vec<u8>, at: usize) {
        let digit = |b: u8| b.is_ascii_digit() || b == b'.';
        let mut start = at;
        while start > 0 && digit(data[start - 1]) {
            start -= 1;
        }
        let mut end = at;
        while end < data.len() && digit(data[end]) {
            end += 1;
        }
        let number = INTERESTING_NUMBERS[self.rng.gen_range(0..INTERESTING_NUMBERS.len())];
        data.splice(start..end, number.bytes());
    }

    /// Overwrites the 4 bytes at `at` (or the last 4) with a boundary word, little-endian as
    /// the log's length and checksum fields.
    fn replace_word(&mut self, data: &mut [u8], at: usize) {
        if data.len() < 4 {
            return;
        }
        let at = at.min(data.len() - 4);
        let word = INTERESTING_WORDS[self.rng.gen_range(0..INTERESTING_WORDS.len())];
        data[at..at + 4].copy_from_slice(&word.to_le_bytes());
    }

    /// Swaps the line holding `at` with the next one (reorders header lines, keys, records).
    fn swap_lines(&mut self, data: &mut Vec<u8>, at: usize) {
        let start = data[..at]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        let Some(mid) = data[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|i| at + i + 1)
        else {
            return;
        };
        let end = data[mid..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |i| mid + i + 1);
        let mut swapped = data[mid..end].to_vec();
        if !swapped.ends_with(b"\n") {
            swapped.push(b'\n');
        }
        swapped.extend_from_slice(&data[start..mid]);
        swapped.truncate(end - start);
        data.splice(start..end, swapped);
    }
}
