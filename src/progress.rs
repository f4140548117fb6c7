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

impl Progress {
    const fn new() -> Self {
        Progress {
            stage: Mutex::new(""),
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
        }
    }

    fn stage(&self, name: &'static str) {
        if let Ok(mut s) = self.stage.lock() {
            *s = name;
        }
        self.done.store(0, Ordering::Relaxed);
        self.total.store(0, Ordering::Relaxed);
    }

    fn add_total(&self, n: u64) {
        self.total.fetch_add(n, Ordering::Relaxed);
    }

    #[inline]
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    fn snapshot(&self) -> (&'static str, u64, u64) {
        let stage = self.stage.lock().map(|s| *s).unwrap_or("");
        (
            stage,
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

/// The process's record.
static PROGRESS: Progress = Progress::new();

/// Starts stage `name` (`"timed pipeline"`), with nothing done and nothing to do yet.
pub fn stage(name: &'static str) {
    PROGRESS.stage(name);
}

/// `n` more primitives for this stage to take.
pub fn add_total(n: u64) {
    PROGRESS.add_total(n);
}

/// `n` primitives taken.
#[inline]
pub fn advance(n: u64) {
    PROGRESS.advance(n);
}

/// The stage, the primitives taken and the primitives to take (0: unknown).
pub fn snapshot() -> (&'static str, u64, u64) {
    PROGRESS.snapshot()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage starts empty and counts what is added and taken (on a record of its own:
    /// the process's is shared with every other test's renders).
    #[test]
    fn a_stage_counts_what_is_added_and_taken() {
        let p = Progress::new();
        p.add_total(7);
        p.advance(2);
        p.stage("test");
        assert_eq!(p.snapshot(), ("test", 0, 0));
        p.add_total(10);
        p.advance(3);
        assert_eq!(p.snapshot(), ("test", 3, 10));
    }
}
