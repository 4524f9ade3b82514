//! Shrinking a failing schedule ([`shrink`]): delta debugging (Zeller's `ddmin`) over its
//! events, each candidate re-run deterministically, down to a schedule from which no single
//! event can be left out without the failure going away.

/// The smallest sub-list of `items` (in their order) that `fails`, as `ddmin` finds it;
/// `items` itself must fail.
pub fn shrink<T: Clone>(items: &[T], mut fails: impl FnMut(&[T]) -> bool) -> Vec<T> {
    if fails(&[]) {
        return Vec::new();
    }
    let mut current = items.to_vec();
    let mut parts = 2;
    while current.len() >= 2 {
        let size = current.len().div_ceil(parts);
        let chunks: Vec<Vec<T>> = current.chunks(size).map(<[T]>::to_vec).collect();
        if let Some(c) = chunks.iter().find(|c| fails(c)) {
            current = c.clone();
            parts = 2;
            continue;
        }
        let complement = |k: usize| -> Vec<T> {
            chunks
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != k)
                .flat_map(|(_, c)| c.iter().cloned())
                .collect()
        };
        if let Some(c) = (0..chunks.len()).map(complement).find(|c| fails(c)) {
            current = c;
            parts = (parts - 1).max(2);
            continue;
        }
        if parts >= current.len() {
            break;
        }
        parts = (parts * 2).min(current.len());
    }
    current
}

#[cfg(test)]
mod tests {
    use super::shrink;

    #[test]
    fn finds_the_two_events_that_fail_together() {
        let items: Vec<u32> = (0..20).collect();
        let mut runs = 0;
        let min = shrink(&items, |s| {
            runs += 1;
            s.contains(&3) && s.contains(&17)
        });
        assert_eq!(min, vec![3, 17]);
        assert!(runs <= 80, "{runs} runs");
    }

    #[test]
    fn a_failure_without_events_shrinks_to_none() {
        assert!(shrink(&[1, 2, 3], |_| true).is_empty());
    }
}
