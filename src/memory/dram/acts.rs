//! One rank's activations: the record of its recent ACTs and the earliest cycle a new ACT
//! may take among them, by tRRD (S or L by bank group) and tFAW (at most four ACTs in any
//! tFAW window).
//!
//! A channel places a row miss's PRE and ACT as early as its request's bank allows, which
//! may be before ACTs it placed for requests decided earlier ([`super::channel`]). So an ACT
//! is checked against every recorded ACT on both sides, not only the last: it is legal
//! when it is tRRD from each and no four recorded ACTs that span less than tFAW lie
//! within tFAW of it. The record keeps the last [`HISTORY`] ACTs by cycle; an ACT is never
//! placed before the oldest kept one plus tFAW and tRRD_L, so the forgotten ones cannot
//! constrain it.

use super::timings::DramTimings;

/// How many ACTs a rank remembers: at tRRD_S of 4 cycles, 256 cycles of DDR4-2400, more
/// than any queued request waits for its bank in the check's traces.
const HISTORY: usize = 64;

/// A rank's ACT record.
#[derive(Clone, Debug, Default)]
pub(crate) struct RankActs {
    /// (cycle, bank group) of the recent ACTs, by cycle.
    acts: Vec<(u64, u32)>,
    /// The first ACT's cycle (background energy).
    pub first: Option<u64>,
}

impl RankActs {
    /// The earliest cycle at or after `earliest` where an ACT to `bank_group` is legal.
    pub(crate) fn earliest(&self, t: &DramTimings, bank_group: u32, earliest: u64) -> u64 {
        let mut act = earliest;
        if self.acts.len() == HISTORY {
            act = act.max(self.acts[0].0 + u64::from(t.tfaw.max(t.trrd_l)));
        }
        // Forbidden open intervals: tRRD around each ACT, and where a fifth ACT would join
        // four that span less than tFAW. Each jump lands at an interval's end, a lower
        // bound of the answer, so the loop ends at the earliest legal cycle.
        loop {
            let mut moved = false;
            for (i, &(cycle, bg)) in self.acts.iter().enumerate() {
                let trrd = u64::from(if bg == bank_group { t.trrd_l } else { t.trrd_s });
                if act + trrd > cycle && act < cycle + trrd {
                    act = cycle + trrd;
                    moved = true;
                }
                if let Some(&(fourth, _)) = self.acts.get(i + 3) {
                    let faw = u64::from(t.tfaw);
                    if act + faw > fourth && act < cycle + faw {
                        act = cycle + faw;
                        moved = true;
                    }
                }
            }
            if !moved {
                return act;
            }
        }
    }

    /// Records an ACT to `bank_group` at `cycle` (one [`RankActs::earliest`] allowed).
    pub(crate) fn record(&mut self, bank_group: u32, cycle: u64) {
        let at = self.acts.partition_point(|&(c, _)| c <= cycle);
        self.acts.insert(at, (cycle, bank_group));
        if self.acts.len() > HISTORY {
            self.acts.remove(0);
        }
        self.first = Some(self.first.map_or(cycle, |f| f.min(cycle)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::dram::ddr4_2400_x8;

    /// An ACT placed between two recorded ones keeps tRRD from both, and a fifth ACT
    /// waits for the tFAW window of the four before it.
    #[test]
    fn acts_keep_trrd_on_both_sides_and_tfaw() {
        let t = ddr4_2400_x8().timings;
        let (s, l, faw) = (u64::from(t.trrd_s), u64::from(t.trrd_l), u64::from(t.tfaw));
        let mut r = RankActs::default();
        r.record(0, 100);
        r.record(1, 100 + 3 * s);
        // Between them, another bank group: tRRD_S after the first, before the second.
        assert_eq!(r.earliest(&t, 2, 99), 100 + s);
        // Same group as the first: tRRD_L after it.
        assert_eq!(r.earliest(&t, 0, 100), 100 + l);
        let mut r = RankActs::default();
        for (i, bg) in [0, 1, 2, 3].into_iter().enumerate() {
            r.record(bg, 100 + i as u64 * s);
        }
        assert!(4 * s < faw, "the preset's tFAW binds five ACTs at tRRD_S");
        assert_eq!(r.earliest(&t, 0, 100 + 3 * s + 1), 100 + faw);
        // Before the four, far enough that no window holds five.
        assert_eq!(r.earliest(&t, 0, 100 - faw), 100 - faw);
    }
}
