//! Timed links: the FIFOs between units (DESIGN.md §3).
//!
//! A link is a FIFO of depth `D >= 1` and latency `L >= 1`. Item n is pushed at p_n and
//! popped at q_n, with
//!
//! ```text
//!   q_n >= p_n + L,   q_n >= q_(n-1)        (the consumer: arrival, in order)
//!   p_n >= q_(n-D)                          (the producer: a full FIFO blocks)
//! ```
//!
//! The consumer records every pop time as a *credit*; the producer reads the credit of
//! item n-D before it pushes item n. Stalls are computed in simulated time from the
//! credits, never from the host.
//!
//! A link between two units of one host thread is a plain queue shared by both ends
//! ([`LocalLink`]). A link between host threads has a half on each side
//! ([`RemoteTx`], [`RemoteRx`]) joined by two bounded crossbeam channels (item batches one
//! way, credit batches the other) and an atomic *horizon*: the producer's bound (see
//! [`super::core`]) published after its batch was sent, so the consumer's merge can
//! know an idle input's time. The producer cannot push item n before the consumer popped
//! item n-D, so at most D items and the end are ever in the item channel: host memory is
//! bounded by the FIFOs.

use super::core::{Core, InputSnap, InputView, Slot, Wait};
use super::cycle::{Cycle, Timed};
use super::signal::Signal;
use crossbeam_channel::{Receiver, Sender, TryRecvError};
use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering::Acquire, Ordering::Release};
use std::sync::Arc;

/// FIFO depth and latency of one link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkSpec {
    /// Items the FIFO holds (D >= 1).
    pub fifo_depth: u32,
    /// Cycles from push to the earliest pop (L >= 1).
    pub latency_cycles: u64,
}

/// Names of a link's ends, for deadlock reports.
#[derive(Clone, Debug)]
pub struct LinkName {
    /// The producing unit.
    pub producer: String,
    /// The consuming unit.
    pub consumer: String,
}

/// Most items per message on a link between host threads (a producer also sends whenever
/// its thread runs out of work).
pub const MAX_BATCH: usize = 64;

/// The pop times of a link's last items in a ring of a power of two >= D entries: the
/// credits the producer reads (item n - D's pop time gates push n) and the FIFO's
/// occupancy. After push n the FIFO holds item n and every earlier item popped after p_n;
/// pop times are non-decreasing, so whether it held more than the most so far is one
/// look at a pop time.
#[derive(Debug)]
struct PopRing {
    times: Box<[Cycle]>,
    mask: u64,
    /// Items popped so far (the index of the next).
    count: u64,
    /// Most items in the FIFO at once.
    max: u64,
}

impl PopRing {
    /// Entries of the ring for a FIFO of `depth`: a power of two, at least `depth`.
    fn capacity(depth: u32) -> usize {
        (depth as usize).next_power_of_two()
    }

    fn new(depth: u32) -> Self {
        let cap = Self::capacity(depth) as u64;
        PopRing {
            times: vec![Cycle::ZERO; cap as usize].into_boxed_slice(),
            mask: cap - 1,
            count: 0,
            max: 0,
        }
    }

    /// The next item, pushed at `pushed_at`, is popped at `q`.
    #[inline]
    fn pop(&mut self, pushed_at: Cycle, q: Cycle) {
        // After push n the FIFO held 1 + n - f items, f the first earlier item popped
        // after p_n (pop times are sorted). f never moves back, so that is at most one more
        // than after push n - 1: the most grows, by one, exactly when item n - max was
        // still in. One look per pop. Item n - D was out (p_n >= q_(n-D)), so the most
        // stops at D and the look stays within the ring's last D entries.
        let n = self.count;
        if self.max == 0
            || (n >= self.max && self.times[((n - self.max) & self.mask) as usize] > pushed_at)
        {
            self.max += 1;
        }
        self.record(q);
    }

    /// The next item's pop time, without the occupancy (a producer's copy of the credits).
    #[inline]
    fn record(&mut self, q: Cycle) {
        self.times[(self.count & self.mask) as usize] = q;
        self.count += 1;
    }

    /// The pop time of item m, if it was popped (m is never older than the last D).
    #[inline]
    fn get(&self, m: u64) -> Option<Cycle> {
        debug_assert!(m + self.mask + 1 >= self.count, "credit {m} overwritten");
        (m < self.count).then(|| self.times[(m & self.mask) as usize])
    }
}

/// The ends of a link: which unit and port on each side.
#[derive(Clone, Copy, Debug)]
pub struct Ends {
    /// Producer's index in its host thread's core.
    pub producer: u32,
    /// Producer's output port.
    pub port: u32,
    /// Consumer's index in its host thread's core.
    pub consumer: u32,
    /// Producer's global index.
    pub from: u32,
}

/// A link between two units of one host thread.
pub struct LocalLink<T> {
    core: Rc<Core>,
    spec: LinkSpec,
    name: LinkName,
    ends: Ends,
    fifo: FifoCell<Fifo<T>>,
    /// The queued head's arrival, [`Cycle::NEVER`] when the queue is empty: the merge reads
    /// it for every input at every item, without borrowing the queue.
    head: Cell<Cycle>,
    /// The producer waits for a credit of this link (set by [`Tx::wait_credit`]); the
    /// next pop gives it and wakes the producer.
    producer_waits: Cell<bool>,
}

/// The cell of a [`LocalLink`]'s state. Each access borrows it within one method of the
/// link and calls nothing that could reach the same link meanwhile, and a link never
/// leaves its host thread (it holds an `Rc`), so borrows never overlap: debug builds check
/// that as a `RefCell` does; release builds skip the flag, on every push and pop.
#[cfg(debug_assertions)]
type FifoCell<T> = RefCell<T>;

#[cfg(not(debug_assertions))]
struct FifoCell<T>(std::cell::UnsafeCell<T>);

#[cfg(not(debug_assertions))]
impl<T> FifoCell<T> {
    fn new(value: T) -> Self {
        FifoCell(std::cell::UnsafeCell::new(value))
    }

    #[inline(always)]
    fn borrow(&self) -> &T {
        // SAFETY: see the type's doc: no mutable borrow is alive while this one is.
        unsafe { &*self.0.get() }
    }

    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    fn borrow_mut(&self) -> &mut T {
        // SAFETY: see the type's doc: no other borrow is alive while this one is.
        unsafe { &mut *self.0.get() }
    }
}

/// The state of a [`LocalLink`], under one borrow.
struct Fifo<T> {
    /// The items in the FIFO, oldest first.
    queue: VecDeque<T>,
    /// The push times of the last items, by item number in a ring as large as the pop
    /// times' (at most D items are ever in the FIFO): item n is `pushes[n & pops.mask]`.
    pushes: Box<[Cycle]>,
    pops: PopRing,
    pushed: u64,
    last_push: Cycle,
    ended: bool,
    /// When the producer ended it.
    end_at: Cycle,
}

impl<T> LocalLink<T> {
    /// A link from `ends.producer` to `ends.consumer` of `core`.
    pub fn new(core: Rc<Core>, spec: LinkSpec, name: LinkName, ends: Ends) -> Self {
        LocalLink {
            core,
            spec,
            name,
            ends,
            fifo: FifoCell::new(Fifo {
                queue: VecDeque::with_capacity(spec.fifo_depth.min(1024) as usize),
                pushes: vec![Cycle::ZERO; PopRing::capacity(spec.fifo_depth)].into_boxed_slice(),
                pops: PopRing::new(spec.fifo_depth),
                pushed: 0,
                last_push: Cycle::ZERO,
                ended: false,
                end_at: Cycle::ZERO,
            }),
            head: Cell::new(Cycle::NEVER),
            producer_waits: Cell::new(false),
        }
    }

    /// Pushes `item` at `at` into the FIFO `f` (this link's, borrowed).
    #[inline(always)]
    fn push(&self, f: &mut Fifo<T>, at: Cycle, item: T) {
        debug_assert!(at >= f.last_push && !f.ended);
        debug_assert!(
            f.pushed - f.pops.count < self.spec.fifo_depth as u64,
            "a push past the FIFO's depth"
        );
        f.last_push = at;
        let slot = (f.pushed & f.pops.mask) as usize;
        f.pushes[slot] = at;
        f.pushed += 1;
        if f.queue.is_empty() {
            self.head.set(at + self.spec.latency_cycles);
        }
        f.queue.push_back(item);
    }

    /// [`Tx::try_push`] on this link.
    #[inline(always)]
    fn try_push(&self, ready: Cycle, item: T) -> Result<Cycle, T> {
        let at = {
            let f = &mut *self.fifo.borrow_mut();
            let depth = self.spec.fifo_depth as u64;
            let credit = if f.pushed < depth {
                Cycle::ZERO
            } else {
                match f.pops.get(f.pushed - depth) {
                    Some(q) => q,
                    None => return Err(item),
                }
            };
            let at = ready.max(credit);
            self.push(f, at, item);
            at
        };
        self.core.wake_if_input(self.ends.consumer);
        Ok(at)
    }

    /// [`Rx::pop`] on this link.
    #[inline(always)]
    fn pop(&self, q: Cycle) -> T {
        let item = {
            let f = &mut *self.fifo.borrow_mut();
            let item = f.queue.pop_front().expect("caller checked");
            let n = f.pops.count;
            let pushed_at = f.pushes[(n & f.pops.mask) as usize];
            debug_assert!(q >= pushed_at + self.spec.latency_cycles);
            self.head.set(match n + 1 < f.pushed {
                true => f.pushes[((n + 1) & f.pops.mask) as usize] + self.spec.latency_cycles,
                false => Cycle::NEVER,
            });
            f.pops.pop(pushed_at, q);
            item
        };
        if self.producer_waits.replace(false) {
            debug_assert_eq!(
                self.core.slots[self.ends.producer as usize].wait.get(),
                Wait::Credit {
                    port: self.ends.port
                }
            );
            self.core.wake(self.ends.producer);
        }
        item
    }
}

/// A link between units `ends.producer` and `ends.consumer` of `core`, registered with
/// both: as the producer's next output (to unit `to`, a global index, for deadlock reports
/// and recoveries) and as the consumer's next input (for its bounds).
pub fn local_link<T: 'static>(
    core: &Rc<Core>,
    spec: LinkSpec,
    name: LinkName,
    ends: Ends,
    to: usize,
) -> (Tx<T>, Rx<T>) {
    core.slots[ends.producer as usize]
        .consumers
        .borrow_mut()
        .push((to, name.consumer.clone()));
    let link = Rc::new(LocalLink::new(core.clone(), spec, name, ends));
    core.slots[ends.consumer as usize]
        .inputs
        .borrow_mut()
        .push(link.clone());
    (Tx::Local(link.clone()), Rx::Local(link))
}

impl<T> InputView for LocalLink<T> {
    #[inline]
    fn next_arrival(&self, core: &Core) -> Cycle {
        let last_push = {
            if self.head.get() != Cycle::NEVER {
                return self.head.get();
            }
            let f = self.fifo.borrow();
            if f.ended {
                return Cycle::NEVER;
            }
            f.last_push
        };
        last_push.max(core.bound(self.ends.producer)) + self.spec.latency_cycles
    }

    fn end_bound(&self, core: &Core) -> Cycle {
        let f = self.fifo.borrow();
        let at = match f.ended {
            true => f.end_at,
            false => core.end_bound(self.ends.producer),
        };
        at + self.spec.latency_cycles
    }

    fn producer_name(&self) -> &str {
        &self.name.producer
    }

    fn snap(&self) -> InputSnap {
        let f = self.fifo.borrow();
        InputSnap {
            producer: self.ends.from as usize,
            latency: self.spec.latency_cycles,
            head: Some(self.head.get()).filter(|&h| h != Cycle::NEVER),
            ended: f.ended,
            last_push: f.last_push,
            end_at: f.ended.then_some(f.end_at),
        }
    }
}

/// A link's half on the producer's host thread when the consumer is on another.
pub struct RemoteTx<T> {
    core: Rc<Core>,
    spec: LinkSpec,
    name: LinkName,
    ends: Ends,
    data: Sender<Msg<T>>,
    credit_rx: Receiver<Vec<Cycle>>,
    horizon: Arc<AtomicU64>,
    /// The producer's end bound as last published (`Core::end_bound`).
    clock: Arc<AtomicU64>,
    /// The consumer's host thread.
    peer: Arc<Signal>,
    credits: RefCell<PopRing>,
    batch: RefCell<Vec<Timed<T>>>,
    pushed: Cell<u64>,
    last_push: Cell<Cycle>,
    published: Cell<Cycle>,
    published_clock: Cell<Cycle>,
    ended: Cell<bool>,
}

/// A link's half on the consumer's host thread when the producer is on another.
pub struct RemoteRx<T> {
    core: Rc<Core>,
    spec: LinkSpec,
    name: LinkName,
    ends: Ends,
    data: Receiver<Msg<T>>,
    credit_tx: Sender<Vec<Cycle>>,
    horizon: Arc<AtomicU64>,
    clock: Arc<AtomicU64>,
    /// The producer's host thread.
    peer: Arc<Signal>,
    queue: RefCell<VecDeque<(Cycle, Cycle, T)>>,
    pops: RefCell<PopRing>,
    pending_credits: RefCell<Vec<Cycle>>,
    /// No item will be pushed before this cycle (the last item's push or the horizon).
    bound: Cell<Cycle>,
    /// The producer's end bound as last received: it cannot end the link before.
    producer_clock: Cell<Cycle>,
    ended: Cell<bool>,
    /// When the producer ended it.
    end_at: Cell<Cycle>,
}

/// What a link between host threads carries producer → consumer.
pub enum Msg<T> {
    /// Items in push order, times non-decreasing.
    Items(Vec<Timed<T>>),
    /// The producer finished, at this cycle; no more items.
    End(Cycle),
}

/// The channels of a link between host threads, made before the threads start and moved
/// into them.
pub struct RemoteParts<T> {
    data: (Sender<Msg<T>>, Receiver<Msg<T>>),
    credits: (Sender<Vec<Cycle>>, Receiver<Vec<Cycle>>),
    horizon: Arc<AtomicU64>,
    clock: Arc<AtomicU64>,
}

impl<T> RemoteParts<T> {
    /// Channels for a link of `spec`.
    pub fn new(spec: LinkSpec) -> Self {
        let d = spec.fifo_depth as usize;
        RemoteParts {
            data: crossbeam_channel::bounded(d + 1),
            credits: crossbeam_channel::bounded(d + 1),
            horizon: Arc::new(AtomicU64::new(0)),
            clock: Arc::new(AtomicU64::new(0)),
        }
    }

    /// The producer's half.
    pub fn tx(
        &self,
        core: Rc<Core>,
        spec: LinkSpec,
        name: LinkName,
        ends: Ends,
        peer: Arc<Signal>,
    ) -> RemoteTx<T> {
        RemoteTx {
            core,
            spec,
            name,
            ends,
            data: self.data.0.clone(),
            credit_rx: self.credits.1.clone(),
            horizon: self.horizon.clone(),
            clock: self.clock.clone(),
            peer,
            credits: RefCell::new(PopRing::new(spec.fifo_depth)),
            batch: RefCell::new(Vec::with_capacity(MAX_BATCH)),
            pushed: Cell::new(0),
            last_push: Cell::new(Cycle::ZERO),
            published: Cell::new(Cycle::ZERO),
            published_clock: Cell::new(Cycle::ZERO),
            ended: Cell::new(false),
        }
    }

    /// The consumer's half.
    pub fn rx(
        &self,
        core: Rc<Core>,
        spec: LinkSpec,
        name: LinkName,
        ends: Ends,
        peer: Arc<Signal>,
    ) -> RemoteRx<T> {
        RemoteRx {
            core,
            spec,
            name,
            ends,
            data: self.data.1.clone(),
            credit_tx: self.credits.0.clone(),
            horizon: self.horizon.clone(),
            clock: self.clock.clone(),
            peer,
            queue: RefCell::new(VecDeque::new()),
            pops: RefCell::new(PopRing::new(spec.fifo_depth)),
            pending_credits: RefCell::new(Vec::new()),
            bound: Cell::new(Cycle::ZERO),
            producer_clock: Cell::new(Cycle::ZERO),
            ended: Cell::new(false),
            end_at: Cell::new(Cycle::ZERO),
        }
    }
}

impl<T> InputView for RemoteRx<T> {
    #[inline]
    fn next_arrival(&self, _: &Core) -> Cycle {
        if let Some(&(arrival, _, _)) = self.queue.borrow().front() {
            return arrival;
        }
        if self.ended.get() {
            return Cycle::NEVER;
        }
        self.bound.get() + self.spec.latency_cycles
    }

    fn end_bound(&self, _: &Core) -> Cycle {
        let at = match self.ended.get() {
            true => self.end_at.get(),
            false => self.producer_clock.get(),
        };
        at + self.spec.latency_cycles
    }

    fn producer_name(&self) -> &str {
        &self.name.producer
    }

    fn snap(&self) -> InputSnap {
        InputSnap {
            producer: self.ends.from as usize,
            latency: self.spec.latency_cycles,
            head: self.queue.borrow().front().map(|h| h.0),
            ended: self.ended.get(),
            last_push: self.bound.get(),
            end_at: self.ended.get().then(|| self.end_at.get()),
        }
    }
}

/// What a host thread does with its halves of links to other threads when it runs out of
/// work: send what it holds, take what arrived.
pub trait RemoteEnd {
    /// Sends batched items (and the horizon) or credits. Returns whether anything was sent.
    fn flush(&self) -> bool;
    /// Takes what arrived; wakes the unit it concerns. Returns whether a unit was woken.
    fn drain(&self) -> bool;
}

impl<T> RemoteTx<T> {
    fn send_batch(&self) -> bool {
        let mut batch = self.batch.borrow_mut();
        if batch.is_empty() {
            return false;
        }
        let items = std::mem::replace(&mut *batch, Vec::with_capacity(MAX_BATCH));
        // A consumer that already finished reads no more; that is not an error.
        let _ = self.data.send(Msg::Items(items));
        true
    }

    fn take_credits(&self) {
        let mut credits = self.credits.borrow_mut();
        while let Ok(batch) = self.credit_rx.try_recv() {
            for q in batch {
                credits.record(q);
            }
        }
    }
}

impl<T> RemoteEnd for RemoteTx<T> {
    fn flush(&self) -> bool {
        let sent = self.send_batch();
        let mut moved = false;
        if !self.ended.get() {
            let bound = self
                .core
                .bound(self.ends.producer)
                .max(self.last_push.get());
            if bound > self.published.get() {
                self.published.set(bound);
                self.horizon.store(bound.0, Release);
                moved = true;
            }
            let clock = self.core.end_bound(self.ends.producer);
            if clock > self.published_clock.get() {
                self.published_clock.set(clock);
                self.clock.store(clock.0, Release);
                moved = true;
            }
        }
        if sent {
            self.peer.notify();
        } else if moved {
            self.peer.nudge();
        }
        sent || moved
    }

    fn drain(&self) -> bool {
        let s = &self.core.slots[self.ends.producer as usize];
        if s.wait.get()
            != (Wait::Credit {
                port: self.ends.port,
            })
        {
            return false;
        }
        self.take_credits();
        let want = self.pushed.get() - self.spec.fifo_depth as u64;
        if self.credits.borrow().get(want).is_some() {
            self.core.wake(self.ends.producer);
            return true;
        }
        false
    }
}

impl<T> RemoteRx<T> {
    fn send_credits(&self) -> bool {
        let mut pending = self.pending_credits.borrow_mut();
        if pending.is_empty() {
            return false;
        }
        let batch = std::mem::take(&mut *pending);
        // A producer that already finished reads no more credits; that is not an error.
        let _ = self.credit_tx.send(batch);
        self.peer.notify();
        true
    }

    /// [`Rx::pop`] on this half: the credit joins the batch sent back.
    #[inline(never)]
    fn pop(&self, q: Cycle) -> T {
        let (arrival, pushed_at, item) =
            self.queue.borrow_mut().pop_front().expect("caller checked");
        debug_assert!(q >= arrival);
        self.pops.borrow_mut().pop(pushed_at, q);
        let full = {
            let mut pending = self.pending_credits.borrow_mut();
            pending.push(q);
            pending.len() >= (self.spec.fifo_depth as usize / 2).clamp(1, MAX_BATCH)
        };
        if full {
            self.send_credits();
        }
        item
    }
}

impl<T> RemoteEnd for RemoteRx<T> {
    fn flush(&self) -> bool {
        self.send_credits()
    }

    fn drain(&self) -> bool {
        if self.ended.get() {
            return false;
        }
        // The horizon first: it was stored after the items sent before it.
        let horizon = Cycle(self.horizon.load(Acquire));
        let clock = Cycle(self.clock.load(Acquire));
        let mut changed = false;
        let latency = self.spec.latency_cycles;
        loop {
            match self.data.try_recv() {
                Ok(Msg::Items(items)) => {
                    let mut queue = self.queue.borrow_mut();
                    for Timed { at, item } in items {
                        self.bound.set(at);
                        queue.push_back((at + latency, at, item));
                    }
                    changed = true;
                }
                Ok(Msg::End(at)) => {
                    self.end_at.set(at);
                    self.ended.set(true);
                    changed = true;
                    break;
                }
                Err(TryRecvError::Empty) | Err(TryRecvError::Disconnected) => break,
            }
        }
        if horizon > self.bound.get() {
            self.bound.set(horizon);
            changed = true;
        }
        if clock > self.producer_clock.get() {
            self.producer_clock.set(clock);
            changed = true;
        }
        if changed {
            self.core.wake_if_input(self.ends.consumer);
        }
        changed
    }
}

/// The producer's end of a link.
pub enum Tx<T> {
    /// Both ends on this host thread.
    Local(Rc<LocalLink<T>>),
    /// The consumer on another host thread.
    Remote(Rc<RemoteTx<T>>),
}

/// The consumer's end of a link.
pub enum Rx<T> {
    /// Both ends on this host thread.
    Local(Rc<LocalLink<T>>),
    /// The producer on another host thread.
    Remote(Rc<RemoteRx<T>>),
}

impl<T> Tx<T> {
    /// The link's name.
    pub fn name(&self) -> &LinkName {
        match self {
            Tx::Local(l) => &l.name,
            Tx::Remote(l) => &l.name,
        }
    }

    /// The pop time of the item whose credit the next push needs: `Cycle::ZERO` while the
    /// FIFO has never been full, `None` if that item has not been popped yet.
    #[inline]
    pub fn credit_needed(&self) -> Option<Cycle> {
        match self {
            Tx::Local(l) => {
                let f = l.fifo.borrow();
                let depth = l.spec.fifo_depth as u64;
                if f.pushed < depth {
                    return Some(Cycle::ZERO);
                }
                f.pops.get(f.pushed - depth)
            }
            Tx::Remote(l) => {
                let depth = l.spec.fifo_depth as u64;
                let pushed = l.pushed.get();
                if pushed < depth {
                    return Some(Cycle::ZERO);
                }
                if let Some(q) = l.credits.borrow().get(pushed - depth) {
                    return Some(q);
                }
                l.take_credits();
                l.credits.borrow().get(pushed - depth)
            }
        }
    }

    /// Pushes `item`, ready at cycle `ready`, at max(ready, the credit it needs) when that
    /// credit is known: returns the push time, or gives the item back when the item whose
    /// pop time is the credit has not been popped yet ([`Self::credit_needed`] and
    /// [`Self::push`] under one look at the FIFO).
    #[inline(always)]
    pub fn try_push(&self, ready: Cycle, item: T) -> Result<Cycle, T> {
        match self {
            Tx::Local(l) => l.try_push(ready, item),
            Tx::Remote(_) => self.try_push_remote(ready, item),
        }
    }

    /// [`Self::try_push`] on a link to another host thread (out of line: the local case is
    /// the hot one).
    #[inline(never)]
    fn try_push_remote(&self, ready: Cycle, item: T) -> Result<Cycle, T> {
        let Some(credit) = self.credit_needed() else {
            return Err(item);
        };
        let at = ready.max(credit);
        self.push(at, item);
        Ok(at)
    }

    /// The producer parks until the credit the next push needs is given: the unit's slot
    /// says so (for bounds, recoveries and reports), and a local link's next pop wakes it.
    pub fn wait_credit(&self, slot: &Slot) {
        slot.wait.set(Wait::Credit { port: self.port() });
        if let Tx::Local(l) = self {
            l.producer_waits.set(true);
        }
    }

    fn port(&self) -> u32 {
        match self {
            Tx::Local(l) => l.ends.port,
            Tx::Remote(l) => l.ends.port,
        }
    }

    /// Pushes an item at cycle `at` (the caller checked the credit); wakes the consumer
    /// if it waits for input.
    #[inline]
    pub fn push(&self, at: Cycle, item: T) {
        match self {
            Tx::Local(l) => {
                l.push(&mut *l.fifo.borrow_mut(), at, item);
                l.core.wake_if_input(l.ends.consumer);
            }
            Tx::Remote(l) => {
                debug_assert!(at >= l.last_push.get() && !l.ended.get());
                l.last_push.set(at);
                l.pushed.set(l.pushed.get() + 1);
                let full = {
                    let mut batch = l.batch.borrow_mut();
                    batch.push(Timed { at, item });
                    batch.len() >= MAX_BATCH
                };
                if full && l.send_batch() {
                    l.peer.notify();
                }
            }
        }
    }

    /// Ends the link at the producer's cycle `at`: nothing more will be pushed.
    pub fn end(&self, at: Cycle) {
        match self {
            Tx::Local(l) => {
                {
                    let f = &mut *l.fifo.borrow_mut();
                    f.ended = true;
                    f.end_at = at;
                }
                l.core.wake_if_input(l.ends.consumer);
            }
            Tx::Remote(l) => {
                if l.ended.replace(true) {
                    return;
                }
                l.send_batch();
                let _ = l.data.send(Msg::End(at));
                l.peer.notify();
            }
        }
    }
}

impl<T> Rx<T> {
    /// The link's name.
    pub fn name(&self) -> &LinkName {
        match self {
            Rx::Local(l) => &l.name,
            Rx::Remote(l) => &l.name,
        }
    }

    /// The arrival of the queued head item, if any.
    #[inline]
    pub fn head(&self) -> Option<Cycle> {
        let h = self.head_or_never();
        (h != Cycle::NEVER).then_some(h)
    }

    /// The arrival of the queued head item, [`Cycle::NEVER`] when none is queued.
    #[inline(always)]
    pub fn head_or_never(&self) -> Cycle {
        match self {
            Rx::Local(l) => l.head.get(),
            Rx::Remote(l) => l.queue.borrow().front().map_or(Cycle::NEVER, |h| h.0),
        }
    }

    /// The earliest arrival of the next item ([`InputView::next_arrival`]).
    #[inline]
    pub fn next_arrival(&self, core: &Core) -> Cycle {
        match self {
            Rx::Local(l) => l.next_arrival(core),
            Rx::Remote(l) => l.next_arrival(core),
        }
    }

    /// When the end reaches the consumer (the producer's end plus the latency), once the
    /// producer ended the link.
    pub fn end_arrival(&self) -> Option<Cycle> {
        match self {
            Rx::Local(l) => {
                let f = l.fifo.borrow();
                f.ended.then_some(f.end_at + l.spec.latency_cycles)
            }
            Rx::Remote(l) => l
                .ended
                .get()
                .then(|| l.end_at.get() + l.spec.latency_cycles),
        }
    }

    /// Whether the producer ended and every item was popped.
    pub fn finished(&self) -> bool {
        match self {
            Rx::Local(l) => {
                let f = l.fifo.borrow();
                f.ended && f.queue.is_empty()
            }
            Rx::Remote(l) => l.ended.get() && l.queue.borrow().is_empty(),
        }
    }

    /// Pops the head item at cycle `q` (>= its arrival): records the credit (waking a
    /// producer that waits for it) and the FIFO occupancy.
    #[inline(always)]
    pub fn pop(&self, q: Cycle) -> T {
        match self {
            Rx::Local(l) => l.pop(q),
            Rx::Remote(l) => l.pop(q),
        }
    }

    /// Most items ever in this FIFO at once.
    pub fn max_occupancy(&self) -> u64 {
        match self {
            Rx::Local(l) => l.fifo.borrow().pops.max,
            Rx::Remote(l) => l.pops.borrow().max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(d: u32, l: u64) -> LinkSpec {
        LinkSpec {
            fifo_depth: d,
            latency_cycles: l,
        }
    }

    fn local(d: u32, l: u64) -> (Rc<Core>, Tx<u32>, Rx<u32>) {
        let core = Rc::new(Core::new(vec![("p".into(), 1), ("c".into(), 1)]));
        let link = Rc::new(LocalLink::new(
            core.clone(),
            spec(d, l),
            LinkName {
                producer: "p".into(),
                consumer: "c".into(),
            },
            Ends {
                producer: 0,
                port: 0,
                consumer: 1,
                from: 0,
            },
        ));
        (core, Tx::Local(link.clone()), Rx::Local(link))
    }

    #[test]
    fn link_credit_of_item_n_minus_depth_gates_push_n() {
        let (core, tx, rx) = local(2, 1);
        assert_eq!(tx.credit_needed(), Some(Cycle::ZERO));
        tx.push(Cycle(0), 0);
        tx.push(Cycle(1), 1);
        // Item 2 needs the pop time of item 0, not yet recorded.
        assert_eq!(tx.credit_needed(), None);
        assert_eq!(rx.head(), Some(Cycle(1)));
        assert_eq!(tx.try_push(Cycle(2), 2), Err(2), "no credit yet");
        assert_eq!(rx.pop(Cycle(5)), 0);
        assert_eq!(tx.credit_needed(), Some(Cycle(5)));
        // The push waits for the credit, or not when it is ready later.
        assert_eq!(tx.try_push(Cycle(2), 2), Ok(Cycle(5)));
        assert_eq!(rx.pop(Cycle(6)), 1);
        assert_eq!(tx.try_push(Cycle(9), 3), Ok(Cycle(9)));
        core.clear();
    }

    #[test]
    fn link_end_bound_is_the_producers_plus_latency_until_the_end_is_pushed() {
        let (core, tx, rx) = local(2, 3);
        let Rx::Local(l) = &rx else {
            panic!("a local link");
        };
        // The producer (no inputs, clock 0) can end its outputs at cycle 0 at the earliest.
        assert_eq!(l.end_bound(&core), Cycle(3));
        assert_eq!(l.snap().head, None, "nothing queued");
        tx.push(Cycle(4), 0);
        assert_eq!(l.snap().head, Some(Cycle(7)), "the head arrives at 4 + 3");
        tx.end(Cycle(20));
        assert_eq!(l.end_bound(&core), Cycle(23));
        core.clear();
    }

    #[test]
    fn link_occupancy_counts_items_pushed_and_not_popped() {
        let (core, tx, rx) = local(4, 1);
        // Four pushes at 0..3, pops at 10..13: all four are in the FIFO at cycle 3.
        for n in 0..4 {
            tx.push(Cycle(n), n as u32);
        }
        for n in 0..4 {
            rx.pop(Cycle(10 + n));
        }
        assert_eq!(rx.max_occupancy(), 4);
        core.clear();
    }

    #[test]
    fn link_occupancy_of_a_consumer_that_keeps_up_is_one() {
        // Popped before the next push, or on the same cycle (the pop goes first).
        for gap in [1, 2] {
            let (core, tx, rx) = local(8, 1);
            for n in 0..6 {
                tx.push(Cycle(2 * n), 0);
                rx.pop(Cycle(2 * n + gap));
            }
            assert_eq!(rx.max_occupancy(), 1, "popped {gap} after its push");
            core.clear();
        }
    }

    /// The one look per pop against the definition: after push n, item n and every earlier
    /// item popped after p_n, for seeded random push and pop times obeying the link's rules.
    #[test]
    fn link_occupancy_matches_its_definition() {
        let mut rng = crate::testkit::SplitMix64::new(0x9E37_79B9_7F4A_7C15);
        let mut rnd = |m: u64| rng.below(m);
        // Small steps make pops and pushes fall on the same cycle (popped first: out).
        for (depth, push_step, pop_step) in [1u32, 2, 3, 5, 8, 16]
            .into_iter()
            .flat_map(|d| [(d, 3, 4), (d, 2, 2)])
        {
            let (core, tx, rx) = local(depth, 1);
            let (mut p, mut q) = (Vec::new(), Vec::<u64>::new());
            let mut last_q = 0;
            // The definition is quadratic in the items: fewer under Miri.
            for n in 0..if cfg!(miri) { 40 } else { 300usize } {
                let credit = if n >= depth as usize {
                    q[n - depth as usize]
                } else {
                    0
                };
                let push = p.last().copied().unwrap_or(0).max(credit) + rnd(push_step);
                p.push(push);
                tx.push(Cycle(push), 0);
                last_q = last_q.max(push + 1) + rnd(pop_step);
                q.push(last_q);
                rx.pop(Cycle(last_q));
            }
            let want = (0..p.len())
                .map(|n| 1 + (0..n).filter(|&m| q[m] > p[n]).count() as u64)
                .max()
                .unwrap();
            assert_eq!(
                rx.max_occupancy(),
                want,
                "depth {depth}, steps {push_step} {pop_step}"
            );
            core.clear();
        }
    }

    /// A link between host threads with both halves on this test thread: unit 0 of
    /// `cp` produces, unit 0 of `cc` consumes.
    struct Remote {
        cp: Rc<Core>,
        cc: Rc<Core>,
        tx_half: Rc<RemoteTx<u32>>,
        rx_half: Rc<RemoteRx<u32>>,
        tx: Tx<u32>,
        rx: Rx<u32>,
    }

    fn remote(d: u32, l: u64) -> Remote {
        let cp = Rc::new(Core::new(vec![("p".into(), 1)]));
        let cc = Rc::new(Core::new(vec![("c".into(), 1)]));
        let name = LinkName {
            producer: "p".into(),
            consumer: "c".into(),
        };
        let ends = Ends {
            producer: 0,
            port: 0,
            consumer: 0,
            from: 0,
        };
        let parts = RemoteParts::new(spec(d, l));
        let signal = Arc::new(Signal::default());
        let tx_half = Rc::new(parts.tx(cp.clone(), spec(d, l), name.clone(), ends, signal.clone()));
        let rx_half = Rc::new(parts.rx(cc.clone(), spec(d, l), name, ends, signal));
        Remote {
            tx: Tx::Remote(tx_half.clone()),
            rx: Rx::Remote(rx_half.clone()),
            cp,
            cc,
            tx_half,
            rx_half,
        }
    }

    /// Between host threads as on one: push n waits for the credit of item n - D, and the
    /// credit reaches the producer when the consumer's thread flushes, even when fewer
    /// credits are pending than a batch (a consumer whose thread ran out of work).
    #[test]
    fn remote_link_credit_of_item_n_minus_depth_gates_push_n() {
        let r = remote(4, 1);
        assert_eq!(r.tx.credit_needed(), Some(Cycle::ZERO));
        for n in 0..4 {
            r.tx.push(Cycle(n), n as u32);
        }
        // Item 4 needs the pop time of item 0, not yet popped.
        assert_eq!(r.tx.credit_needed(), None);
        assert!(!r.tx_half.drain(), "the producer waits for no credit");
        r.tx.wait_credit(&r.cp.slots[0]);
        assert!(!r.tx_half.drain(), "its credit has not come");
        // Items travel in batches: nothing arrives before the producer's thread flushes.
        assert!(!r.rx_half.drain());
        assert_eq!(r.rx.head(), None);
        r.tx_half.flush();
        assert!(r.rx_half.drain());
        assert_eq!(r.rx.head(), Some(Cycle(1)));
        assert_eq!(r.rx.pop(Cycle(10)), 0);
        // One credit pending, a batch is D/2 = 2: it waits for the consumer's flush.
        assert_eq!(r.tx.credit_needed(), None);
        assert!(r.rx_half.flush(), "a pending credit is sent");
        assert!(r.tx_half.drain(), "its credit came: the producer wakes");
        assert!(!r.rx_half.flush(), "nothing left to send");
        assert_eq!(r.tx.credit_needed(), Some(Cycle(10)));
        // Two pops fill a batch: sent at once, no flush needed.
        r.tx.push(Cycle(10), 4);
        assert_eq!(r.tx.credit_needed(), None);
        assert_eq!(r.rx.pop(Cycle(11)), 1);
        assert_eq!(r.rx.pop(Cycle(12)), 2);
        assert_eq!(r.tx.credit_needed(), Some(Cycle(11)));
        r.cp.clear();
        r.cc.clear();
    }

    /// Push n's credit is item n - D's pop time at every push, also where the credit was
    /// taken from the channel at an earlier push (the fast path).
    #[test]
    fn remote_link_credit_is_item_n_minus_depth_at_every_push() {
        let r = remote(2, 1);
        for n in 0..6 {
            let want = match n {
                0 | 1 => Cycle::ZERO,
                _ => Cycle(10 + n - 2),
            };
            assert_eq!(r.tx.credit_needed(), Some(want), "push {n}");
            r.tx.push(want.max(Cycle(n)), n as u32);
            r.tx_half.flush();
            assert!(r.rx_half.drain());
            assert_eq!(r.rx.pop(Cycle(10 + n)), n as u32);
        }
        r.cp.clear();
        r.cc.clear();
    }

    /// With no item in flight the consumer's bound is the producer's published horizon;
    /// a drain that finds nothing new reports no change (the executor then goes idle).
    #[test]
    fn remote_link_consumer_bound_follows_the_producer_horizon() {
        let r = remote(4, 2);
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle(2));
        // The producer's clock moves to 20 without pushing: its bound is 20 + latency 1.
        r.cp.slots[0].now.set(Cycle(20));
        r.cp.next_step();
        assert!(r.tx_half.flush(), "the horizon moved");
        assert!(
            !r.tx_half.flush(),
            "the same horizon is not published twice"
        );
        assert!(r.rx_half.drain());
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle(21 + 2));
        // The producer can end its outputs at its clock, 20, at the earliest.
        assert_eq!(r.rx_half.end_bound(&r.cc), Cycle(20 + 2));
        assert!(!r.rx_half.drain(), "nothing new arrived");
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle(23));
        // An item behind the horizon: the queued item is next, then the bound.
        r.tx.push(Cycle(30), 7);
        r.tx_half.flush();
        assert!(r.rx_half.drain());
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle(32));
        assert_eq!(r.rx.pop(Cycle(32)), 7);
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle(32));
        r.tx.end(Cycle(40));
        assert!(r.rx_half.drain());
        assert!(r.rx.finished());
        assert_eq!(r.rx.end_arrival(), Some(Cycle(42)));
        assert_eq!(r.rx_half.end_bound(&r.cc), Cycle(42));
        assert_eq!(r.rx.next_arrival(&r.cc), Cycle::NEVER);
        r.cp.clear();
        r.cc.clear();
    }
}
