//! How a replicated front end shares the scene's primitives (ARCHITECTURE.md, "Front
//! ends"): in batches of `batch` consecutive primitives, in submission order, batch b to
//! engine b mod count, as a GPU's front end deals batches of primitives to its geometry
//! engines. Every engine reads the same primitive stream and keeps its own batches, so no
//! engine needs another's result and no primitive is set up twice.

/// Which primitives one engine of a replicated front end takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Deal {
    index: u64,
    count: u64,
    batch: u64,
}

impl Deal {
    /// Engine `index` of `count`, dealt batches of `batch` primitives (both at least 1).
    pub fn new(index: usize, count: u32, batch: u32) -> Self {
        debug_assert!(count >= 1 && batch >= 1 && (index as u64) < count as u64);
        Deal {
            index: index as u64,
            count: count.max(1) as u64,
            batch: batch.max(1) as u64,
        }
    }

    /// Whether primitive `p` (its index in submission order) is this engine's.
    #[inline]
    pub fn takes(&self, p: u64) -> bool {
        (p / self.batch) % self.count == self.index
    }

    /// Whether any of the `len` primitives from `first` on is this engine's.
    pub fn takes_any(&self, first: u64, len: u64) -> bool {
        if len == 0 {
            return false;
        }
        let (b0, b1) = (first / self.batch, (first + len - 1) / self.batch);
        // Any `count` consecutive batches include one of every engine.
        b1 - b0 + 1 >= self.count || (b0..=b1).any(|b| b % self.count == self.index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every primitive goes to exactly one engine, in runs of `batch`, engines in turn.
    #[test]
    fn deal_gives_every_primitive_to_one_engine_in_batches() {
        for (count, batch) in [(1u32, 32u32), (4, 1), (4, 3), (3, 32), (7, 5)] {
            let deals: Vec<Deal> = (0..count as usize)
                .map(|i| Deal::new(i, count, batch))
                .collect();
            for p in 0..500u64 {
                let owners: Vec<usize> = (0..deals.len()).filter(|&i| deals[i].takes(p)).collect();
                assert_eq!(
                    owners.len(),
                    1,
                    "primitive {p}, count {count}, batch {batch}"
                );
                let want = ((p / batch as u64) % count as u64) as usize;
                assert_eq!(owners[0], want);
            }
        }
    }

    /// `takes_any` agrees with testing each primitive of the range.
    #[test]
    fn deal_takes_any_matches_takes() {
        for (count, batch) in [(1u32, 32u32), (4, 1), (4, 3), (3, 32), (7, 5)] {
            for i in 0..count as usize {
                let d = Deal::new(i, count, batch);
                for first in 0..80u64 {
                    for len in 0..40u64 {
                        let want = (first..first + len).any(|p| d.takes(p));
                        assert_eq!(d.takes_any(first, len), want, "{d:?} {first}+{len}");
                    }
                }
            }
        }
    }
}
