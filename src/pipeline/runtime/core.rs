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
        // At most one more than was woken: a queue that repeats a unit fails, not hangs.
        std::iter::from_fn(|| core.pop_ready()).take(7).collect()
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

    /// A core of `n` units of latency 1, named U[u].
    fn core(n: u32) -> Core {
        Core::new((0..n).map(|u| (format!("U[{u}]"), 1)).collect())
    }

    /// The units `core` runs, in order, until its queue is empty (at most 8).
    fn drain(core: &Core) -> Vec<u32> {
        std::iter::from_fn(|| core.pop_ready()).take(8).collect()
    }

    #[test]
    fn a_unit_is_queued_once_and_a_finished_one_never() {
        let c = core(3);
        c.wake(1);
        c.wake(1);
        c.slots[2].wait.set(Wait::Done);
        c.wake(2);
        assert_eq!(drain(&c), [1]);
        assert_eq!(c.pop_ready(), None);
        // Once popped, it can be woken again.
        c.wake(1);
        assert_eq!(drain(&c), [1]);
    }

    #[test]
    fn a_held_item_requeues_its_unit_once_at_its_arrival() {
        let c = core(2);
        c.slots[1].now.set(Cycle(3));
        c.wake(1);
        // Parked holding an item at 9: queued again at key 9, after unit 1's wake at 3 was
        // taken, and only once for the same arrival.
        assert_eq!(c.pop_ready(), Some(1));
        c.park_input(1, Some(Cycle(9)));
        c.park_input(1, Some(Cycle(9)));
        c.slots[0].now.set(Cycle(5));
        c.wake(0);
        assert_eq!(drain(&c), [0, 1]);
        c.park_input(1, Some(Cycle(9)));
        assert!(drain(&c).is_empty(), "not again for the same arrival");
        assert_eq!(
            c.slots[1].wait.get(),
            Wait::Input {
                held: Some(Cycle(9))
            }
        );
        // A later arrival is speculated on once more; a queued unit is not queued twice.
        c.wake(1);
        c.park_input(1, Some(Cycle(12)));
        assert_eq!(drain(&c), [1]);
    }

    #[test]
    fn a_go_ahead_reaches_only_the_unit_holding_that_item() {
        let c = core(2);
        c.park_input(0, Some(Cycle(4)));
        assert_eq!(drain(&c), [0]);
        c.go_ahead(0, Cycle(5));
        assert_eq!((c.slots[0].go.get(), drain(&c)), (None, vec![]));
        c.go_ahead(0, Cycle(4));
        assert_eq!((c.slots[0].go.get(), drain(&c)), (Some(Cycle(4)), vec![0]));
        c.go_ahead(1, Cycle(4));
        assert_eq!((c.slots[1].go.get(), drain(&c)), (None, vec![]));
    }

    /// An input link for the bound recursion with fixed answers.
    struct Fixed {
        arrival: Cycle,
        end: Cycle,
        snap: InputSnap,
    }

    impl InputView for Fixed {
        fn next_arrival(&self, _: &Core) -> Cycle {
            self.arrival
        }
        fn end_bound(&self, _: &Core) -> Cycle {
            self.end
        }
        fn producer_name(&self) -> &str {
            "P"
        }
        fn snap(&self) -> InputSnap {
            self.snap.clone()
        }
    }

    fn fixed(arrival: u64, end: u64, producer: usize) -> std::rc::Rc<Fixed> {
        std::rc::Rc::new(Fixed {
            arrival: Cycle(arrival),
            end: Cycle(end),
            snap: InputSnap {
                producer,
                ..input(0, 1, Some(arrival), 0)
            },
        })
    }

    #[test]
    fn a_units_end_bound_is_its_clock_or_its_last_inputs_end() {
        let c = core(3);
        c.slots[0].now.set(Cycle(10));
        for (u, end) in [(0, 7), (0, 25), (1, 4)] {
            c.slots[u].inputs.borrow_mut().push(fixed(0, end, 2));
        }
        c.slots[1].now.set(Cycle(6));
        c.next_step();
        assert_eq!(c.end_bound(0), Cycle(25), "the last input's end");
        assert_eq!(c.end_bound(1), Cycle(6), "its clock, past its input's end");
        assert_eq!(c.end_bound(2), Cycle::ZERO, "no input: its clock");
        // A finished unit ended its outputs at its clock, whatever its inputs.
        c.slots[0].wait.set(Wait::Done);
        c.next_step();
        assert_eq!(
            c.end_bound(0),
            Cycle(25),
            "never below the bound given before"
        );
        c.slots[0].now.set(Cycle(30));
        c.next_step();
        assert_eq!(c.end_bound(0), Cycle(30));
        let fresh = core(1);
        fresh.slots[0].inputs.borrow_mut().push(fixed(0, 25, 2));
        fresh.slots[0].now.set(Cycle(10));
        fresh.slots[0].wait.set(Wait::Done);
        assert_eq!(fresh.end_bound(0), Cycle(10), "finished: its clock alone");
    }

    #[test]
    fn a_snapshot_holds_each_units_state_and_credits_consumer() {
        let c = core(3);
        c.slots[0].now.set(Cycle(8));
        c.slots[0].wait.set(Wait::Credit { port: 1 });
        c.slots[0]
            .consumers
            .borrow_mut()
            .extend([(5, "A".into()), (9, "B".into())]);
        c.slots[1].wait.set(Wait::Input {
            held: Some(Cycle(3)),
        });
        c.slots[1].inputs.borrow_mut().push(fixed(3, 0, 7));
        c.slots[1].consumers.borrow_mut().push((4, "C".into()));
        c.slots[2].pushes_at_end.set(true);
        let snaps = c.snapshot(&[20, 21, 22]);
        let got: Vec<_> = snaps
            .iter()
            .map(|s| {
                (
                    s.unit,
                    s.now,
                    s.wait,
                    s.credit_from,
                    s.pushes_at_end,
                    s.inputs.len(),
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (20, Cycle(8), Wait::Credit { port: 1 }, Some(9), false, 0),
                (
                    21,
                    Cycle::ZERO,
                    Wait::Input {
                        held: Some(Cycle(3))
                    },
                    None,
                    false,
                    1
                ),
                (22, Cycle::ZERO, Wait::Runnable, None, true, 0),
            ]
        );
        assert_eq!(
            (snaps[1].inputs[0].producer, snaps[1].inputs[0].head),
            (7, Some(Cycle(3)))
        );
    }

    #[test]
    fn clearing_a_core_drops_its_links() {
        let c = core(2);
        let link = fixed(0, 0, 1);
        c.slots[0].inputs.borrow_mut().push(link.clone());
        assert_eq!(std::rc::Rc::strong_count(&link), 2);
        c.clear();
        assert_eq!(std::rc::Rc::strong_count(&link), 1);
    }

    /// An input link from `producer` of `latency`, its head arriving at `head` if one is
    /// queued, its last item pushed at `last_push`; not ended.
    fn input(producer: usize, latency: u64, head: Option<u64>, last_push: u64) -> InputSnap {
        InputSnap {
            producer,
            latency,
            head: head.map(Cycle),
            ended: false,
            last_push: Cycle(last_push),
            end_at: None,
        }
    }

    /// Unit `unit` at clock `now` of op latency `latency`, waiting as `wait` on `inputs`.
    fn unit(unit: usize, now: u64, latency: u64, wait: Wait, inputs: Vec<InputSnap>) -> UnitSnap {
        UnitSnap {
            unit,
            now: Cycle(now),
            latency,
            wait,
            inputs,
            credit_from: None,
            pushes_at_end: false,
        }
    }

    fn holding(a: u64) -> Wait {
        Wait::Input {
            held: Some(Cycle(a)),
        }
    }

    /// Unit 1 holds an item arriving at `a` on port `port`; its other port is fed by unit 0
    /// (`producer`) over a link of latency 1. Unit 3, the held item's producer, is in no
    /// snapshot while unit 4 is (so unit 3's place is empty).
    fn held_against(producer: UnitSnap, a: u64, port: usize) -> Vec<UnitSnap> {
        let mut inputs = vec![input(3, 1, Some(a), 0), input(0, 1, None, 0)];
        if port == 1 {
            inputs.reverse();
        }
        vec![
            producer,
            unit(1, 0, 1, holding(a), inputs),
            unit(4, 50, 1, Wait::Runnable, vec![]),
        ]
    }

    /// A held item goes ahead exactly when every other input's bound is past it, or at it
    /// from a later port: here the other input's bound is the runnable producer's next push
    /// (clock + latency) plus the link's latency.
    #[test]
    fn a_held_item_goes_ahead_when_every_other_input_is_bound_past_it() {
        let producer = |now| unit(0, now, 1, Wait::Runnable, vec![]);
        let go = |now, port| recover(&held_against(producer(now), 10, port));
        assert_eq!(go(9, 0), [(1, Cycle(10))], "bound 11, past 10");
        assert_eq!(go(8, 0), [(1, Cycle(10))], "bound 10 from a later port");
        assert_eq!(go(8, 1), [], "bound 10 from an earlier port");
        assert_eq!(go(7, 0), [], "bound 9, before 10");
        // A finished producer pushes nothing more.
        let done = unit(0, 0, 1, Wait::Done, vec![]);
        assert_eq!(recover(&held_against(done, 10, 0)), [(1, Cycle(10))]);
        // Without a held item, nothing goes ahead.
        let mut snaps = held_against(producer(9), 10, 0);
        snaps[1].wait = Wait::Input { held: None };
        assert!(recover(&snaps).is_empty());
    }

    /// A producer waiting for input pushes next at its input's next arrival plus its
    /// latency; once all its inputs ended, at its clock plus its latency.
    #[test]
    fn a_producer_waiting_for_input_is_bound_by_its_next_arrival() {
        let waiting = |head: Option<u64>, ended: bool| {
            let feed = InputSnap {
                ended,
                ..input(3, 1, head, 0)
            };
            unit(0, 0, 1, Wait::Input { held: None }, vec![feed])
        };
        // Arrival 50: bound 50 + 1 + 1.
        assert_eq!(recover(&held_against(waiting(Some(50), false), 52, 1)), []);
        assert_eq!(
            recover(&held_against(waiting(Some(50), false), 52, 0)),
            [(1, Cycle(52))]
        );
        // Ended: bound 0 + 1 + 1.
        assert_eq!(
            recover(&held_against(waiting(None, true), 2, 0)),
            [(1, Cycle(2))]
        );
        assert_eq!(recover(&held_against(waiting(None, true), 3, 0)), []);
    }

    /// A producer that pushes at the end of its inputs is bound by when their ends reach it,
    /// found through its own producer's inputs. Unit 0 is fed by unit 2, which holds
    /// nothing yet: its next item arrives at 30, so it pushes at 31, and unit 0 takes that at
    /// 32 and pushes at 33 (bound 34 at unit 1). But unit 2's input may end at 1 (its
    /// producer, in no snapshot, may end at once), so unit 2 may end at 1, which reaches
    /// unit 0 at 2: pushing at its inputs' end, unit 0 may push at 3 (bound 4).
    #[test]
    fn a_producer_that_pushes_at_the_end_is_bound_by_its_inputs_ends() {
        let chain = |pushes_at_end: bool, held: u64| {
            let mut p = unit(
                0,
                0,
                1,
                Wait::Input { held: None },
                vec![input(2, 1, None, 0)],
            );
            p.pushes_at_end = pushes_at_end;
            let mut snaps = held_against(p, held, 0);
            let feed = input(5, 1, Some(30), 0);
            snaps.push(unit(2, 0, 1, Wait::Input { held: None }, vec![feed]));
            recover(&snaps)
        };
        assert_eq!(chain(false, 34), [(1, Cycle(34))]);
        assert!(chain(false, 35).is_empty());
        assert_eq!(chain(true, 4), [(1, Cycle(4))]);
        assert!(chain(true, 5).is_empty(), "its end may come first");
    }

    /// Unit `u` at `now` of latency `latency`, waiting for the credit of unit `from`, with
    /// inputs `inputs`.
    fn crediting(
        u: usize,
        now: u64,
        latency: u64,
        from: usize,
        inputs: Vec<InputSnap>,
    ) -> UnitSnap {
        UnitSnap {
            credit_from: Some(from),
            ..unit(u, now, latency, Wait::Credit { port: 0 }, inputs)
        }
    }

    /// Unit 0 waits for the credit of unit 2, whose queued item from unit 0 arrives at 35
    /// (unit 2 runs at 30): the credit comes at q = 35 at the earliest, so unit 0 (latency 3)
    /// pushes at max(now + 2, q) at the earliest: 35 from clock 10 (bound 36 at unit 1),
    /// 42 from clock 40 (bound 43).
    #[test]
    fn a_producer_waiting_for_a_credit_is_bound_by_the_credit() {
        let go = |now: u64, held: u64| {
            let first = input(5, 1, Some(0), 0);
            let mut snaps = held_against(crediting(0, now, 3, 2, vec![first]), held, 0);
            snaps.push(unit(
                2,
                30,
                1,
                Wait::Runnable,
                vec![input(0, 1, Some(35), 0)],
            ));
            recover(&snaps)
        };
        assert_eq!(go(10, 36), [(1, Cycle(36))]);
        assert!(go(10, 37).is_empty());
        assert_eq!(go(40, 43), [(1, Cycle(43))]);
        assert!(go(40, 44).is_empty());
    }

    /// The bounds are iterated until they stop moving: unit 0 (clock 10, latency 3) waits
    /// for the credit of unit 2, which waits for its next input: from unit 0 itself (nothing
    /// queued) or an item at 35. Each round raises unit 0's bound by a cycle through unit
    /// 2's, until the item at 35 caps unit 2's: unit 0 then pushes at 35 (bound 36).
    #[test]
    fn the_bounds_are_iterated_to_their_fixed_point() {
        let go = |held: u64| {
            let first = input(5, 1, Some(0), 0);
            let mut snaps = held_against(crediting(0, 10, 3, 2, vec![first]), held, 0);
            let inputs = vec![input(0, 1, None, 0), input(5, 1, Some(35), 0)];
            snaps.push(unit(2, 30, 1, Wait::Input { held: None }, inputs));
            recover(&snaps)
        };
        assert_eq!(go(36), [(1, Cycle(36))]);
        assert!(go(37).is_empty());
    }

    /// Credits chain: unit 0 waits for the credit of unit 2, which waits for the credit of
    /// unit 6 (as in `a_producer_waiting_for_a_credit_is_bound_by_the_credit`: q = 35). Unit
    /// 2 (latency 3) takes its next input at 35 - 2 = 33 at the earliest, which is when its
    /// credit to unit 0 can come: unit 0 (latency 1) pushes at 33 (bound 34).
    #[test]
    fn a_credit_is_bound_by_when_its_consumer_takes_its_next_input() {
        let go = |held: u64| {
            let p2 = crediting(0, 0, 1, 2, vec![input(5, 1, Some(0), 0)]);
            let mut snaps = held_against(p2, held, 0);
            let inputs = vec![input(0, 1, None, 0), input(5, 1, Some(0), 0)];
            snaps.push(crediting(2, 10, 3, 6, inputs));
            snaps.push(unit(
                6,
                30,
                1,
                Wait::Runnable,
                vec![input(2, 1, Some(35), 0)],
            ));
            recover(&snaps)
        };
        assert_eq!(go(34), [(1, Cycle(34))]);
        assert!(go(35).is_empty());
    }
}
