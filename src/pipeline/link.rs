//! Timed links: the FIFOs between units (DESIGN §3), carried on bounded crossbeam channels.
//!
//! A link is a FIFO of depth `D >= 1` and latency `L >= 1`. Item n is pushed at p_n and
//! popped at q_n, with
//!
//! ```text
//!   q_n >= p_n + L,   q_n >= q_(n-1)        (the consumer: arrival, in order)
//!   p_n >= q_(n-D)                          (the producer: a full FIFO blocks)
//! ```
//!
//! The consumer returns every pop time as a *credit*; the producer reads the credit of item
//! n-D before it pushes item n. Stalls are therefore computed in simulated time from the
//! credits, never inferred from the host channel, whose fullness depends on scheduling.
//!
//! Three things travel producer → consumer:
//! - items, as `Timed { at: p_n, item }`, in batches ([`Msg::Items`]) with per-item time;
//! - a *watermark*: "nothing more will be pushed before cycle w". Merges need it to know an
//!   idle input's time (conservative PDES, Chandy-Misra-Bryant). The value lives in an
//!   atomic horizon and a [`Msg::Watermark`] only wakes the consumer, so at most one
//!   watermark message per link is ever in flight;
//! - [`Msg::End`]: nothing more at all.
//!
//! Host memory per link is bounded by the simulated FIFO: the producer cannot send item n
//! before the consumer popped item n-D, so at most D items, one watermark and the end are
//! in the host channel, whose capacity is D + 2 messages. A send never waits on the host.

use crossbeam_channel::{Receiver, Sender, TryRecvError};
use std::collections::VecDeque;
use std::fmt;
use std::ops::{Add, AddAssign, Sub};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::SeqCst};
use std::sync::Arc;

/// A point in simulated time, or a number of cycles [clock cycles].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Cycle(pub u64);

impl Cycle {
    pub const ZERO: Cycle = Cycle(0);
    /// Later than any real time: the bound of an input that has ended.
    pub const NEVER: Cycle = Cycle(u64::MAX);
}

impl Add<u64> for Cycle {
    type Output = Cycle;
    #[inline(always)]
    fn add(self, rhs: u64) -> Cycle {
        Cycle(self.0.saturating_add(rhs))
    }
}

impl AddAssign<u64> for Cycle {
    #[inline(always)]
    fn add_assign(&mut self, rhs: u64) {
        self.0 = self.0.saturating_add(rhs);
    }
}

impl Sub for Cycle {
    type Output = u64;
    #[inline(always)]
    fn sub(self, rhs: Cycle) -> u64 {
        self.0 - rhs.0
    }
}

impl fmt::Display for Cycle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// An item on a link with its push time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timed<T> {
    /// Push time p_n [cycle].
    pub at: Cycle,
    pub item: T,
}

/// What the host channel of a link carries.
pub enum Msg<T> {
    /// Items in push order, times non-decreasing.
    Items(Vec<Timed<T>>),
    /// The horizon moved: read it (see the module doc).
    Watermark,
    /// The producer finished; no more items.
    End,
}

/// FIFO depth and latency of one link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkSpec {
    /// Items the FIFO holds (D >= 1).
    pub fifo_depth: u32,
    /// Cycles from push to the earliest pop (L >= 1).
    pub latency_cycles: u64,
}

/// State shared by the two ends of a link.
struct Shared {
    /// Latest watermark: no item will be pushed before this cycle.
    horizon: AtomicU64,
    /// A [`Msg::Watermark`] is in the channel, unread.
    watermark_pending: AtomicBool,
    /// Item and end messages sent and not yet taken (the deadlock detector's view: a
    /// watermark alone cannot make a unit progress if nobody holds an item).
    unread_items: AtomicU64,
    /// Credit messages sent and not yet taken.
    unread_credits: AtomicU64,
}

/// Whether a link has a message its waiting end must take.
pub type Pending = Box<dyn Fn() -> bool + Send + Sync>;

/// Names of a link's ends, for deadlock reports.
#[derive(Clone, Debug)]
pub struct LinkName {
    pub producer: String,
    pub consumer: String,
}

impl fmt::Display for LinkName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} -> {}", self.producer, self.consumer)
    }
}

/// Most items per message: batches amortise the host channel without delaying a consumer
/// much (a producer also flushes whenever it is about to wait).
pub const MAX_BATCH: usize = 64;

/// Creates a link; the producer keeps the [`Tx`], the consumer the [`Rx`].
pub fn link<T>(spec: LinkSpec, name: LinkName) -> (Tx<T>, Rx<T>) {
    assert!(
        spec.fifo_depth >= 1 && spec.latency_cycles >= 1,
        "validated"
    );
    let depth = spec.fifo_depth as usize;
    let (data_tx, data_rx) = crossbeam_channel::bounded(depth + 2);
    let (credit_tx, credit_rx) = crossbeam_channel::bounded(depth + 1);
    let shared = Arc::new(Shared {
        horizon: AtomicU64::new(0),
        watermark_pending: AtomicBool::new(false),
        unread_items: AtomicU64::new(0),
        unread_credits: AtomicU64::new(0),
    });
    let tx = Tx {
        data: data_tx,
        credits: credit_rx,
        shared: shared.clone(),
        spec,
        name: name.clone(),
        pushed: 0,
        credits_seen: 0,
        credit_window: VecDeque::new(),
        batch: Vec::new(),
        last_push: Cycle::ZERO,
        published: Cycle::ZERO,
        ended: false,
    };
    let rx = Rx {
        data: data_rx,
        credits: credit_tx,
        shared,
        spec,
        name,
        queue: VecDeque::new(),
        bound: Cycle::ZERO,
        deferred_horizon: Cycle::ZERO,
        ended: false,
        popped: 0,
        pending_credits: Vec::new(),
        recent_pops: VecDeque::new(),
        max_occupancy: 0,
    };
    (tx, rx)
}

/// The producer's end of a link.
pub struct Tx<T> {
    data: Sender<Msg<T>>,
    credits: Receiver<Vec<Cycle>>,
    shared: Arc<Shared>,
    pub spec: LinkSpec,
    pub name: LinkName,
    /// Items pushed so far (the index of the next one).
    pushed: u64,
    /// Credits received so far.
    credits_seen: u64,
    /// Received pop times q_m for m in [credits_seen - len, credits_seen).
    credit_window: VecDeque<Cycle>,
    batch: Vec<Timed<T>>,
    last_push: Cycle,
    /// Latest watermark published.
    published: Cycle,
    ended: bool,
}

/// Why a host operation on a link failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LinkError {
    /// The other end was dropped before the link ended: its actor failed.
    Disconnected,
}

impl<T> Tx<T> {
    /// Index of the next item to push.
    pub fn pushed(&self) -> u64 {
        self.pushed
    }

    /// The pop time of the item whose credit the next push needs: `Some(Cycle::ZERO)`
    /// while the FIFO has never been full, `None` if that credit has not arrived yet.
    pub fn credit_needed(&mut self) -> Result<Option<Cycle>, LinkError> {
        let depth = self.spec.fifo_depth as u64;
        if self.pushed < depth {
            return Ok(Some(Cycle::ZERO));
        }
        let want = self.pushed - depth;
        while self.credits_seen <= want {
            match self.credits.try_recv() {
                Ok(batch) => self.take_credits(batch),
                Err(TryRecvError::Empty) => return Ok(None),
                Err(TryRecvError::Disconnected) => return Err(LinkError::Disconnected),
            }
        }
        Ok(Some(self.credit_at(want)))
    }

    /// The host channel credits arrive on (the caller flushed everything before waiting).
    pub fn receiver(&self) -> &Receiver<Vec<Cycle>> {
        &self.credits
    }

    /// Whether a credit message waits to be taken.
    pub fn credits_pending(&self) -> Pending {
        let shared = self.shared.clone();
        Box::new(move || shared.unread_credits.load(SeqCst) > 0)
    }

    /// Takes a credit message received from the host channel.
    pub fn take_credits(&mut self, batch: Vec<Cycle>) {
        self.shared.unread_credits.fetch_sub(1, SeqCst);
        self.credits_seen += batch.len() as u64;
        self.credit_window.extend(batch);
        // Only credits for items not yet pushed-past matter; keep at most D.
        let depth = self.spec.fifo_depth as usize;
        while self.credit_window.len() > depth {
            self.credit_window.pop_front();
        }
    }

    fn credit_at(&self, m: u64) -> Cycle {
        let first = self.credits_seen - self.credit_window.len() as u64;
        debug_assert!(
            m >= first,
            "credit {m} already dropped (window starts at {first})"
        );
        self.credit_window[(m - first) as usize]
    }

    /// Pushes an item at cycle `at` (the caller checked the credit). Sends when the batch
    /// is full; returns whether a message was sent.
    pub fn push(&mut self, at: Cycle, item: T) -> Result<bool, LinkError> {
        debug_assert!(at >= self.last_push, "pushes in time order");
        debug_assert!(!self.ended);
        self.last_push = at;
        self.pushed += 1;
        self.batch.push(Timed { at, item });
        if self.batch.len() >= MAX_BATCH {
            return self.flush();
        }
        Ok(false)
    }

    /// Sends the pending batch. Returns whether a message was sent.
    pub fn flush(&mut self) -> Result<bool, LinkError> {
        if self.batch.is_empty() {
            return Ok(false);
        }
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(MAX_BATCH));
        self.shared.unread_items.fetch_add(1, SeqCst);
        self.data
            .send(Msg::Items(batch))
            .map_err(|_| LinkError::Disconnected)?;
        Ok(true)
    }

    /// Promises that nothing more will be pushed before `bound`. Call after [`Tx::flush`].
    /// Returns whether a message was sent.
    pub fn publish(&mut self, bound: Cycle) -> Result<bool, LinkError> {
        debug_assert!(self.batch.is_empty(), "flush before publishing");
        if bound <= self.published || bound <= self.last_push || self.ended {
            return Ok(false);
        }
        self.published = bound;
        self.shared.horizon.fetch_max(bound.0, SeqCst);
        if self.shared.watermark_pending.swap(true, SeqCst) {
            return Ok(false);
        }
        self.data
            .send(Msg::Watermark)
            .map_err(|_| LinkError::Disconnected)?;
        Ok(true)
    }

    /// Sends the pending batch and the end of the link.
    pub fn end(&mut self) -> Result<(), LinkError> {
        if self.ended {
            return Ok(());
        }
        self.flush()?;
        self.ended = true;
        self.shared.unread_items.fetch_add(1, SeqCst);
        self.data
            .send(Msg::End)
            .map_err(|_| LinkError::Disconnected)
    }
}

/// The consumer's end of a link: received items waiting to be popped, the input's time
/// bound, credits to return and the FIFO occupancy measurement.
pub struct Rx<T> {
    data: Receiver<Msg<T>>,
    credits: Sender<Vec<Cycle>>,
    shared: Arc<Shared>,
    pub spec: LinkSpec,
    pub name: LinkName,
    /// Received items: (arrival = p + L, push time, item).
    queue: VecDeque<(Cycle, Cycle, T)>,
    /// No future item will be pushed before this cycle.
    bound: Cycle,
    /// A horizon read before items that were still to be taken.
    deferred_horizon: Cycle,
    ended: bool,
    /// Items popped so far.
    popped: u64,
    pending_credits: Vec<Cycle>,
    /// Pop times of the last D-1 items (non-decreasing), for the occupancy.
    recent_pops: VecDeque<Cycle>,
    /// Most items ever in this FIFO (pushed and not yet popped) at once.
    pub max_occupancy: u64,
}

impl<T> Rx<T> {
    pub fn receiver(&self) -> &Receiver<Msg<T>> {
        &self.data
    }

    /// Whether an item or end message waits to be taken.
    pub fn items_pending(&self) -> Pending {
        let shared = self.shared.clone();
        Box::new(move || shared.unread_items.load(SeqCst) > 0)
    }

    /// Whether the producer ended and every item was popped.
    pub fn finished(&self) -> bool {
        self.ended && self.queue.is_empty()
    }

    pub fn ended(&self) -> bool {
        self.ended
    }

    /// Earliest arrival of the next item: the head's if one is queued, else the bound
    /// plus the latency; [`Cycle::NEVER`] once the producer ended and the queue is empty.
    pub fn next_arrival(&self) -> Cycle {
        match self.queue.front() {
            Some(&(arrival, _, _)) => arrival,
            None if self.ended => Cycle::NEVER,
            None => self.bound + self.spec.latency_cycles,
        }
    }

    /// Whether an item is queued.
    pub fn has_item(&self) -> bool {
        !self.queue.is_empty()
    }

    /// Handles one message from the host channel.
    pub fn accept(&mut self, msg: Msg<T>) -> Result<(), LinkError> {
        if !matches!(msg, Msg::Watermark) {
            self.shared.unread_items.fetch_sub(1, SeqCst);
        }
        match msg {
            Msg::Items(items) => {
                let latency = self.spec.latency_cycles;
                for Timed { at, item } in items {
                    debug_assert!(at >= self.bound, "items in time order");
                    self.bound = at;
                    self.queue.push_back((at + latency, at, item));
                }
            }
            Msg::Watermark => {
                // Clear the flag before reading the horizon, then drain what was sent
                // before the horizon was stored (module doc), then apply it.
                self.shared.watermark_pending.store(false, SeqCst);
                let horizon = Cycle(self.shared.horizon.load(SeqCst));
                self.drain()?;
                self.bound = self.bound.max(horizon);
            }
            Msg::End => self.ended = true,
        }
        Ok(())
    }

    /// For a unit that waits: handles a watermark message without taking any item, so the
    /// unit can stay waiting. Returns the first item or end message found behind it, not
    /// taken: the caller marks itself running, then [`Rx::accept`]s it and [`Rx::drain`]s.
    /// The horizon read here is applied once everything sent before it was taken.
    pub fn accept_watermark(&mut self) -> Result<Option<Msg<T>>, LinkError> {
        self.shared.watermark_pending.store(false, SeqCst);
        let mut horizon = Cycle(self.shared.horizon.load(SeqCst));
        loop {
            match self.data.try_recv() {
                Ok(Msg::Watermark) => {
                    self.shared.watermark_pending.store(false, SeqCst);
                    horizon = horizon.max(Cycle(self.shared.horizon.load(SeqCst)));
                }
                Ok(msg) => {
                    self.deferred_horizon = self.deferred_horizon.max(horizon);
                    return Ok(Some(msg));
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return Err(LinkError::Disconnected),
            }
        }
        self.bound = self.bound.max(horizon);
        Ok(None)
    }

    /// Applies a horizon [`Rx::accept_watermark`] deferred (call after draining).
    pub fn apply_deferred(&mut self) {
        self.bound = self.bound.max(self.deferred_horizon);
    }

    /// Accepts every message already in the host channel, without waiting. Returns how
    /// many there were.
    pub fn drain(&mut self) -> Result<usize, LinkError> {
        let mut n = 0;
        while !self.ended {
            match self.data.try_recv() {
                Ok(msg) => {
                    n += 1;
                    self.accept(msg)?;
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return Err(LinkError::Disconnected),
            }
        }
        Ok(n)
    }

    /// Pops the head item at cycle `q` (>= its arrival): records the credit and the FIFO
    /// occupancy. Returns the item.
    pub fn pop(&mut self, q: Cycle) -> T {
        let (arrival, pushed_at, item) = self.queue.pop_front().expect("caller checked");
        debug_assert!(q >= arrival);
        // Occupancy right after this item's push: itself plus the earlier items not yet
        // popped then (only the last D-1 can be: item n-D was popped before p_n).
        let still_in =
            self.recent_pops.len() - self.recent_pops.partition_point(|&t| t <= pushed_at);
        self.max_occupancy = self.max_occupancy.max(1 + still_in as u64);
        let keep = self.spec.fifo_depth as usize - 1;
        if keep > 0 {
            if self.recent_pops.len() == keep {
                self.recent_pops.pop_front();
            }
            self.recent_pops.push_back(q);
        }
        self.popped += 1;
        self.pending_credits.push(q);
        item
    }

    /// Credits waiting to be returned.
    pub fn pending_credits(&self) -> usize {
        self.pending_credits.len()
    }

    /// Returns the pending credits to the producer.
    pub fn flush_credits(&mut self) -> Result<bool, LinkError> {
        if self.pending_credits.is_empty() {
            return Ok(false);
        }
        let batch = std::mem::take(&mut self.pending_credits);
        // A producer that already finished no longer reads credits; that is not an error.
        self.shared.unread_credits.fetch_add(1, SeqCst);
        if self.credits.send(batch).is_err() {
            self.shared.unread_credits.fetch_sub(1, SeqCst);
        }
        Ok(true)
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

    fn name() -> LinkName {
        LinkName {
            producer: "p".into(),
            consumer: "c".into(),
        }
    }

    #[test]
    fn link_credit_of_item_n_minus_depth_gates_push_n() {
        let (mut tx, mut rx) = link::<u32>(spec(2, 1), name());
        assert_eq!(tx.credit_needed(), Ok(Some(Cycle::ZERO)));
        tx.push(Cycle(0), 0).unwrap();
        tx.push(Cycle(1), 1).unwrap();
        // Item 2 needs the pop time of item 0, not yet returned.
        assert_eq!(tx.credit_needed(), Ok(None));
        tx.flush().unwrap();
        rx.drain().unwrap();
        assert_eq!(rx.next_arrival(), Cycle(1));
        assert_eq!(rx.pop(Cycle(5)), 0);
        rx.flush_credits().unwrap();
        assert_eq!(tx.credit_needed(), Ok(Some(Cycle(5))));
    }

    #[test]
    fn link_occupancy_counts_items_pushed_and_not_popped() {
        let (mut tx, mut rx) = link::<u32>(spec(4, 1), name());
        // Four pushes at 0..3, pops at 10..13: all four are in the FIFO at cycle 3.
        for n in 0..4 {
            tx.push(Cycle(n), n as u32).unwrap();
        }
        tx.flush().unwrap();
        rx.drain().unwrap();
        for n in 0..4 {
            rx.pop(Cycle(10 + n));
        }
        assert_eq!(rx.max_occupancy, 4);
    }

    #[test]
    fn link_occupancy_of_a_consumer_that_keeps_up_is_one() {
        let (mut tx, mut rx) = link::<u32>(spec(8, 1), name());
        for n in 0..6 {
            tx.push(Cycle(2 * n), 0).unwrap();
        }
        tx.flush().unwrap();
        rx.drain().unwrap();
        for n in 0..6 {
            rx.pop(Cycle(2 * n + 1));
        }
        assert_eq!(rx.max_occupancy, 1);
    }

    #[test]
    fn link_watermark_applies_only_after_earlier_items() {
        let (mut tx, mut rx) = link::<u32>(spec(4, 3), name());
        tx.publish(Cycle(5)).unwrap();
        tx.push(Cycle(7), 1).unwrap();
        tx.flush().unwrap();
        tx.publish(Cycle(20)).unwrap();
        // The first watermark message is still unread: the second only moved the horizon.
        let msg = rx.receiver().recv().unwrap();
        rx.accept(msg).unwrap();
        // Reading it drained the item sent before the horizon moved to 20.
        assert!(rx.has_item());
        assert_eq!(rx.next_arrival(), Cycle(10));
        rx.pop(Cycle(10));
        assert_eq!(rx.next_arrival(), Cycle(23));
        tx.end().unwrap();
        rx.drain().unwrap();
        assert!(rx.finished());
        assert_eq!(rx.next_arrival(), Cycle::NEVER);
    }
}
