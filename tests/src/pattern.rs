//! Deterministic payloads that a sending and a receiving test process both compute.

use hnav_runtime::hash::{Fnv1a64, SplitMix64};

/// The value of element `i` of a test slice: the first SplitMix64 output seeded with `i`,
/// turned into an `f32` in `[0, 1)`, so that every element differs and a misplaced one
/// changes the checksum.
pub fn slice_value(i: usize) -> f32 {
    let x = SplitMix64::new(i as u64).next_u64();
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// FNV-1a 64 over the little-endian bytes of `values`.
pub fn checksum(values: &[f32]) -> u64 {
    let mut h = Fnv1a64::new();
    for v in values {
        h.bytes(&v.to_le_bytes());
    }
    h.finish()
}

/// The checksum of the first `len` pattern values.
pub fn expected_checksum(len: usize) -> u64 {
    let values: Vec<f32> = (0..len).map(slice_value).collect();
    checksum(&values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_changed_element_changes_the_checksum() {
        let mut v: Vec<f32> = (0..1000).map(slice_value).collect();
        let a = checksum(&v);
        assert_eq!(a, expected_checksum(1000));
        v.swap(10, 11);
        assert_ne!(checksum(&v), a);
    }
}
