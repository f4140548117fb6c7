//! The deterministic executor: runs the units of one host thread, always the runnable unit
//! with the smallest local clock (ties by unit index), each until it must wait.
//!
//! Units are `async fn`s; their awaits ([`super::ctx::Ctx::next_input`],
//! [`super::ctx::Ctx::emit`]) return `Pending` after recording what the unit waits for in
//! its [`super::core::Slot`], and the link operation that ends the wait (a push, an end, a
//! pop that returns the credit) queues the unit again. No waker is used: the executor
//! knows every unit's state, so it needs no general-purpose async runtime.
//!
//! **One host thread.** When no unit can run, every unit waits: a global quiescence. Then
//! the held items that are provably safe go ahead ([`super::core::recover`]); if no unit
//! holds an item, it is a true deadlock (a mis-wired graph), reported with what each unit
//! waits for. Results are the merge rule's, whatever order units run in.
//!
//! **Several host threads** (`--host-threads N`). The units are partitioned over N
//! threads, each running this executor on its share; links between threads carry the same
//! items and credits on crossbeam channels ([`super::link`]). A thread that runs out of
//! work sends what it holds, publishes each outgoing link's horizon, takes what arrived and
//! goes on; if nothing arrived it goes idle on the [`Board`]. When every thread is idle and
//! nothing is unread, the same recovery runs over all threads' held items, or the run
//! stops with the deadlock.

use super::core::{recover, Core, UnitSnap, Wait};
use super::cycle::Cycle;
use super::link::RemoteEnd;
pub use super::signal::Signal;
use std::future::Future;
use std::pin::Pin;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::Mutex;
use std::task::{Context, Poll, Waker};
use std::time::Duration;

/// How long an idle host thread sleeps before it looks again (a notification wakes it
/// sooner).
const TICK: Duration = Duration::from_millis(20);

/// A unit's body, as the executor polls it.
pub type UnitFuture<'a, F> = Pin<Box<dyn Future<Output = F> + 'a>>;

/// Per host thread, under the board's lock.
#[derive(Clone, Debug, Default)]
struct ThreadState {
    idle: bool,
    done: bool,
    /// Its units' states while it is idle.
    snap: Vec<UnitSnap>,
    /// Go-aheads for its units: (global unit, arrival).
    go: Vec<(usize, Cycle)>,
}

/// What an idle thread resumes with.
enum Resume {
    Go(Vec<(usize, Cycle)>),
    Continue,
    /// A horizon moved; the thread is still idle on the board.
    Horizon,
    Halt,
}

/// How often a run needed a recovery (host statistics; they do not change results).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Recoveries {
    /// Global quiescences resolved by a recovery.
    pub proven: u64,
    /// Quiescences where no held item could be proven safe and the earliest was taken
    /// (Chandy-Misra's rule); results may then depend on when the quiescence was reached.
    pub unproven: u64,
}

/// The go-aheads of a recovery over `snaps`: the proven ones, else the earliest held
/// item's (counted as unproven); None when no unit holds an item.
fn resolve(snaps: &[UnitSnap], stats: &mut Recoveries) -> Option<Vec<(usize, Cycle)>> {
    let go = recover(snaps);
    if !go.is_empty() {
        stats.proven += 1;
        return Some(go);
    }
    let held = |s: &UnitSnap| match s.wait {
        Wait::Input { held } => held,
        _ => None,
    };
    let a = snaps.iter().filter_map(held).min()?;
    stats.unproven += 1;
    Some(
        snaps
            .iter()
            .filter(|s| held(s) == Some(a))
            .map(|s| (s.unit, a))
            .collect(),
    )
}

/// The host threads of one run: who is idle, and the go-ahead of a recovery.
pub struct Board {
    state: Mutex<Vec<ThreadState>>,
    /// Host thread of each global unit.
    owner: Vec<usize>,
    proven: AtomicU64,
    unproven: AtomicU64,
    /// One per host thread.
    pub signals: Vec<std::sync::Arc<Signal>>,
    abort: AtomicBool,
    deadlock: AtomicBool,
}

impl Board {
    /// A board for `threads` host threads; `owner[u]` runs unit u.
    pub fn new(threads: usize, owner: Vec<usize>) -> Self {
        Board {
            state: Mutex::new(vec![ThreadState::default(); threads]),
            owner,
            proven: AtomicU64::new(0),
            unproven: AtomicU64::new(0),
            signals: (0..threads).map(|_| Default::default()).collect(),
            abort: AtomicBool::new(false),
            deadlock: AtomicBool::new(false),
        }
    }

    /// Stops every thread (a panic or a failure elsewhere).
    pub fn abort(&self) {
        self.abort.store(true, SeqCst);
        for s in &self.signals {
            s.notify();
        }
    }

    /// The recoveries over all threads.
    pub fn recoveries(&self) -> Recoveries {
        Recoveries {
            proven: self.proven.load(Relaxed),
            unproven: self.unproven.load(Relaxed),
        }
    }

    /// Whether the run stopped on a deadlock.
    pub fn deadlocked(&self) -> bool {
        self.deadlock.load(SeqCst)
    }

    /// Under the lock: at a global quiescence, the recovery or the deadlock.
    fn check_quiescence(&self, st: &mut [ThreadState]) {
        // A finished thread reads nothing more, so what is sent to it does not count.
        let quiet = st
            .iter()
            .zip(&self.signals)
            .all(|(t, s)| t.done || (t.idle && !s.dirty.load(SeqCst)));
        if !quiet || self.abort.load(SeqCst) {
            return;
        }
        let snaps: Vec<UnitSnap> = st.iter().flat_map(|t| t.snap.iter().cloned()).collect();
        let mut stats = Recoveries::default();
        match resolve(&snaps, &mut stats) {
            Some(go) => {
                self.proven.fetch_add(stats.proven, Relaxed);
                self.unproven.fetch_add(stats.unproven, Relaxed);
                for (u, a) in go {
                    let t = self.owner[u];
                    if st[t].go.is_empty() {
                        self.signals[t].notify();
                    }
                    st[t].go.push((u, a));
                }
            }
            None if st.iter().all(|t| t.done) => {}
            None => {
                self.deadlock.store(true, SeqCst);
                self.abort();
            }
        }
    }

    /// Registers thread `me` as idle with its units' states, unless something was sent to
    /// it meanwhile (then false).
    fn enter_idle(&self, me: usize, snap: Vec<UnitSnap>) -> bool {
        let mut st = self.state.lock().expect("not poisoned");
        if self.signals[me].dirty.load(SeqCst) {
            return false;
        }
        st[me].idle = true;
        st[me].snap = snap;
        self.check_quiescence(&mut st);
        true
    }

    /// Thread `me`, idle, has a unit to run again.
    fn leave_idle(&self, me: usize) {
        self.state.lock().expect("not poisoned")[me].idle = false;
    }

    /// Waits, idle, for a go-ahead, something sent, a horizon or the end of the run.
    fn wait(&self, me: usize) -> Resume {
        loop {
            {
                let mut st = self.state.lock().expect("not poisoned");
                if self.abort.load(SeqCst) {
                    st[me].idle = false;
                    return Resume::Halt;
                }
                if !st[me].go.is_empty() {
                    st[me].idle = false;
                    return Resume::Go(std::mem::take(&mut st[me].go));
                }
                if self.signals[me].dirty.load(SeqCst) {
                    st[me].idle = false;
                    return Resume::Continue;
                }
                if self.signals[me].horizon.swap(false, SeqCst) {
                    return Resume::Horizon;
                }
            }
            std::thread::park_timeout(TICK);
        }
    }

    fn done(&self, me: usize) {
        let mut st = self.state.lock().expect("not poisoned");
        st[me].done = true;
        st[me].idle = true;
        st[me].snap.clear();
        self.check_quiescence(&mut st);
    }
}

/// Why a thread's units stopped before finishing.
#[derive(Debug, PartialEq, Eq)]
pub enum Halt {
    /// Every unit waits and none holds an item: what each waits for, by global index.
    Deadlock(Vec<(usize, String)>),
    /// Another host thread stopped the run.
    Aborted,
}

/// The units one host thread runs.
pub struct HostThread<'a, F> {
    /// Their states.
    pub core: Rc<Core>,
    /// Their bodies, by local index.
    pub futures: Vec<UnitFuture<'a, F>>,
    /// Global unit index of each local one.
    pub global: Vec<usize>,
    /// This thread's halves of links to other threads.
    pub remotes: Vec<Rc<dyn RemoteEnd>>,
}

impl<F> HostThread<'_, F> {
    /// Runs every unit to its end. With a board, this is host thread `me` of several.
    /// Returns each unit's output by global index.
    pub fn run(
        mut self,
        sync: Option<(&Board, usize)>,
    ) -> Result<(Vec<(usize, F)>, Recoveries), Halt> {
        let bodies = std::mem::take(&mut self.futures);
        let result = self.run_inner(bodies, sync);
        self.core.clear();
        result
    }

    fn run_inner(
        &self,
        bodies: Vec<UnitFuture<'_, F>>,
        sync: Option<(&Board, usize)>,
    ) -> Result<(Vec<(usize, F)>, Recoveries), Halt> {
        let core = &self.core;
        let mut stats = Recoveries::default();
        let local = self.local_index();
        let go_ahead = |go: Vec<(usize, Cycle)>| {
            for (g, a) in go {
                core.go_ahead(local[g], a);
            }
        };
        let n = bodies.len();
        let mut bodies: Vec<Option<UnitFuture<'_, F>>> = bodies.into_iter().map(Some).collect();
        let mut outputs: Vec<Option<F>> = (0..n).map(|_| None).collect();
        if let Some((board, me)) = sync {
            let _ = board.signals[me].thread.set(std::thread::current());
        }
        let waker = Waker::noop();
        let mut cx = Context::from_waker(waker);
        for u in 0..n {
            core.wake(u as u32);
        }
        let mut polls = 0u32;
        loop {
            while let Some(u) = core.pop_ready() {
                let Some(body) = bodies[u as usize].as_mut() else {
                    continue;
                };
                core.next_step();
                let slot = &core.slots[u as usize];
                slot.wait.set(super::core::Wait::Runnable);
                if let Poll::Ready(out) = body.as_mut().poll(&mut cx) {
                    outputs[u as usize] = Some(out);
                    bodies[u as usize] = None;
                    slot.wait.set(super::core::Wait::Done);
                }
                polls = polls.wrapping_add(1);
                if polls.is_multiple_of(1024) {
                    if let Some((board, _)) = sync {
                        if board.abort.load(SeqCst) {
                            return Err(self.stopped(board));
                        }
                    }
                }
            }
            match sync {
                None => {
                    if core.all_done() {
                        break;
                    }
                    match resolve(&core.snapshot(&self.global), &mut stats) {
                        Some(go) => go_ahead(go),
                        None => return Err(Halt::Deadlock(self.waiting())),
                    }
                }
                Some((board, me)) => {
                    core.next_step();
                    self.flush();
                    if core.all_done() {
                        board.done(me);
                        break;
                    }
                    board.signals[me].dirty.store(false, SeqCst);
                    board.signals[me].horizon.store(false, SeqCst);
                    if self.drain() || !board.enter_idle(me, core.snapshot(&self.global)) {
                        continue;
                    }
                    loop {
                        match board.wait(me) {
                            Resume::Go(go) => go_ahead(go),
                            Resume::Continue => {}
                            Resume::Halt => return Err(self.stopped(board)),
                            Resume::Horizon => {
                                core.next_step();
                                if self.drain() {
                                    board.leave_idle(me);
                                } else {
                                    self.flush();
                                    continue;
                                }
                            }
                        }
                        break;
                    }
                }
            }
        }
        let outputs = outputs
            .into_iter()
            .enumerate()
            .map(|(u, out)| (self.global[u], out.expect("every unit finished")))
            .collect();
        Ok((outputs, stats))
    }

    /// Each unit's index on this thread, by its global index (`u32::MAX`: another
    /// thread's).
    fn local_index(&self) -> Vec<u32> {
        let mut local = Vec::new();
        for (u, &g) in self.global.iter().enumerate() {
            if local.len() <= g {
                local.resize(g + 1, u32::MAX);
            }
            local[g] = u as u32;
        }
        local
    }

    /// Sends what this thread holds for others (items, credits, horizons).
    fn flush(&self) {
        for r in &self.remotes {
            r.flush();
        }
    }

    /// Takes what others sent; whether a unit can run.
    fn drain(&self) -> bool {
        let mut woke = false;
        for r in &self.remotes {
            woke |= r.drain();
        }
        woke
    }

    fn waiting(&self) -> Vec<(usize, String)> {
        self.core
            .describe_waiting()
            .into_iter()
            .map(|(u, s)| (self.global[u], s))
            .collect()
    }

    fn stopped(&self, board: &Board) -> Halt {
        if board.deadlocked() {
            Halt::Deadlock(self.waiting())
        } else {
            Halt::Aborted
        }
    }
}
