//! How far a long render has got, for the person watching it: the command line draws it as
//! a progress bar on stderr (`main.rs`, when stderr is a terminal and the run has taken more
//! than a moment). Host-side only: nothing simulated reads it, so it changes no pixel, count
//! or cycle. One process-wide record: a render's stages set it in turn ([`stage`]), the
//! models add the primitives they will take ([`add_total`]) and count those they took
//! ([`advance`]); a sweep's parallel runs share it, and it shows them nothing.
//!
//! A leaf of the crate: it imports nothing of it.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The stage a render is in, and the primitives of it done and to do.
struct Progress {
    stage: Mutex<&'static str>,
    done: AtomicU64,
    total: AtomicU64,
}

static PROGRESS: Progress = Progress {
    stage: Mutex::new(""),
    done: AtomicU64::new(0),
    total: AtomicU64::new(0),
};

/// Starts stage `name` (`"timed pipeline"`), with nothing done and nothing to do yet.
pub fn stage(name: &'static str) {
    if let Ok(mut s) = PROGRESS.stage.lock() {
        *s = name;
    }
    PROGRESS.done.store(0, Ordering::Relaxed);
    PROGRESS.total.store(0, Ordering::Relaxed);
}

/// `n` more primitives for this stage to take.
pub fn add_total(n: u64) {
    PROGRESS.total.fetch_add(n, Ordering::Relaxed);
}

/// `n` primitives taken.
#[inline]
pub fn advance(n: u64) {
    PROGRESS.done.fetch_add(n, Ordering::Relaxed);
}

/// The stage, the primitives taken and the primitives to take (0: unknown).
pub fn snapshot() -> (&'static str, u64, u64) {
    let stage = PROGRESS.stage.lock().map(|s| *s).unwrap_or("");
    (
        stage,
        PROGRESS.done.load(Ordering::Relaxed),
        PROGRESS.total.load(Ordering::Relaxed),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage starts empty; totals and advances add up. (Other tests' renders share the
    /// record, so only this thread's own additions are checked, as differences.)
    #[test]
    fn a_stage_counts_what_is_added_and_taken() {
        stage("test");
        let (_, done0, total0) = snapshot();
        add_total(10);
        advance(3);
        let (_, done, total) = snapshot();
        assert!(total >= total0 + 10 && done >= done0 + 3);
    }
}
