//! The controller's front end: requests in, completions out, one [`Channel`] per channel,
//! run as a discrete-event simulation (time jumps from one admission or decision to the
//! next; no loop over idle cycles).
//!
//! Requests are admitted in submission order, as DRAMsim3's trace-driven CPU feeds them
//! (`TraceBasedCPU::ClockTick`, `src/cpu.cc`): the oldest waiting request enters its
//! channel's read or write queue at its arrival, or later when that queue is full, and the
//! requests behind it wait too. Memory is bounded by the queues, the requests submitted but
//! not yet admitted, and the completions not yet collected; [`replay`] keeps the first
//! few hundred long and the last drained.

use super::channel::Channel;
use super::channel::Queued;
use super::config::DramConfig;
use super::mapping::Decoder;
use super::stats::{Counters, DramStats};
use crate::error::Result;
use crate::memory::trace::Request;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// A submitted request's name: its position in submission order, from 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Ticket(pub u64);

/// A request done: the cycle its last data beat moved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Completion {
    /// The cycle it completed \[cycles\].
    pub done: u64,
    /// Which request.
    pub ticket: Ticket,
    /// When it arrived \[cycles\].
    pub arrival: u64,
}

/// A memory system: one controller per channel.
#[derive(Clone, Debug)]
pub struct Dram {
    cfg: DramConfig,
    decoder: Decoder,
    channels: Vec<Channel>,
    /// Submitted, not yet admitted, in submission order.
    pending: VecDeque<Queued>,
    next_ticket: u64,
    /// The last event's cycle.
    now: u64,
    /// Scheduled, not yet collected: by (done, ticket).
    done: BinaryHeap<Reverse<Completion>>,
    /// The cycle `run_until` reached: completions up to it are final.
    horizon: u64,
    counters: Counters,
}

enum Event {
    Admit,
    Decide(usize),
}

impl Dram {
    /// A controller for `cfg`, refused with the field named if `cfg` is invalid.
    pub fn new(cfg: &DramConfig) -> Result<Dram> {
        cfg.validate()?;
        Ok(Dram {
            cfg: cfg.clone(),
            decoder: Decoder::new(cfg.mapping, cfg.atom_bytes(), cfg.sizes())
                .with_bank_xor(cfg.bank_xor),
            channels: (0..cfg.channels).map(|_| Channel::new(cfg)).collect(),
            pending: VecDeque::new(),
            next_ticket: 0,
            now: 0,
            done: BinaryHeap::new(),
            horizon: 0,
            counters: Counters::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &DramConfig {
        &self.cfg
    }

    /// Submits a request for the atom holding `req.addr`. Requests are admitted in
    /// submission order; one that arrives before the cycle [`Dram::run_until`] reached is
    /// taken as arriving then, so completions already returned stay final (its latency
    /// still counts from `req.arrival`).
    pub fn submit(&mut self, req: Request) -> Ticket {
        let ticket = Ticket(self.next_ticket);
        self.next_ticket += 1;
        self.pending.push_back(Queued {
            ticket: ticket.0,
            arrival: req.arrival,
            ready: req.arrival.max(self.horizon),
            admitted: 0,
            moved: false,
            write: req.write,
            loc: self.decoder.decode(req.addr),
        });
        ticket
    }

    /// Runs every admission and decision before `cycle`; afterwards every request that
    /// completes at or before `cycle` is known to [`Dram::complete`].
    pub fn run_until(&mut self, cycle: u64) {
        while let Some((t, _)) = self.next_event() {
            if t >= cycle {
                break;
            }
            self.step();
        }
        self.horizon = self.horizon.max(cycle);
    }

    /// Runs until every submitted request is scheduled; returns the last completion's cycle.
    pub fn finish(&mut self) -> u64 {
        while self.step() {}
        let last = self.counters_stats().last_done;
        self.horizon = self.horizon.max(last);
        last
    }

    /// The requests completed by the cycle [`Dram::run_until`] reached (all of them after
    /// [`Dram::finish`]), each once, by completion cycle then ticket.
    pub fn complete(&mut self) -> Vec<Completion> {
        let mut out = Vec::new();
        while let Some(Reverse(c)) = self.done.peek() {
            if c.done > self.horizon {
                break;
            }
            out.push(*c);
            self.done.pop();
        }
        out
    }

    /// The totals so far (over the requests scheduled).
    pub fn stats(&self) -> DramStats {
        self.counters_stats()
    }

    fn counters_stats(&self) -> DramStats {
        let first_acts = self.channels.iter().flat_map(|c| c.first_acts());
        self.counters.stats(&self.cfg, first_acts)
    }

    /// Runs until every submitted request has entered its channel's queue; returns the
    /// cycle the last one entered (the cycle reached when none was waiting). What a client
    /// that must not run ahead of a full queue waits for.
    pub fn admit_all(&mut self) -> u64 {
        while !self.pending.is_empty() && self.step() {}
        self.now
    }

    /// Requests submitted and not yet admitted to a queue.
    pub fn waiting(&self) -> usize {
        self.pending.len()
    }

    /// The earliest event: the head's admission (first on a tie, so a request can be chosen
    /// at its arrival), or a channel's decision.
    fn next_event(&self) -> Option<(u64, Event)> {
        let mut best: Option<(u64, Event)> = None;
        if let Some(head) = self.pending.front() {
            let ch = &self.channels[head.loc.channel as usize];
            if ch.accepts(&self.cfg, head.write) {
                best = Some((head.ready.max(self.now), Event::Admit));
            }
        }
        for (i, ch) in self.channels.iter().enumerate() {
            if !ch.is_idle() && best.as_ref().is_none_or(|(t, _)| ch.clock < *t) {
                best = Some((ch.clock, Event::Decide(i)));
            }
        }
        best
    }

    /// Processes the earliest event; false when there is none.
    fn step(&mut self) -> bool {
        let Some((t, event)) = self.next_event() else {
            return false;
        };
        self.now = t;
        match event {
            Event::Admit => {
                let Some(mut req) = self.pending.pop_front() else {
                    return false;
                };
                req.admitted = t;
                let ch = &mut self.channels[req.loc.channel as usize];
                if ch.is_idle() {
                    ch.clock = ch.clock.max(t);
                }
                ch.push(req);
            }
            Event::Decide(i) => {
                let s = self.channels[i].decide(&self.cfg);
                self.counters.record(&s);
                self.done.push(Reverse(Completion {
                    done: s.done,
                    ticket: Ticket(s.req.ticket),
                    arrival: s.req.arrival,
                }));
            }
        }
        true
    }
}

/// Runs `requests` (in order) through a controller for `cfg` and returns the totals, with
/// bounded memory: at most a few hundred requests wait outside the queues, and completions
/// are dropped as they become final.
pub fn replay(cfg: &DramConfig, requests: &[Request]) -> Result<DramStats> {
    const WAITING: usize = 256;
    let mut dram = Dram::new(cfg)?;
    for (i, r) in requests.iter().enumerate() {
        dram.submit(*r);
        while dram.waiting() > WAITING && dram.step() {}
        if i % 4096 == 0 {
            dram.run_until(dram.now);
            dram.complete();
        }
    }
    dram.finish();
    Ok(dram.stats())
}
