//! A unit's timing context: its links, its clock and its counters (DESIGN.md §3).
//!
//! A unit is an `async fn` whose life is a sequence of ops. [`Ctx::next_input`] takes the
//! next input by merge order; [`Ctx::work`] spends busy cycles with no output;
//! [`Ctx::emit`] spends busy cycles and pushes one output item, on the port its boundary's
//! dispatch rule picks ([`super::dispatch`]). The awaits are where the
//! unit waits: the executor ([`super::executor`]) then runs another unit. Every cycle from
//! 0 to the unit's last op is exactly one of busy, starved (waiting for an input to
//! arrive) or blocked (a full FIFO downstream):
//!
//! - an input is accepted at max(arrival, now); the wait is *starved*;
//! - an op of c cycles issued at s is *busy* for [s, s + c); its output is ready at
//!   r = s + c - 1 + latency (pipelined: the unit issues its next op at s + c);
//! - the output is pushed at p = max(r, q_(n-D)) where q_(n-D) is the credit of the link;
//!   if p > r the unit's pipeline freezes for p - r cycles: *blocked*. The freeze is
//!   accounted right after the op (the totals are exact; a timeline shows it up to
//!   `latency` cycles early).
//!
//! Merging: a unit with several inputs takes the queued item with the smallest (arrival,
//! port), once every other input's bound proves nothing earlier can come (or a recovery
//! proved it, see [`super::core::Core::go_ahead`]).

use super::core::{Core, Wait};
use super::cycle::Cycle;
use super::dispatch::Dispatcher;
use super::link::{Rx, Tx};
use super::trace::{Recorder, State};
use std::future::Future;
use std::pin::Pin;
use std::rc::Rc;
use std::task::{Context, Poll};

/// Counters of one unit over its life, \[cycles\] unless named otherwise.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UnitStats {
    /// Cycles issuing ops.
    pub busy: u64,
    /// Cycles waiting for an input to arrive.
    pub starved: u64,
    /// Cycles frozen by a full FIFO downstream.
    pub blocked: u64,
    /// Cycle of the unit's last activity: busy + starved + blocked.
    pub end: Cycle,
    /// Items popped \[items\].
    pub items_in: u64,
    /// Items pushed \[items\].
    pub items_out: u64,
    /// Most items in any one input FIFO at once \[items\].
    pub max_fifo_occupancy: u64,
    /// Pops that broke the merge order (an item taken after a later one): always 0 unless
    /// the executor is wrong; checked on every run.
    pub out_of_order: u64,
}

/// ceil(n / d) for d >= 1, without a division when d is a power of two (the usual rates):
/// the per-item cost of a unit is often such a quotient.
#[inline(always)]
pub fn ceil_div(n: u64, d: u64) -> u64 {
    debug_assert!(d >= 1);
    if d.is_power_of_two() {
        (n >> d.trailing_zeros()) + (n & (d - 1) != 0) as u64
    } else {
        n.div_ceil(d)
    }
}

/// What a merge can do.
enum Choice {
    Take(usize, Cycle),
    Finished,
    /// Wait; with the arrival of the earliest item held, if any.
    Wait(Option<Cycle>),
}

/// The timing context of one unit: inputs, outputs, its clock and counters.
pub struct Ctx<I, O> {
    core: Rc<Core>,
    unit: u32,
    inputs: Vec<Rx<I>>,
    outputs: Vec<Tx<O>>,
    /// Which output port each item leaves by.
    dispatch: Dispatcher<O>,
    /// The port of its link to a shared unit it is a client of, if any
    /// ([`Self::emit_shared`]).
    shared: Option<usize>,
    /// Cycles from an op's last cycle to its output being ready.
    latency: u64,
    /// Its clock, shown in its slot when it yields ([`Self::publish`]).
    now: Cycle,
    /// (arrival, port) of the last item taken: the merge takes items in this order.
    last_taken: (Cycle, usize),
    /// Per input: a lower bound on its next arrival, computed when last needed. A bound
    /// stays valid as time goes on, so it is recomputed only when it cannot decide.
    horizon: Vec<Cycle>,
    /// It waited for input since its last pop (so a recovery may have let it go ahead).
    parked: bool,
    stats: UnitStats,
    trace: Option<Recorder>,
}

impl<I, O> Ctx<I, O> {
    /// The context of unit `unit` of `core`, with a timeline of up to `trace_cap` events
    /// when given, sending round-robin over all its outputs until told otherwise
    /// ([`Self::with_dispatch`]).
    pub fn new(
        core: Rc<Core>,
        unit: u32,
        inputs: Vec<Rx<I>>,
        outputs: Vec<Tx<O>>,
        trace_cap: Option<usize>,
    ) -> Self {
        let latency = core.slots[unit as usize].latency;
        let n = inputs.len();
        Ctx {
            core,
            unit,
            inputs,
            dispatch: Dispatcher::round_robin(0..outputs.len()),
            shared: None,
            outputs,
            latency,
            now: Cycle::ZERO,
            last_taken: (Cycle::ZERO, 0),
            horizon: vec![Cycle::ZERO; n],
            parked: false,
            stats: UnitStats::default(),
            trace: trace_cap.map(Recorder::new),
        }
    }

    /// Items leave by the ports `dispatch` picks (the boundary's rule, over the ports of
    /// the boundary the run's path takes).
    pub fn with_dispatch(mut self, dispatch: Dispatcher<O>) -> Self {
        self.dispatch = dispatch;
        self
    }

    /// Its link to a shared unit it is a client of leaves by output `port`
    /// ([`crate::graph::SHARED`]).
    pub fn with_shared(mut self, port: Option<usize>) -> Self {
        self.shared = port;
        self
    }

    /// Whether it has a link to a shared unit ([`Self::emit_shared`]).
    pub fn has_shared(&self) -> bool {
        self.shared.is_some()
    }

    /// The primitives per batch its consumers take when its boundary deals batches
    /// ([`crate::graph::Dispatch::Batches`]); None otherwise.
    pub fn batch(&self) -> Option<u32> {
        self.dispatch.batch()
    }

    /// The consumers its items are dispatched over.
    pub fn consumers(&self) -> usize {
        self.dispatch.consumers()
    }

    /// Which of them (by position) the next item goes to, when the rule does not depend on
    /// the item ([`Dispatcher::next_consumer`]): for what a producer models per consumer.
    pub fn next_consumer(&self) -> Option<usize> {
        self.dispatch.next_consumer()
    }

    /// Shows the unit's clock to the executor and the other units' bounds. Done whenever
    /// the unit yields: while it runs, no other unit of its host thread runs, so only its
    /// own bound recursion could read its slot, and a clock read early is still a lower
    /// bound.
    #[inline(always)]
    fn publish(&self) {
        self.core.slots[self.unit as usize].now.set(self.now);
    }

    /// The unit's clock, and the arrival of the last item it took: what a unit whose
    /// operations are shorter than a cycle needs to know whether its last one left part of
    /// a cycle free for the next (the frame-buffer port, [`crate::pipeline::units::framebuffer`]).
    pub fn clock(&self) -> (Cycle, Cycle) {
        (self.now, self.last_taken.0)
    }

    /// Spends `cycles` busy cycles with no output.
    #[inline]
    pub fn work(&mut self, cycles: u64) {
        let start = self.now;
        self.now = start + cycles;
        self.stats.busy += cycles;
        if let Some(t) = self.trace.as_mut() {
            t.record(start.0, self.now.0, State::Busy);
        }
    }

    /// Spends `cycles` (>= 1) busy cycles producing `item`, then pushes it on the port the
    /// dispatch rule picks when that FIFO has room (see the module doc for the freeze). The
    /// op is issued and, when the credit is known, the item pushed before this returns; the
    /// future then only waits for a credit not yet given.
    #[inline(always)]
    pub fn emit(&mut self, cycles: u64, item: O) -> Emit<'_, I, O> {
        let port = self.dispatch.port(&item);
        self.emit_on(port, cycles, item)
    }

    /// As [`Self::emit`], on its link to the shared unit it is a client of (a geometry
    /// fetch's read request to the DRAM controller), not by the dispatch rule.
    ///
    /// # Panics
    /// When it has no such link ([`Self::has_shared`]).
    pub fn emit_shared(&mut self, cycles: u64, item: O) -> Emit<'_, I, O> {
        let port = self.shared.expect("a link to a shared unit");
        self.emit_on(port, cycles, item)
    }

    #[inline(always)]
    fn emit_on(&mut self, port: usize, cycles: u64, item: O) -> Emit<'_, I, O> {
        debug_assert!(cycles >= 1);
        let cycles = cycles.max(1);
        let issue = self.now;
        self.work(cycles);
        let ready = issue + (cycles - 1 + self.latency);
        self.stats.items_out += 1;
        match self.outputs[port].try_push(ready, item) {
            Ok(push) => {
                self.blocked_until(ready, push);
                Emit(None)
            }
            Err(item) => Emit(Some((self, port, ready, item))),
        }
    }

    /// An output ready at `ready` was pushed at `push`: the pipeline froze in between.
    #[inline(always)]
    fn blocked_until(&mut self, ready: Cycle, push: Cycle) {
        if push > ready {
            let start = self.now;
            self.now = start + (push - ready);
            self.stats.blocked += push - ready;
            if let Some(t) = self.trace.as_mut() {
                t.record(start.0, self.now.0, State::Blocked);
            }
        }
    }

    /// The next input item in merge order, after waiting for it (starved cycles); `None`
    /// once every input has ended.
    #[inline]
    pub fn next_input(&mut self) -> NextInput<'_, I, O> {
        NextInput(self)
    }

    /// What the merge can do now: the queued item with the smallest (arrival, port), once
    /// every other input's bound proves nothing earlier can come (or a recovery did).
    #[inline(always)]
    fn choose(&mut self) -> Choice {
        if let [rx] = &self.inputs[..] {
            // One input: its head is next.
            return match rx.head() {
                Some(a) => Choice::Take(0, a),
                None if rx.finished() => Choice::Finished,
                None => Choice::Wait(None),
            };
        }
        // One pass: the earliest queued item, and the earliest cached bound of an empty
        // input (both as (cycle, port), the merge's order: ports come in increasing order,
        // so only a strictly earlier cycle displaces the one found).
        let (mut arrival, mut port) = (Cycle::NEVER, usize::MAX);
        let mut empty = (Cycle::NEVER, usize::MAX);
        for (i, (rx, &h)) in self.inputs.iter().zip(&self.horizon).enumerate() {
            let a = rx.head_or_never();
            if a != Cycle::NEVER {
                if a < arrival {
                    (arrival, port) = (a, i);
                }
            } else if h < empty.0 {
                empty = (h, i);
            }
        }
        if port == usize::MAX {
            return if self.inputs.iter().all(Rx::finished) {
                Choice::Finished
            } else {
                Choice::Wait(None)
            };
        }
        // (A go-ahead is only ever given to a parked unit.)
        if empty > (arrival, port)
            || (self.parked && self.core.slots[self.unit as usize].go.get() == Some(arrival))
        {
            return Choice::Take(port, arrival);
        }
        // Some cached bound cannot decide: recompute those (a bound only grows).
        for (j, rx) in self.inputs.iter().enumerate() {
            if (self.horizon[j], j) > (arrival, port) || rx.head().is_some() {
                continue;
            }
            self.horizon[j] = rx.next_arrival(&self.core);
            if (self.horizon[j], j) < (arrival, port) {
                return Choice::Wait(Some(arrival));
            }
        }
        Choice::Take(port, arrival)
    }

    #[inline(always)]
    fn pop(&mut self, port: usize, arrival: Cycle) -> I {
        // A recovery's go-ahead is given only to a unit parked waiting for input, and is
        // spent by its next pop.
        if self.parked {
            self.parked = false;
            self.core.slots[self.unit as usize].go.set(None);
        }
        // Every item a merge takes is the earliest (arrival, port) of all it will ever
        // take, so the taken sequence is sorted: a cheap check of the whole executor.
        if (arrival, port) < self.last_taken {
            self.stats.out_of_order += 1;
        }
        self.last_taken = (arrival, port);
        if arrival > self.now {
            self.stats.starved += arrival - self.now;
            self.now = arrival;
        }
        self.stats.items_in += 1;
        self.inputs[port].pop(self.now)
    }

    /// Declares that it will push once the end of its inputs reaches it
    /// ([`Self::wait_for_end_of_inputs`], then [`Self::emit`]), so that the bounds its
    /// consumers read follow its inputs' ends too. A unit that pushes after its inputs have
    /// ended must call it before it first waits for input.
    pub fn pushes_at_end(&self) {
        self.core.slots[self.unit as usize].pushes_at_end.set(true);
    }

    /// Waits (starved) until the end of its inputs reaches it: for a unit that still has
    /// work once its inputs have ended ([`Self::next_input`] returned `None`), such as a
    /// ROP writing back its caches at the end of the frame. Inputs not yet ended count
    /// from the unit's clock.
    pub fn wait_for_end_of_inputs(&mut self) {
        let end = self
            .inputs
            .iter()
            .filter_map(Rx::end_arrival)
            .max()
            .unwrap_or(self.now);
        if end > self.now {
            self.stats.starved += end - self.now;
            self.now = end;
        }
    }

    /// Ends every output and returns the unit's counters and timeline. Consumes the
    /// context: a finished unit does nothing more.
    pub fn finish(mut self) -> (UnitStats, Option<Recorder>) {
        self.publish();
        self.core.slots[self.unit as usize].wait.set(Wait::Done);
        // The end leaves after the ends of its inputs reached it (it finishes because they
        // ended), though its clock, and so its counters, stay at its last op: the dates of
        // ends then follow their causes, which a unit that pushes at the end of its inputs
        // relies on (`Core::end_bound`).
        let end = self
            .inputs
            .iter()
            .filter_map(Rx::end_arrival)
            .fold(self.now, Cycle::max);
        for tx in &self.outputs {
            tx.end(end);
        }
        let mut stats = std::mem::take(&mut self.stats);
        stats.end = self.now;
        stats.max_fifo_occupancy = self.inputs.iter().map(Rx::max_occupancy).max().unwrap_or(0);
        debug_assert_eq!(stats.busy + stats.starved + stats.blocked, stats.end.0);
        (stats, self.trace.take())
    }
}

/// The future of [`Ctx::emit`]: done, or an item waiting for the credit of its port
/// (with the cycle it was ready).
pub struct Emit<'a, I, O>(Option<(&'a mut Ctx<I, O>, usize, Cycle, O)>);

// The item is never pinned: it is moved into the FIFO by value.
impl<I, O> Unpin for Emit<'_, I, O> {}

impl<I, O> Future for Emit<'_, I, O> {
    type Output = ();

    #[inline]
    fn poll(self: Pin<&mut Self>, _: &mut Context<'_>) -> Poll<()> {
        let this = self.get_mut();
        let Some((ctx, port, _, _)) = &this.0 else {
            return Poll::Ready(());
        };
        let port = *port;
        let Some(credit) = ctx.outputs[port].credit_needed() else {
            ctx.publish();
            ctx.outputs[port].wait_credit(&ctx.core.slots[ctx.unit as usize]);
            return Poll::Pending;
        };
        let (ctx, _, ready, item) = this.0.take().expect("checked above");
        let push = ready.max(credit);
        ctx.outputs[port].push(push, item);
        ctx.blocked_until(ready, push);
        Poll::Ready(())
    }
}

/// The future of [`Ctx::next_input`].
pub struct NextInput<'a, I, O>(&'a mut Ctx<I, O>);

impl<I, O> Future for NextInput<'_, I, O> {
    type Output = Option<I>;

    #[inline(always)]
    fn poll(self: Pin<&mut Self>, _: &mut Context<'_>) -> Poll<Option<I>> {
        let ctx = &mut *self.get_mut().0;
        match ctx.choose() {
            Choice::Take(port, arrival) => Poll::Ready(Some(ctx.pop(port, arrival))),
            Choice::Finished => Poll::Ready(None),
            Choice::Wait(held) => {
                ctx.publish();
                ctx.parked = true;
                ctx.core.park_input(ctx.unit, held);
                Poll::Pending
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::runtime::link::{local_link, Ends, LinkName, LinkSpec};
    use std::task::Waker;

    /// Units 0 and 1 each feed unit 2 by a link of depth 4 and latency 1; unit 2 sends to
    /// units 3, 4 and 5 by its ports 0, 1 and 2. Returns the core, the producers' ends and
    /// unit 2's context.
    fn merge() -> (Rc<Core>, Vec<Tx<u32>>, Ctx<u32, u32>) {
        let core = Rc::new(Core::new((0..6).map(|u| (format!("U[{u}]"), 1)).collect()));
        let link = |from: u32, port: u32, to: u32| {
            local_link::<u32>(
                &core,
                LinkSpec {
                    fifo_depth: 4,
                    latency_cycles: 1,
                },
                LinkName {
                    producer: format!("U[{from}]"),
                    consumer: format!("U[{to}]"),
                },
                Ends {
                    producer: from,
                    port,
                    consumer: to,
                    from,
                },
                to as usize,
            )
        };
        let (producers, inputs): (Vec<_>, Vec<_>) =
            [link(0, 0, 2), link(1, 0, 2)].into_iter().unzip();
        let outputs = (0..3).map(|p| link(2, p, 3 + p).0).collect();
        let ctx = Ctx::new(core.clone(), 2, inputs, outputs, None);
        (core, producers, ctx)
    }

    /// One poll of `future`, as the executor's (its waker unused: a unit is woken through
    /// its slot).
    fn poll_once<F: Future + Unpin>(mut future: F) -> Poll<F::Output> {
        Pin::new(&mut future).poll(&mut Context::from_waker(Waker::noop()))
    }

    fn poll_input(ctx: &mut Ctx<u32, u32>) -> Poll<Option<u32>> {
        poll_once(ctx.next_input())
    }

    /// What a producer models per consumer reads the boundary's rule through its context:
    /// its batch, how many consumers, which one is next, whether it has a shared link.
    #[test]
    fn a_context_reports_its_dispatch_rule_and_shared_link() {
        let (core, _, ctx) = merge();
        let mut ctx = ctx
            .with_dispatch(Dispatcher::round_robin(0..2).with_batch(Some(16)))
            .with_shared(Some(2));
        assert!(ctx.has_shared());
        assert_eq!((ctx.batch(), ctx.consumers()), (Some(16), 2));
        let consumers: Vec<_> = (0..3)
            .map(|n| {
                let next = ctx.next_consumer();
                assert_eq!(poll_once(ctx.emit(1, n)), Poll::Ready(()));
                next
            })
            .collect();
        assert_eq!(consumers, [Some(0), Some(1), Some(0)]);
        let ctx = ctx
            .with_dispatch(Dispatcher::keyed(0..3, |&n: &u32| n as usize % 3))
            .with_shared(None);
        assert!(!ctx.has_shared());
        assert_eq!(
            (ctx.batch(), ctx.consumers(), ctx.next_consumer()),
            (None, 3, None)
        );
        core.clear();
    }

    /// The clock is the unit's and the arrival its last pop's; a unit that parks shows its
    /// clock to the bounds of the others (its slot).
    #[test]
    fn the_clock_follows_pops_and_work_and_is_published_on_a_wait() {
        let (core, producers, mut ctx) = merge();
        producers[0].push(Cycle(4), 7);
        producers[0].end(Cycle(4));
        producers[1].push(Cycle(6), 8);
        assert_eq!(poll_input(&mut ctx), Poll::Ready(Some(7)));
        assert_eq!(ctx.clock(), (Cycle(5), Cycle(5)));
        ctx.work(3);
        assert_eq!(ctx.clock(), (Cycle(8), Cycle(5)));
        assert_eq!(poll_input(&mut ctx), Poll::Ready(Some(8)));
        assert_eq!(ctx.clock(), (Cycle(8), Cycle(7)));
        assert_eq!(
            core.slots[2].now.get(),
            Cycle::ZERO,
            "not shown while it runs"
        );
        ctx.work(9);
        assert_eq!(poll_input(&mut ctx), Poll::Pending);
        assert_eq!(core.slots[2].now.get(), Cycle(17));
        core.clear();
    }

    /// A recovery's go-ahead lets a parked unit take the item it holds though a bound of
    /// another input still says something earlier might come; without one it waits.
    #[test]
    fn a_go_ahead_takes_the_held_item_over_an_undecided_bound() {
        let (core, producers, mut ctx) = merge();
        // Input 0 holds an item arriving at 5; input 1's producer is at cycle 0, so an item
        // of it could arrive at 2.
        producers[0].push(Cycle(4), 7);
        assert_eq!(poll_input(&mut ctx), Poll::Pending);
        assert_eq!(
            core.slots[2].wait.get(),
            Wait::Input {
                held: Some(Cycle(5))
            }
        );
        assert_eq!(poll_input(&mut ctx), Poll::Pending, "no go-ahead: it waits");
        core.go_ahead(2, Cycle(5));
        assert_eq!(poll_input(&mut ctx), Poll::Ready(Some(7)));
        assert_eq!(ctx.clock(), (Cycle(5), Cycle(5)));
        assert_eq!(core.slots[2].go.get(), None, "spent by the pop");
        core.clear();
    }

    /// Two items of one input that arrive in the same cycle are taken in merge order, not
    /// counted out of order (which fails the run), while a pop that breaks the order is
    /// counted; a unit that works past its inputs' end waits, starved, for the last end to
    /// reach it.
    #[test]
    fn items_of_one_cycle_keep_merge_order_and_the_last_end_is_waited_for() {
        let (core, producers, mut ctx) = merge();
        producers[0].push(Cycle(4), 7);
        producers[0].push(Cycle(4), 9);
        producers[0].end(Cycle(6));
        producers[1].end(Cycle(20));
        assert_eq!(poll_input(&mut ctx), Poll::Ready(Some(7)));
        assert_eq!(poll_input(&mut ctx), Poll::Ready(Some(9)));
        assert_eq!(ctx.clock(), (Cycle(5), Cycle(5)));
        assert_eq!(poll_input(&mut ctx), Poll::Ready(None));
        assert_eq!((ctx.stats.items_in, ctx.stats.out_of_order), (2, 0));
        assert_eq!(ctx.stats.starved, 5, "the first item arrives at 5");
        ctx.wait_for_end_of_inputs();
        assert_eq!(
            ctx.clock().0,
            Cycle(21),
            "input 1's end at 20, plus the latency"
        );
        assert_eq!(ctx.stats.starved, 5 + 16);
        core.clear();

        // The check itself: an item taken after a later one is counted, each time.
        let (core, producers, mut ctx) = merge();
        producers[0].push(Cycle(8), 7);
        producers[1].push(Cycle(4), 8);
        producers[1].push(Cycle(4), 9);
        assert_eq!(ctx.pop(0, Cycle(9)), 7);
        assert_eq!(ctx.pop(1, Cycle(5)), 8);
        assert_eq!(ctx.pop(1, Cycle(5)), 9);
        assert_eq!(ctx.stats.out_of_order, 1, "(5, 1) after (9, 0)");
        producers[0].push(Cycle(8), 10);
        assert_eq!(ctx.pop(0, Cycle(9)), 10);
        producers[1].push(Cycle(4), 11);
        assert_eq!(ctx.pop(1, Cycle(5)), 11);
        assert_eq!(ctx.stats.out_of_order, 2, "(5, 1) after (9, 0) again");
        core.clear();
    }

    #[test]
    fn ceil_div_matches_div_ceil() {
        for d in 1..=70u64 {
            for n in 0..300u64 {
                assert_eq!(ceil_div(n, d), n.div_ceil(d), "{n} / {d}");
            }
        }
        assert_eq!(ceil_div(u64::MAX, 64), u64::MAX.div_ceil(64));
    }
}
