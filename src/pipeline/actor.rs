//! The actor runtime: one host thread per unit instance, each with a [`Ctx`] that adds
//! simulated time to whatever functional work the unit does (DESIGN §3).
//!
//! A unit's life is a sequence of ops. [`Ctx::next_input`] pops the next input by merge order;
//! [`Ctx::work`] spends busy cycles with no output; [`Ctx::emit`] spends busy cycles and
//! pushes one output item. Every cycle from 0 to the unit's last op is exactly one of busy,
//! starved (waiting for an input to arrive) or blocked (a full FIFO downstream):
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
//! port), once every other input's watermark proves nothing earlier can come.
//!
//! Host protocol: before a thread waits on the host it flushes everything it knows: its
//! batched items, a watermark on every output (the earliest cycle it could still push) and
//! the credits of its inputs. With link latencies >= 1 this is the conservative
//! (Chandy-Misra-Bryant) argument for progress; a watchdog turns any remaining deadlock (a
//! mis-wired graph) into an error that names the waiting units.

use super::link::{Cycle, LinkError, Msg, Pending, Rx, Tx};
use super::trace::{Recorder, State};
use crossbeam_channel::{Receiver, RecvTimeoutError, Select, Sender};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed, Ordering::SeqCst};
use std::sync::Mutex;
use std::time::Duration;

/// How long a waiting thread sleeps before it checks whether the run was aborted.
const TICK: Duration = Duration::from_millis(25);

/// Host-side options of a timed run; none of them changes a simulated result.
#[derive(Clone, Debug)]
pub struct SimOptions {
    /// Test switch: perturb the host schedule with random yields and sleeps (seeded), to
    /// show that results do not depend on it.
    pub perturb: Option<u64>,
    /// Record a timeline of unit activity (for `--trace-out`).
    pub trace: bool,
    /// Most timeline events kept over all units; beyond it events are coarsened.
    pub trace_event_cap: usize,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            perturb: None,
            trace: false,
            trace_event_cap: 200_000,
        }
    }
}

/// Why an actor stopped early.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ActorError {
    /// Another actor failed or the watchdog found a deadlock; this one just stopped.
    Aborted,
    /// A link's other end vanished before the link ended (its actor failed).
    Disconnected(String),
}

/// What a waiting unit waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Waiting {
    Running,
    /// For input; with the earliest item it holds but may not yet take (its merge lacks a
    /// watermark), if any.
    Input(Option<Cycle>),
    /// For a credit on output `port`.
    Credit(usize),
    Done,
}

/// What wakes a unit: its input channels (and its go-ahead channel) when it waits for
/// input, one output's credit channel when it waits for a credit.
struct Listens {
    inputs: Pending,
    credits: Vec<Pending>,
}

/// The run-wide state the deadlock detector reads, under one lock.
struct Board {
    listens: Vec<Option<Listens>>,
    waiting: Vec<Waiting>,
    /// Units neither running nor done.
    n_waiting: usize,
    live: usize,
}

/// Shared by the actors of one run: who waits for what, and the go-ahead of a recovery.
///
/// Conservative merges can stall on a cycle of zero lookahead that runs through credits
/// (Rop[1] waits for the frame-buffer port's credit, the port's merge waits for Rop[0]'s
/// watermark, Rop[0] is idle because every rasterizer waits for Rop[1]'s credit). Such a
/// stall is a global quiescence: every live unit waits and no item, end or credit message
/// it waits on is unread (checked under the lock every wait goes through, so no send can
/// slip past). Watermarks do not count: in a mis-wired loop they would circle forever,
/// and when no unit holds an item they cannot make anything progress.
/// Then the earliest item any waiting unit holds, at cycle a*, is safe to take (Chandy and
/// Misra's deadlock recovery): every item not yet delivered will be pushed by an op that
/// starts at or after some pop at or after a*, so it arrives after a*. The units holding
/// an item at a* get a go-ahead; the simulated result is the one the merge rule defines,
/// only reached without the missing watermark. Quiescence with no unit holding an item
/// is a true deadlock (a mis-wired graph): the run stops with [`Monitor::deadlock`].
pub struct Monitor {
    names: Vec<String>,
    board: Mutex<Board>,
    /// Per unit: the channel a go-ahead arrives on (the cycle it may take).
    go: Vec<(Sender<Cycle>, Receiver<Cycle>)>,
    /// Per unit: the producers of its inputs and the consumers of its outputs.
    wiring: Vec<Mutex<(Vec<String>, Vec<String>)>>,
    abort: AtomicBool,
    deadlock: Mutex<Option<Vec<String>>>,
    /// Recoveries performed (a host statistic: how often watermarks were not enough).
    pub recoveries: AtomicU64,
}

impl Monitor {
    pub fn new(names: Vec<String>) -> Self {
        let n = names.len();
        Monitor {
            names,
            board: Mutex::new(Board {
                listens: (0..n).map(|_| None).collect(),
                waiting: vec![Waiting::Running; n],
                n_waiting: 0,
                live: n,
            }),
            go: (0..n).map(|_| crossbeam_channel::bounded(1)).collect(),
            wiring: (0..n)
                .map(|_| Mutex::new((Vec::new(), Vec::new())))
                .collect(),
            abort: AtomicBool::new(false),
            deadlock: Mutex::new(None),
            recoveries: AtomicU64::new(0),
        }
    }

    pub fn name(&self, unit: usize) -> &str {
        &self.names[unit]
    }

    /// Stops every actor (they notice within a tick).
    pub fn abort(&self) {
        self.abort.store(true, SeqCst);
    }

    pub fn aborted(&self) -> bool {
        self.abort.load(Relaxed)
    }

    /// The waiting units of a detected deadlock, if there was one.
    pub fn deadlock(&self) -> Option<Vec<String>> {
        self.deadlock.lock().expect("not poisoned").clone()
    }

    fn set(&self, unit: usize, state: Waiting) {
        let mut b = self.board.lock().expect("not poisoned");
        let was = b.waiting[unit];
        let counts = |w: Waiting| matches!(w, Waiting::Input(_) | Waiting::Credit(_));
        b.n_waiting = b.n_waiting + counts(state) as usize - counts(was) as usize;
        if state == Waiting::Done && was != Waiting::Done {
            b.live -= 1;
        }
        b.waiting[unit] = state;
        if b.live > 0 && b.n_waiting == b.live && !self.aborted() && Self::quiet(&b) {
            self.recover(&b);
        }
    }

    /// No waiting unit has a message to wake it.
    fn quiet(b: &Board) -> bool {
        b.waiting.iter().zip(&b.listens).all(|(w, l)| match (w, l) {
            (Waiting::Input(_), Some(l)) => !(l.inputs)(),
            (Waiting::Credit(port), Some(l)) => !(l.credits[*port])(),
            _ => true,
        })
    }

    /// Marks a unit finished (also on failure).
    pub fn done(&self, unit: usize) {
        self.set(unit, Waiting::Done);
    }

    /// Called under the board lock at a global quiescence (type doc).
    fn recover(&self, b: &Board) {
        let earliest = b
            .waiting
            .iter()
            .filter_map(|w| match w {
                Waiting::Input(Some(a)) => Some(*a),
                _ => None,
            })
            .min();
        match earliest {
            Some(a) => {
                self.recoveries.fetch_add(1, Relaxed);
                for (u, w) in b.waiting.iter().enumerate() {
                    if *w == Waiting::Input(Some(a)) {
                        // Capacity 1 and at most one go-ahead per quiescence: never full.
                        let _ = self.go[u].0.try_send(a);
                    }
                }
            }
            None => {
                let waiting = b
                    .waiting
                    .iter()
                    .enumerate()
                    .filter(|(_, w)| !matches!(w, Waiting::Done | Waiting::Running))
                    .map(|(u, &w)| self.describe(u, w))
                    .collect();
                *self.deadlock.lock().expect("not poisoned") = Some(waiting);
                self.abort();
            }
        }
    }

    fn describe(&self, unit: usize, state: Waiting) -> String {
        let wiring = self.wiring[unit].lock().expect("not poisoned");
        let (inputs, outputs) = &*wiring;
        let what = match state {
            Waiting::Credit(port) => {
                let to = outputs.get(port).map(String::as_str).unwrap_or("?");
                format!("waits for a credit from {to} (its FIFO is full)")
            }
            _ if inputs.is_empty() => "waits for input but has no input link".to_string(),
            _ => format!("waits for input from [{}]", inputs.join(", ")),
        };
        format!("{} {what}", self.names[unit])
    }
}

/// Counters of one unit over its life, [cycles] unless named otherwise.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UnitStats {
    pub busy: u64,
    pub starved: u64,
    pub blocked: u64,
    /// Cycle of the unit's last activity: busy + starved + blocked.
    pub end: Cycle,
    pub items_in: u64,
    pub items_out: u64,
    /// Most items in any one input FIFO at once.
    pub max_fifo_occupancy: u64,
}

/// What a merge can do.
enum Choice {
    Take(usize, Cycle),
    Finished,
    Wait,
}

/// The per-thread timing context of one unit: inputs, outputs, its clock and counters.
pub struct Ctx<'m, I, O> {
    unit: usize,
    inputs: Vec<Rx<I>>,
    outputs: Vec<Tx<O>>,
    /// Cycles from an op's last cycle to its output being ready.
    latency: u64,
    now: Cycle,
    stats: UnitStats,
    monitor: &'m Monitor,
    trace: Option<Recorder>,
    /// xorshift state of the perturbation switch.
    perturb: Option<u64>,
    /// A recovery's go-ahead: the arrival cycle of the item this unit may take.
    go: Option<Cycle>,
}

impl<'m, I: Send + 'static, O: Send + 'static> Ctx<'m, I, O> {
    pub fn new(
        unit: usize,
        inputs: Vec<Rx<I>>,
        outputs: Vec<Tx<O>>,
        latency: u64,
        monitor: &'m Monitor,
        options: &SimOptions,
        trace_cap: usize,
    ) -> Self {
        *monitor.wiring[unit].lock().expect("not poisoned") = (
            inputs.iter().map(|rx| rx.name.producer.clone()).collect(),
            outputs.iter().map(|tx| tx.name.consumer.clone()).collect(),
        );
        let data: Vec<Pending> = inputs.iter().map(Rx::items_pending).collect();
        let go = monitor.go[unit].1.clone();
        monitor.board.lock().expect("not poisoned").listens[unit] = Some(Listens {
            inputs: Box::new(move || !go.is_empty() || data.iter().any(|p| p())),
            credits: outputs.iter().map(Tx::credits_pending).collect(),
        });
        Ctx {
            unit,
            inputs,
            outputs,
            latency: latency.max(1),
            now: Cycle::ZERO,
            stats: UnitStats::default(),
            monitor,
            trace: options.trace.then(|| Recorder::new(trace_cap)),
            perturb: options
                .perturb
                .map(|seed| (seed ^ (unit as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15)) | 1),
            go: None,
        }
    }

    pub fn outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Spends `cycles` busy cycles with no output.
    pub fn work(&mut self, cycles: u64) {
        let start = self.now;
        self.now += cycles;
        self.stats.busy += cycles;
        if let Some(t) = self.trace.as_mut() {
            t.record(start.0, self.now.0, State::Busy);
        }
    }

    /// Spends `cycles` (>= 1) busy cycles producing `item` for output `port`, then pushes
    /// it when the FIFO has room (see the module doc for the freeze).
    pub fn emit(&mut self, cycles: u64, port: usize, item: O) -> Result<(), ActorError> {
        debug_assert!(cycles >= 1);
        let cycles = cycles.max(1);
        let issue = self.now;
        self.work(cycles);
        let ready = issue + (cycles - 1 + self.latency);
        let credit = loop {
            match self.outputs[port].credit_needed() {
                Ok(Some(q)) => break q,
                Ok(None) => self.wait_credit(port, ready)?,
                Err(e) => return Err(self.link_error(e, port, false)),
            }
        };
        let push = ready.max(credit);
        if push > ready {
            let freeze = push - ready;
            let start = self.now;
            self.now += freeze;
            self.stats.blocked += freeze;
            if let Some(t) = self.trace.as_mut() {
                t.record(start.0, self.now.0, State::Blocked);
            }
        }
        self.stats.items_out += 1;
        let sent = self.outputs[port]
            .push(push, item)
            .map_err(|e| self.link_error(e, port, false))?;
        if sent {
            self.perturb_host();
        }
        Ok(())
    }

    /// The next input item in merge order, after waiting for it (starved cycles); `None`
    /// once every input has ended.
    pub fn next_input(&mut self) -> Result<Option<I>, ActorError> {
        loop {
            match self.choose() {
                Choice::Take(port, arrival) => {
                    self.go = None;
                    return Ok(Some(self.pop(port, arrival)));
                }
                Choice::Finished => return Ok(None),
                Choice::Wait => self.wait_input()?,
            }
        }
    }

    /// What the merge can do now: the queued item with the smallest (arrival, port), once
    /// every other input's bound proves nothing earlier can come (or a recovery said so).
    fn choose(&self) -> Choice {
        let mut best: Option<(Cycle, usize)> = None;
        for (i, rx) in self.inputs.iter().enumerate() {
            if rx.has_item() {
                let a = rx.next_arrival();
                if best.is_none_or(|(b, _)| a < b) {
                    best = Some((a, i));
                }
            }
        }
        match best {
            Some((arrival, port)) => {
                let safe = self.inputs.iter().enumerate().all(|(j, rx)| {
                    rx.has_item() || {
                        let b = rx.next_arrival();
                        b > arrival || (b == arrival && j > port)
                    }
                });
                if safe || self.go == Some(arrival) {
                    Choice::Take(port, arrival)
                } else {
                    Choice::Wait
                }
            }
            None if self.inputs.iter().all(Rx::finished) => Choice::Finished,
            None => Choice::Wait,
        }
    }

    fn pop(&mut self, port: usize, arrival: Cycle) -> I {
        if arrival > self.now {
            self.stats.starved += arrival - self.now;
            self.now = arrival;
        }
        self.stats.items_in += 1;
        let rx = &mut self.inputs[port];
        rx.pop(self.now)
    }

    /// The earliest cycle this unit could still push anything, while it waits for input.
    fn output_bound(&self) -> Cycle {
        let arrival = self
            .inputs
            .iter()
            .map(Rx::next_arrival)
            .min()
            .unwrap_or(Cycle::NEVER);
        if arrival == Cycle::NEVER {
            return Cycle::NEVER;
        }
        arrival.max(self.now) + self.latency
    }

    /// Flushes everything this unit knows (module doc): items, watermarks, credits.
    fn flush_all(&mut self, bound: Cycle) -> Result<(), ActorError> {
        for port in 0..self.outputs.len() {
            let tx = &mut self.outputs[port];
            if let Err(e) = tx.flush().and_then(|_| tx.publish(bound)) {
                return Err(self.link_error(e, port, false));
            }
        }
        for rx in &mut self.inputs {
            let _ = rx.flush_credits();
        }
        Ok(())
    }

    fn wait_input(&mut self) -> Result<(), ActorError> {
        // Whatever is already in the host channels first, without waiting.
        let mut drained = 0;
        for port in 0..self.inputs.len() {
            match self.inputs[port].drain() {
                Ok(n) => drained += n,
                Err(e) => return Err(self.link_error(e, port, true)),
            }
        }
        if drained > 0 {
            return Ok(());
        }
        let bound = self.output_bound();
        self.flush_all(bound)?;
        self.perturb_host();
        let held = self
            .inputs
            .iter()
            .filter(|rx| rx.has_item())
            .map(Rx::next_arrival)
            .min();
        self.monitor.set(self.unit, Waiting::Input(held));
        let unit = self.unit;
        loop {
            if self.monitor.aborted() {
                self.monitor.set(unit, Waiting::Running);
                return Err(ActorError::Aborted);
            }
            let live: Vec<usize> = (0..self.inputs.len())
                .filter(|&i| !self.inputs[i].ended())
                .collect();
            let received = {
                let mut select = Select::new();
                for &i in &live {
                    select.recv(self.inputs[i].receiver());
                }
                let go = select.recv(&self.monitor.go[unit].1);
                match select.select_timeout(TICK) {
                    Ok(op) if op.index() == go => {
                        let a = op.recv(&self.monitor.go[unit].1);
                        Some((usize::MAX, a.map(Ok)))
                    }
                    Ok(op) => {
                        let port = live[op.index()];
                        Some((port, op.recv(self.inputs[port].receiver()).map(Err)))
                    }
                    Err(_) => None,
                }
            };
            match received {
                Some((_, Ok(Ok(a)))) => {
                    self.monitor.set(unit, Waiting::Running);
                    self.go = Some(a);
                    return Ok(());
                }
                Some((port, Ok(Err(Msg::Watermark)))) => {
                    // Stay waiting unless the watermark lets the merge move: a loop of
                    // watermarks alone must not look like progress (Monitor doc).
                    let behind = match self.inputs[port].accept_watermark() {
                        Ok(behind) => behind,
                        Err(e) => {
                            self.monitor.set(unit, Waiting::Running);
                            return Err(self.link_error(e, port, true));
                        }
                    };
                    if let Some(msg) = behind {
                        self.monitor.set(unit, Waiting::Running);
                        let rx = &mut self.inputs[port];
                        let r = rx.accept(msg).and_then(|_| rx.drain());
                        rx.apply_deferred();
                        return r.map(|_| ()).map_err(|e| self.link_error(e, port, true));
                    }
                    if !matches!(self.choose(), Choice::Wait) {
                        self.monitor.set(unit, Waiting::Running);
                        return Ok(());
                    }
                    let bound = self.output_bound();
                    for port in 0..self.outputs.len() {
                        if let Err(e) = self.outputs[port].publish(bound) {
                            self.monitor.set(unit, Waiting::Running);
                            return Err(self.link_error(e, port, false));
                        }
                    }
                }
                Some((port, Ok(Err(msg)))) => {
                    self.monitor.set(unit, Waiting::Running);
                    return self.inputs[port]
                        .accept(msg)
                        .map_err(|e| self.link_error(e, port, true));
                }
                Some((port, Err(_))) => {
                    self.monitor.set(unit, Waiting::Running);
                    return Err(self.link_error(LinkError::Disconnected, port, true));
                }
                None if self.monitor.aborted() => return Err(ActorError::Aborted),
                None => {}
            }
        }
    }

    fn wait_credit(&mut self, port: usize, bound: Cycle) -> Result<(), ActorError> {
        self.flush_all(bound)?;
        self.perturb_host();
        self.monitor.set(self.unit, Waiting::Credit(port));
        let result = loop {
            match self.outputs[port].receiver().recv_timeout(TICK) {
                Ok(batch) => {
                    self.monitor.set(self.unit, Waiting::Running);
                    self.outputs[port].take_credits(batch);
                    break Ok(());
                }
                Err(RecvTimeoutError::Timeout) if self.monitor.aborted() => {
                    break Err(ActorError::Aborted)
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => {
                    break Err(self.link_error(LinkError::Disconnected, port, false))
                }
            }
        };
        result
    }

    fn link_error(&self, e: LinkError, port: usize, input: bool) -> ActorError {
        if self.monitor.aborted() {
            return ActorError::Aborted;
        }
        let LinkError::Disconnected = e;
        let name = if input {
            self.inputs[port].name.to_string()
        } else {
            self.outputs[port].name.to_string()
        };
        ActorError::Disconnected(name)
    }

    fn perturb_host(&mut self) {
        let Some(x) = self.perturb.as_mut() else {
            return;
        };
        *x ^= *x << 13;
        *x ^= *x >> 7;
        *x ^= *x << 17;
        match *x % 16 {
            0..=3 => std::thread::yield_now(),
            4 => std::thread::sleep(Duration::from_micros(*x % 200)),
            _ => {}
        }
    }

    /// Ends every output and returns the unit's counters and timeline. Consumes the
    /// context: a finished unit does nothing more.
    pub fn finish(mut self) -> Result<(UnitStats, Option<Recorder>), ActorError> {
        for port in 0..self.outputs.len() {
            if let Err(e) = self.outputs[port].end() {
                return Err(self.link_error(e, port, false));
            }
        }
        for rx in &mut self.inputs {
            let _ = rx.flush_credits();
        }
        let mut stats = self.stats.clone();
        stats.end = self.now;
        stats.max_fifo_occupancy = self
            .inputs
            .iter()
            .map(|rx| rx.max_occupancy)
            .max()
            .unwrap_or(0);
        debug_assert_eq!(stats.busy + stats.starved + stats.blocked, stats.end.0);
        Ok((stats, self.trace.take()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::link::{link, LinkName, LinkSpec};

    fn spec(d: u32, l: u64) -> LinkSpec {
        LinkSpec {
            fifo_depth: d,
            latency_cycles: l,
        }
    }

    fn name(p: &str, c: &str) -> LinkName {
        LinkName {
            producer: p.into(),
            consumer: c.into(),
        }
    }

    /// Runs `body` on its own thread as unit `unit`, marking it done at the end.
    fn run_unit<'s, T: Send + 's>(
        s: &'s std::thread::Scope<'s, '_>,
        monitor: &'s Monitor,
        unit: usize,
        body: impl FnOnce() -> Result<T, ActorError> + Send + 's,
    ) -> std::thread::ScopedJoinHandle<'s, Result<T, ActorError>> {
        s.spawn(move || {
            let r = body();
            monitor.done(unit);
            r
        })
    }

    /// Source: 3 ops of 2 cycles, latency 3, into a FIFO of depth 1 and latency 1; sink: 5
    /// busy cycles per item. By hand (p push, q pop):
    ///   op0 issues 0, ready 0+2-1+3 = 4, p0 = 4;  sink: arrives 5, q0 = 5, busy 5..10
    ///   op1 issues 2, ready 6, credit q0 = 5, p1 = 6;  arrives 7, q1 = 10, busy 10..15
    ///   op2 issues 4, ready 8, credit q1 = 10, p2 = 10: frozen 2 cycles; q2 = 15, busy 15..20
    /// Source: busy 6, blocked 2, ends at 8. Sink: busy 15, starved 5, ends at 20.
    #[test]
    fn actor_cycles_of_a_tiny_pipeline_are_exact() {
        let monitor = Monitor::new(vec!["Source".into(), "Sink".into()]);
        let options = SimOptions::default();
        let (tx, rx) = link::<u32>(spec(1, 1), name("Source", "Sink"));
        let (src, snk) = std::thread::scope(|s| {
            let m = &monitor;
            let o = &options;
            let a = run_unit(s, m, 0, move || {
                let mut c = Ctx::<(), u32>::new(0, Vec::new(), vec![tx], 3, m, o, 16);
                for n in 0..3 {
                    c.emit(2, 0, n)?;
                }
                c.finish()
            });
            let b = run_unit(s, m, 1, move || {
                let mut c = Ctx::<u32, ()>::new(1, vec![rx], Vec::new(), 1, m, o, 16);
                let mut seen = Vec::new();
                while let Some(n) = c.next_input()? {
                    seen.push(n);
                    c.work(5);
                }
                assert_eq!(seen, [0, 1, 2]);
                c.finish()
            });
            (a.join().unwrap().unwrap().0, b.join().unwrap().unwrap().0)
        });
        assert_eq!(
            (src.busy, src.starved, src.blocked, src.end),
            (6, 0, 2, Cycle(8))
        );
        assert_eq!(
            (snk.busy, snk.starved, snk.blocked, snk.end),
            (15, 5, 0, Cycle(20))
        );
        assert_eq!((src.items_out, snk.items_in), (3, 3));
        assert_eq!(snk.max_fifo_occupancy, 1);
    }

    /// Two sources into one merging sink: items are taken by (arrival, port), whatever
    /// order the host delivers them in. A: items at arrival 2, 5, 8 (port 0); B: arrival 2,
    /// 3 (port 1). Merge order: A0 (2, port 0), B0 (2, port 1), B1 (3), A1 (5), A2 (8).
    #[test]
    fn actor_merge_takes_items_by_arrival_then_port() {
        let names = vec!["A".into(), "B".into(), "Sink".into()];
        let monitor = Monitor::new(names);
        let options = SimOptions {
            perturb: Some(7),
            ..SimOptions::default()
        };
        let (ta, ra) = link::<(char, u32)>(spec(8, 1), name("A", "Sink"));
        let (tb, rb) = link::<(char, u32)>(spec(8, 1), name("B", "Sink"));
        let order = std::thread::scope(|s| {
            let m = &monitor;
            let o = &options;
            // Each op costs 1 cycle, latency 1: ready = issue; A issues at 1, 4, 7 after gaps.
            run_unit(s, m, 0, move || {
                let mut c = Ctx::<(), (char, u32)>::new(0, Vec::new(), vec![ta], 1, m, o, 16);
                for n in 0..3 {
                    c.work(if n == 0 { 1 } else { 2 });
                    c.emit(1, 0, ('A', n))?;
                }
                c.finish()
            });
            run_unit(s, m, 1, move || {
                let mut c = Ctx::<(), (char, u32)>::new(1, Vec::new(), vec![tb], 1, m, o, 16);
                c.work(1);
                c.emit(1, 0, ('B', 0))?;
                c.emit(1, 0, ('B', 1))?;
                c.finish()
            });
            let sink = run_unit(s, m, 2, move || {
                let mut c = Ctx::<(char, u32), ()>::new(2, vec![ra, rb], Vec::new(), 1, m, o, 16);
                let mut order = Vec::new();
                while let Some(item) = c.next_input()? {
                    order.push(item);
                }
                c.finish().map(|_| order)
            });
            sink.join().unwrap().unwrap()
        });
        assert_eq!(order, [('A', 0), ('B', 0), ('B', 1), ('A', 1), ('A', 2)]);
    }

    /// Two units wired into a loop, each waiting for the other's first item: the run stops
    /// at once with a deadlock naming both and what they wait for.
    #[test]
    fn actor_miswired_loop_is_reported_as_a_deadlock() {
        let monitor = Monitor::new(vec!["Left".into(), "Right".into()]);
        let options = SimOptions::default();
        let (t1, r1) = link::<u32>(spec(2, 1), name("Left", "Right"));
        let (t2, r2) = link::<u32>(spec(2, 1), name("Right", "Left"));
        let started = std::time::Instant::now();
        let results = std::thread::scope(|s| {
            let m = &monitor;
            let o = &options;
            let mk = |unit: usize, rx, tx| {
                run_unit(s, m, unit, move || {
                    let mut c = Ctx::<u32, u32>::new(unit, vec![rx], vec![tx], 1, m, o, 16);
                    while let Some(n) = c.next_input()? {
                        c.emit(1, 0, n)?;
                    }
                    c.finish()
                })
            };
            let a = mk(0, r2, t1);
            let b = mk(1, r1, t2);
            [a.join().unwrap(), b.join().unwrap()]
        });
        assert!(started.elapsed() < Duration::from_secs(5));
        for r in results {
            assert_eq!(r.err(), Some(ActorError::Aborted));
        }
        let waiting = monitor.deadlock().expect("a deadlock was found");
        assert_eq!(
            waiting,
            [
                "Left waits for input from [Right]",
                "Right waits for input from [Left]"
            ]
        );
    }
}
