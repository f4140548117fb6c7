//! How host threads wake one another: a [`Signal`] per thread, set by the links that send
//! to it (`link.rs`) and read by its executor (`executor.rs`). Its own file so that links and
//! the executor both depend on it and not on each other.

use std::sync::atomic::{AtomicBool, Ordering::SeqCst};
use std::sync::OnceLock;

/// Wakes a host thread: something was sent to it.
#[derive(Debug, Default)]
pub struct Signal {
    /// Items, an end or credits were sent: the thread is not quiescent until it read them.
    pub(super) dirty: AtomicBool,
    /// Only a horizon moved: the thread should look, but stays idle unless a unit can run
    /// (in a mis-wired loop horizons would otherwise circle forever and hide the deadlock).
    pub(super) horizon: AtomicBool,
    pub(super) thread: OnceLock<std::thread::Thread>,
}

impl Signal {
    /// Marks the thread as having something to read and unparks it.
    pub fn notify(&self) {
        self.dirty.store(true, SeqCst);
        self.unpark();
    }

    /// Tells the thread a horizon it reads moved.
    pub fn nudge(&self) {
        self.horizon.store(true, SeqCst);
        self.unpark();
    }

    fn unpark(&self) {
        if let Some(t) = self.thread.get() {
            t.unpark();
        }
    }
}
