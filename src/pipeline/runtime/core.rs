//! One host thread's view of the simulation: every unit it runs ([`Slot`]: the unit's
//! clock and what it waits for), the queue of runnable units ordered by local clock, and
//! the lower bounds on what a unit can still push, which the merges read instead of
//! watermark messages.
//!
//! **Bounds.** A merge may take its earliest queued item at arrival `a` only when no other
//! input can still deliver an item arriving earlier (DESIGN.md §3). With every unit's state
//! in view that is read from the producer itself, as DAM reads a sender's clock
//! (`tick_lower_bound`): a unit that can run issues its next op at or after its clock
//! `now`, so it pushes nothing before `now + latency`; one waiting for a credit pushes its
//! pending item at or after `now - 1 + latency`; one waiting for input pushes nothing
//! before `max(now, A) + latency`, where `A` is the earliest arrival on any of its inputs
//! (a queued item's, or the input's own bound plus the link's latency: recursive, up the
//! dataflow graph, memoised per step); a finished unit never pushes again. Every such
//! figure stays a valid lower bound as time goes on, so a stale one is never wrong, only
//! less useful.

use super::cycle::Cycle;
#[cfg(feature = "testkit")]
use crate::testkit::SplitMix64;
use std::cell::{Cell, RefCell};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// What a unit is doing, as its host thread's executor sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wait {
    /// Ready to run, or running.
    Runnable,
    /// Waiting for input: its merge cannot take anything yet. `held` is the arrival of the
    /// earliest item it holds but may not take (another input's bound is not past it).
    Input {
        /// Arrival of the earliest queued item \[cycle\], if any.
        held: Option<Cycle>,
    },
    /// Waiting for the credit of output `port` (its FIFO is full).
    Credit {
        /// The output port.
        port: u32,
    },
    /// Finished: its outputs have ended.
    Done,
}

/// What the bound recursion needs of a unit's input link.
pub trait InputView {
    /// The earliest cycle the next item can arrive: the head's arrival if one is queued,
    /// [`Cycle::NEVER`] once the link ended empty, else the producer's bound plus the
    /// link's latency.
    fn next_arrival(&self, core: &Core) -> Cycle;
    /// The earliest cycle the link's end can reach the consumer: when it ended plus the
    /// latency, else the producer's [`Core::end_bound`] plus the latency.
    fn end_bound(&self, core: &Core) -> Cycle;
    /// The producing unit's name (deadlock reports).
    fn producer_name(&self) -> &str;
    /// The link's state, for a recovery ([`recover`]).
    fn snap(&self) -> InputSnap;
}

/// What a recovery needs of one input link.
#[derive(Clone, Debug)]
pub struct InputSnap {
    /// The producing unit (global index).
    pub producer: usize,
    /// The link's latency \[cycles\].
    pub latency: u64,
    /// The arrival of the queued head item, if any.
    pub head: Option<Cycle>,
    /// The producer ended the link.
    pub ended: bool,
    /// The last item's push time (items come in push order).
    pub last_push: Cycle,
    /// When the producer ended it, if it did.
    pub end_at: Option<Cycle>,
}

/// What a recovery needs of one unit.
#[derive(Clone, Debug)]
pub struct UnitSnap {
    /// Global index.
    pub unit: usize,
    /// Its clock.
    pub now: Cycle,
    /// Its op latency \[cycles\].
    pub latency: u64,
    /// What it waits for.
    pub wait: Wait,
    /// Its inputs, by port.
    pub inputs: Vec<InputSnap>,
    /// When it waits for a credit: the consumer (global index) of that output.
    pub credit_from: Option<usize>,
    /// It pushes once its inputs have ended ([`Slot::pushes_at_end`]).
    pub pushes_at_end: bool,
}

/// One unit as its host thread sees it.
pub struct Slot {
    /// `Segmenter[2]`.
    pub name: String,
    /// Cycles from an op's last cycle to its output being ready (>= 1).
    pub latency: u64,
    /// The unit's local clock, as it last showed it: the unit writes it whenever it yields
    /// (and when it finishes), so every other unit and the executor read it current.
    pub now: Cell<Cycle>,
    /// What it waits for.
    pub wait: Cell<Wait>,
    /// In the ready queue.
    queued: Cell<bool>,
    /// The held arrival it was last woken for speculatively (see [`Core::park_input`]).
    speculated: Cell<Option<Cycle>>,
    /// A recovery's go-ahead: the arrival of the item it may take.
    pub go: Cell<Option<Cycle>>,
    /// Its input links, for the bound recursion.
    pub inputs: RefCell<Vec<std::rc::Rc<dyn InputView>>>,
    /// Consumers of its outputs by port: global index and name.
    pub consumers: RefCell<Vec<(usize, String)>>,
    /// (step, bound) of the last bound computed.
    memo: Cell<(u64, Cycle)>,
    /// (step, bound) of the last end bound computed ([`Core::end_bound`]).
    end_memo: Cell<(u64, Cycle)>,
    /// It may push once the end of its inputs reaches it (a ROP writing back its caches,
    /// [`super::Ctx::pushes_at_end`]): its bound then also follows its inputs' ends, which
    /// can come before any item they would carry.
    pub pushes_at_end: Cell<bool>,
}

/// The units of one host thread and its ready queue.
pub struct Core {
    /// By local index.
    pub slots: Vec<Slot>,
    /// (key, local index): the runnable unit with the smallest key runs next; the key is
    /// its clock (or a held item's arrival for a speculative wake), ties by index.
    ready: RefCell<BinaryHeap<Reverse<(Cycle, u32)>>>,
    /// Increments at every poll; bounds are memoised per step.
    step: Cell<u64>,
    /// The `perturb` test hook's generator: when set, the queue is keyed by random numbers
    /// instead of clocks (the schedule-independence tests).
    #[cfg(feature = "testkit")]
    perturb: RefCell<Option<SplitMix64>>,
}

impl Core {
    /// A core for units named `names` with the given latencies.
    pub fn new(units: Vec<(String, u64)>) -> Self {
        Core {
            slots: units
                .into_iter()
                .map(|(name, latency)| Slot {
                    name,
                    latency: latency.max(1),
                    now: Cell::new(Cycle::ZERO),
                    wait: Cell::new(Wait::Runnable),
                    queued: Cell::new(false),
                    speculated: Cell::new(None),
                    go: Cell::new(None),
                    inputs: RefCell::new(Vec::new()),
                    consumers: RefCell::new(Vec::new()),
                    memo: Cell::new((u64::MAX, Cycle::ZERO)),
                    end_memo: Cell::new((u64::MAX, Cycle::ZERO)),
                    pushes_at_end: Cell::new(false),
                })
                .collect(),
            ready: RefCell::new(BinaryHeap::new()),
            step: Cell::new(0),
            #[cfg(feature = "testkit")]
            perturb: RefCell::new(None),
        }
    }

    /// The `perturb` test hook: with a seed, units run in an order drawn at random from it
    /// instead of smallest clock first.
    #[cfg(feature = "testkit")]
    pub fn perturbed(self, seed: Option<u64>) -> Self {
        *self.perturb.borrow_mut() = seed.map(SplitMix64::new);
        self
    }

    /// The ready queue's key of a unit woken at `clock`: the clock, or under the `perturb`
    /// test hook a random number.
    fn key(&self, clock: Cycle) -> Cycle {
        #[cfg(feature = "testkit")]
        if let Some(rng) = self.perturb.borrow_mut().as_mut() {
            return Cycle(rng.next_u64());
        }
        clock
    }

    /// Queues unit `u` (no-op if queued or finished): an event it waits for happened.
    #[inline]
    pub fn wake(&self, u: u32) {
        let s = &self.slots[u as usize];
        if s.queued.get() || s.wait.get() == Wait::Done {
            return;
        }
        s.queued.set(true);
        s.speculated.set(None);
        let key = self.key(s.now.get());
        self.ready.borrow_mut().push(Reverse((key, u)));
    }

    /// Wakes `u` if it waits for input.
    #[inline]
    pub fn wake_if_input(&self, u: u32) {
        if matches!(self.slots[u as usize].wait.get(), Wait::Input { .. }) {
            self.wake(u);
        }
    }

    /// Parks `u` waiting for input. A unit holding an item at `a` is queued once more at
    /// key `a`: by the time it is the smallest key, every runnable unit's clock is at or
    /// past `a`, so their bounds usually prove the item safe. It is not requeued for the
    /// same `a` again; then a push, an end or a recovery wakes it.
    pub fn park_input(&self, u: u32, held: Option<Cycle>) {
        let s = &self.slots[u as usize];
        s.wait.set(Wait::Input { held });
        if let Some(a) = held {
            if s.speculated.get() != Some(a) && !s.queued.get() {
                s.speculated.set(Some(a));
                s.queued.set(true);
                let key = self.key(a);
                self.ready.borrow_mut().push(Reverse((key, u)));
            }
        }
    }

    /// The next unit to run, if any.
    pub fn pop_ready(&self) -> Option<u32> {
        let Reverse((_, u)) = self.ready.borrow_mut().pop()?;
        self.slots[u as usize].queued.set(false);
        Some(u)
    }

    /// Starts a new step: bounds computed before are stale from now on.
    pub fn next_step(&self) {
        self.step.set(self.step.get() + 1);
    }

    /// A lower bound on the push time of anything unit `u` pushes from now on (module
    /// doc); [`Cycle::NEVER`] once it finished.
    pub fn bound(&self, u: u32) -> Cycle {
        let s = &self.slots[u as usize];
        self.memoised(&s.memo, || {
            let now = s.now.get();
            match s.wait.get() {
                Wait::Runnable => now + s.latency,
                Wait::Credit { .. } => now + (s.latency - 1),
                Wait::Done => Cycle::NEVER,
                Wait::Input { .. } => {
                    let inputs = s.inputs.borrow();
                    let a = inputs
                        .iter()
                        .map(|i| i.next_arrival(self))
                        .min()
                        .unwrap_or(Cycle::NEVER);
                    // Every input ended: the unit runs next and may still push (a ROP writes
                    // its caches back once its inputs end), so it is bounded as a runnable one.
                    // A unit that pushes at the end of its inputs may do so before their next
                    // items: once the last end reaches it.
                    let a = match s.pushes_at_end.get() {
                        true => a.min(
                            inputs
                                .iter()
                                .map(|i| i.end_bound(self))
                                .max()
                                .unwrap_or(now),
                        ),
                        false => a,
                    };
                    match a {
                        Cycle::NEVER => now + s.latency,
                        a => a.max(now) + s.latency,
                    }
                }
            }
        })
    }

    /// `compute`'s bound memoised per step in `memo`, never below the one memoised
    /// before. While it computes, a re-entry (a mis-wired loop) reads the stale value,
    /// which is still a bound.
    fn memoised(&self, memo: &Cell<(u64, Cycle)>, compute: impl FnOnce() -> Cycle) -> Cycle {
        let (step, cached) = memo.get();
        if step == self.step.get() {
            return cached;
        }
        memo.set((self.step.get(), cached));
        let b = compute().max(cached);
        memo.set((self.step.get(), b));
        b
    }

    /// A lower bound on the cycle unit `u` ends its outputs: a unit ends them at its clock,
    /// which only grows, or when the last of its inputs' ends reached it, if later
    /// ([`super::Ctx::finish`]). Memoised per step, as [`Self::bound`].
    pub fn end_bound(&self, u: u32) -> Cycle {
        let s = &self.slots[u as usize];
        self.memoised(&s.end_memo, || {
            let now = s.now.get();
            match s.wait.get() {
                Wait::Done => now,
                _ => s
                    .inputs
                    .borrow()
                    .iter()
                    .map(|i| i.end_bound(self))
                    .max()
                    .unwrap_or(now)
                    .max(now),
            }
        })
    }

    /// Whether every unit finished.
    pub fn all_done(&self) -> bool {
        self.slots.iter().all(|s| s.wait.get() == Wait::Done)
    }

    /// Lets unit `u` take its held item at arrival `a` (a recovery proved it safe).
    pub fn go_ahead(&self, u: u32, a: Cycle) {
        let s = &self.slots[u as usize];
        if s.wait.get() == (Wait::Input { held: Some(a) }) {
            s.go.set(Some(a));
            self.wake(u);
        }
    }

    /// Every unit's state for a recovery, `global[u]` naming unit u.
    pub fn snapshot(&self, global: &[usize]) -> Vec<UnitSnap> {
        self.slots
            .iter()
            .enumerate()
            .map(|(u, s)| {
                let wait = s.wait.get();
                UnitSnap {
                    unit: global[u],
                    now: s.now.get(),
                    latency: s.latency,
                    wait,
                    inputs: s.inputs.borrow().iter().map(|i| i.snap()).collect(),
                    credit_from: match wait {
                        Wait::Credit { port } => {
                            s.consumers.borrow().get(port as usize).map(|c| c.0)
                        }
                        _ => None,
                    },
                    pushes_at_end: s.pushes_at_end.get(),
                }
            })
            .collect()
    }

    /// What every waiting unit waits for, by local index (a deadlock's report).
    pub fn describe_waiting(&self) -> Vec<(usize, String)> {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(u, s)| {
                let what = match s.wait.get() {
                    Wait::Runnable | Wait::Done => return None,
                    Wait::Credit { port } => {
                        let consumers = s.consumers.borrow();
                        let to = consumers.get(port as usize).map_or("?", |c| c.1.as_str());
                        format!("waits for a credit from {to} (its FIFO is full)")
                    }
                    Wait::Input { .. } => {
                        let inputs = s.inputs.borrow();
                        if inputs.is_empty() {
                            "waits for input but has no input link".to_string()
                        } else {
                            let names: Vec<&str> =
                                inputs.iter().map(|i| i.producer_name()).collect();
                            format!("waits for input from [{}]", names.join(", "))
                        }
                    }
                };
                Some((u, format!("{} {what}", s.name)))
            })
            .collect()
    }

    /// Drops the links the slots hold (they hold this core: a reference cycle).
    pub fn clear(&self) {
        for s in &self.slots {
            s.inputs.borrow_mut().clear();
        }
    }
}

/// A recovery at a global quiescence: every unit of every host thread waits and nothing is
/// in flight, so only a held item can be taken next. Which held items are safe, i.e. no
/// item not yet pushed can arrive before them on another input of their unit?
///
/// Chandy and Misra's rule (the earliest held item is safe) does not hold here: a unit
/// that waits for a credit q freezes only until `q - latency + 1` (the freeze is accounted
/// right after the op), so it can take its next input *before* q, and through it a credit
/// reaches further upstream, which can then push to another consumer an item arriving
/// before the earliest held one (found by the seeded random architectures). So the bounds
/// are computed again with the credit loops closed: for every unit a lower bound E on its
/// next pop and X on its next push,
///
/// ```text
///   waiting for input:   E >= max(now, A),                        X >= E + latency
///   waiting for credit q from consumer c (q >= E_c and >= the item's arrival):
///                        E >= max(now, q - latency + 1, A),       X >= min(max(now - 1 + latency, q), E + latency)
///   A = earliest arrival on an input: a queued head's, else max(last push, X_producer) + L
/// ```
///
/// iterated from E = now, X = now - 1 + latency (every iterate is a valid bound, since the
/// true times satisfy the inequalities and the right-hand sides are monotone) until they
/// stop moving. A held item is safe when every other input's bound is past it (ties by
/// port), and every safe item goes ahead. Returns (unit, arrival) of each; empty when no
/// held item could be proven safe.
pub fn recover(snaps: &[UnitSnap]) -> Vec<(usize, Cycle)> {
    let n = snaps.iter().map(|s| s.unit + 1).max().unwrap_or(0);
    let mut at = vec![usize::MAX; n];
    for (i, s) in snaps.iter().enumerate() {
        at[s.unit] = i;
    }
    let never = |c: Cycle| c == Cycle::NEVER;
    let mut e: Vec<Cycle> = snaps.iter().map(|s| s.now).collect();
    let mut x: Vec<Cycle> = snaps.iter().map(|s| s.now + (s.latency - 1)).collect();
    // A lower bound on when each unit ends its outputs (as `Core::end_bound`).
    let mut ends: Vec<Cycle> = snaps.iter().map(|s| s.now).collect();
    for (i, s) in snaps.iter().enumerate() {
        if s.wait == Wait::Done {
            e[i] = Cycle::NEVER;
            x[i] = Cycle::NEVER;
        }
    }
    let bound = |input: &InputSnap, x: &[Cycle]| -> Cycle {
        if let Some(h) = input.head {
            return h;
        }
        if input.ended {
            return Cycle::NEVER;
        }
        let p = at.get(input.producer).copied().unwrap_or(usize::MAX);
        let xp = if p == usize::MAX { Cycle::ZERO } else { x[p] };
        if never(xp) {
            return Cycle::NEVER;
        }
        input.last_push.max(xp) + input.latency
    };
    for _sweep in 0..4096 {
        let mut moved = false;
        for (i, s) in snaps.iter().enumerate() {
            let a = s
                .inputs
                .iter()
                .map(|inp| bound(inp, &x))
                .min()
                .unwrap_or(Cycle::NEVER);
            let end_in = inputs_end(s, &ends, &at);
            if s.wait != Wait::Done && end_in > ends[i] {
                ends[i] = end_in;
                moved = true;
            }
            let (ei, xi) = match s.wait {
                Wait::Done => continue,
                Wait::Runnable => (s.now, s.now + s.latency),
                // Every input ended: it runs next, and may still push (as `Core::bound`).
                Wait::Input { .. } if never(a) => (s.now, s.now + s.latency),
                Wait::Input { .. } => {
                    let ei = s.now.max(a);
                    (ei, (ei + s.latency).min(at_end(s, end_in)))
                }
                Wait::Credit { .. } => {
                    let c = s
                        .credit_from
                        .map_or(usize::MAX, |c| at.get(c).copied().unwrap_or(usize::MAX));
                    let q = if c == usize::MAX {
                        Cycle::ZERO
                    } else {
                        let head = snaps[c]
                            .inputs
                            .iter()
                            .find(|inp| inp.producer == s.unit)
                            .and_then(|inp| inp.head)
                            .unwrap_or(Cycle::ZERO);
                        e[c].max(head)
                    };
                    let ei = s.now.max(Cycle(q.0.saturating_sub(s.latency - 1))).max(a);
                    let pending = (s.now + (s.latency - 1)).max(q);
                    let later = if never(ei) { ei } else { ei + s.latency };
                    (ei, pending.min(later))
                }
            };
            if ei > e[i] {
                e[i] = ei;
                moved = true;
            }
            if xi > x[i] {
                x[i] = xi;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    safe_to_go(snaps, &|input: &InputSnap| bound(input, &x))
}

/// When the last of unit `s`'s inputs' ends can reach it, at the earliest: each ended
/// link's end, else its producer's end bound in `ends`, plus the link's latency (its clock
/// when it has none). `at[u]` is unit u's position in the snapshot.
fn inputs_end(s: &UnitSnap, ends: &[Cycle], at: &[usize]) -> Cycle {
    s.inputs
        .iter()
        .map(|inp| {
            let producer = match at.get(inp.producer).copied() {
                Some(p) if p != usize::MAX => ends[p],
                _ => Cycle::ZERO,
            };
            inp.end_at.unwrap_or(producer) + inp.latency
        })
        .max()
        .unwrap_or(s.now)
        .max(s.now)
}

/// When a unit that pushes at the end of its inputs (`s`) can push at that end, at the
/// earliest: once the last end reaches it (`end_in`), plus its latency; never for another
/// unit.
fn at_end(s: &UnitSnap, end_in: Cycle) -> Cycle {
    match s.pushes_at_end {
        true => end_in + s.latency,
        false => Cycle::NEVER,
    }
}

/// The held items that may go ahead, given each input's bound: an item every other input's
/// bound is past (ties by port), as (unit, arrival).
fn safe_to_go(snaps: &[UnitSnap], bound: &dyn Fn(&InputSnap) -> Cycle) -> Vec<(usize, Cycle)> {
    let mut go = Vec::new();
    for s in snaps {
        let Wait::Input { held: Some(a) } = s.wait else {
            continue;
        };
        let Some(port) = s
            .inputs
            .iter()
            .enumerate()
            .filter_map(|(j, inp)| inp.head.map(|h| (h, j)))
            .min()
            .map(|(_, j)| j)
        else {
            continue;
        };
        let safe = s.inputs.iter().enumerate().all(|(j, inp)| {
            inp.head.is_some() || {
                let b = bound(inp);
                b > a || (b == a && j > port)
            }
        });
        if safe {
            go.push((s.unit, a));
        }
    }
    go
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    /// The order in which `core` (six units) runs its units when each is woken at its own
    /// clock, unit u at cycle u.
    fn run_order(core: Core) -> Vec<u32> {
        for u in 0..6u32 {
            core.slots[u as usize].now.set(Cycle(u as u64));
            core.wake(u);
        }
        std::iter::from_fn(|| core.pop_ready()).collect()
    }

    /// The schedule-independence tests can only fail if the `perturb` hook does change the
    /// schedule: without a seed units run smallest clock first; with one they run in an
    /// order drawn from the seed, the same for the same seed and another for another (eight
    /// seeds, 720 orders: two alike or one the clock order would be a 1-in-20 event).
    #[test]
    fn the_perturb_hook_runs_units_in_seeded_random_orders() {
        let units = || (0..6).map(|u| (format!("U[{u}]"), 1)).collect::<Vec<_>>();
        let by_clock: Vec<u32> = (0..6).collect();
        assert_eq!(run_order(Core::new(units())), by_clock);
        assert_eq!(run_order(Core::new(units()).perturbed(None)), by_clock);
        let orders: Vec<Vec<u32>> = (1..=8)
            .map(|seed| run_order(Core::new(units()).perturbed(Some(seed))))
            .collect();
        assert_eq!(
            orders[2],
            run_order(Core::new(units()).perturbed(Some(3))),
            "the same seed, the same order"
        );
        let distinct: HashSet<&Vec<u32>> = orders.iter().collect();
        assert_eq!(distinct.len(), 8, "{orders:?}");
        assert!(!distinct.contains(&by_clock), "{orders:?}");
    }
}
