//! Deterministic payloads that a sending and a receiving test process both compute.

/// The value of element `i` of a test slice: a cheap integer hash turned into an `f32` in
/// `[0, 1)`, so that every element differs and a misplaced one changes the checksum.
pub fn slice_value(i: usize) -> f32 {
    let mut x = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// FNV-1a 64 over the bytes of `values`.
pub fn checksum(values: &[f32]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for b in v.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
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
