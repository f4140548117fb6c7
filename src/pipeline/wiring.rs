//! The links of a run, made from the graph's boundaries: one [`Crossbar`] per boundary for the
//! whole run (the channels of every link whose ends are on different host threads), and per
//! host thread a [`HostWiring`] that hands each of its units the ends of its links
//! ([`Wired`]) and its [`Ctx`].

use super::runtime::core::Core;
use super::runtime::link::{local_link, Ends, RemoteEnd, RemoteParts, Rx, Tx};
use super::runtime::signal::Signal;
use super::runtime::{Ctx, Dispatcher, LinkName, LinkSpec, SimOptions};
use crate::graph::{UnitInstance, UnitKind};
use std::ops::Range;
use std::rc::Rc;
use std::sync::Arc;

/// The links of one boundary: producers `producers` to consumers `consumers` (global unit
/// indices), each link configured alike, with the channels of each link whose ends are on
/// different host threads.
pub struct Crossbar<T> {
    producers: Range<usize>,
    consumers: Range<usize>,
    spec: LinkSpec,
    /// The producers' first output port on this crossbar (the ports of the boundaries
    /// they feed before it come first).
    port_base: usize,
    /// By producer position * consumers + consumer position.
    remote: Vec<Option<RemoteParts<T>>>,
}

impl<T> Crossbar<T> {
    /// The crossbar from every instance of `from` to every instance of `to` among `units`
    /// (global indices, each kind's instances contiguous), with unit `g` on host thread
    /// `thread[g]`, its links each producer's output ports from `port_base` on.
    pub fn new(
        units: &[UnitInstance],
        from: UnitKind,
        to: UnitKind,
        thread: &[usize],
        spec: LinkSpec,
        port_base: usize,
    ) -> Self {
        let of = |kind: UnitKind| {
            let first = units.iter().position(|u| u.kind == kind).unwrap_or(0);
            first..first + units.iter().filter(|u| u.kind == kind).count()
        };
        let (producers, consumers) = (of(from), of(to));
        let mut remote = Vec::new();
        for p in producers.clone() {
            for q in consumers.clone() {
                remote.push((thread[p] != thread[q]).then(|| RemoteParts::new(spec)));
            }
        }
        Crossbar {
            producers,
            consumers,
            spec,
            port_base,
            remote,
        }
    }
}

/// One host thread's ends of a crossbar: `tx[p]` the outputs of producer position p, `rx[c]`
/// the inputs of consumer position c (empty for units of other threads), each taken once by
/// its unit.
pub struct Wired<T> {
    tx: Vec<Vec<Tx<T>>>,
    rx: Vec<Vec<Rx<T>>>,
}

impl<T> Wired<T> {
    /// The output links of producer position `i`.
    pub fn take_tx(&mut self, i: usize) -> Vec<Tx<T>> {
        std::mem::take(&mut self.tx[i])
    }

    /// The input links of consumer position `i`.
    pub fn take_rx(&mut self, i: usize) -> Vec<Rx<T>> {
        std::mem::take(&mut self.rx[i])
    }
}

/// Builds one host thread's share of the graph: its core and its ends of every link.
pub struct HostWiring<'p> {
    units: &'p [UnitInstance],
    thread: &'p [usize],
    me: usize,
    /// The units of this thread.
    pub core: Rc<Core>,
    /// Local index of each global unit on this thread.
    local: Vec<Option<u32>>,
    /// This thread's halves of links to other threads.
    pub remotes: Vec<Rc<dyn RemoteEnd>>,
    /// One per host thread; empty when there is only one.
    signals: &'p [Arc<Signal>],
}

impl<'p> HostWiring<'p> {
    /// Host thread `me`'s share of `units` (with their latencies \[cycles\]), unit `g` being
    /// on thread `thread[g]`; `options` gives the `perturb` test hook's seed.
    pub fn new(
        units: &'p [UnitInstance],
        latency: &[u64],
        thread: &'p [usize],
        me: usize,
        // Read only by the test hooks.
        #[cfg_attr(not(feature = "testkit"), allow(unused_variables))] options: &SimOptions,
        signals: &'p [Arc<Signal>],
    ) -> Self {
        let mut local = vec![None; units.len()];
        let mut mine = Vec::new();
        for (g, u) in units.iter().enumerate() {
            if thread[g] == me {
                local[g] = Some(mine.len() as u32);
                mine.push((u.name.clone(), latency[g]));
            }
        }
        let core = Core::new(mine);
        // Each host thread's own random order.
        #[cfg(feature = "testkit")]
        let core = core.perturbed(options.perturb.map(|p| p ^ me as u64));
        HostWiring {
            units,
            thread,
            me,
            core: Rc::new(core),
            local,
            remotes: Vec::new(),
            signals,
        }
    }

    /// Whether unit `g` runs on this thread.
    pub fn is_local(&self, g: usize) -> bool {
        self.local[g].is_some()
    }

    /// This thread's ends of `xb`'s links.
    pub fn wire<T: Send + 'static>(&mut self, xb: &Crossbar<T>) -> Wired<T> {
        let mut tx: Vec<Vec<Tx<T>>> = xb.producers.clone().map(|_| Vec::new()).collect();
        let mut rx: Vec<Vec<Rx<T>>> = xb.consumers.clone().map(|_| Vec::new()).collect();
        let nc = xb.consumers.len();
        for (pi, p) in xb.producers.clone().enumerate() {
            for (ci, c) in xb.consumers.clone().enumerate() {
                let name = LinkName {
                    producer: self.units[p].name.clone(),
                    consumer: self.units[c].name.clone(),
                };
                let ends = Ends {
                    producer: self.local[p].unwrap_or(u32::MAX),
                    port: (xb.port_base + ci) as u32,
                    consumer: self.local[c].unwrap_or(u32::MAX),
                    from: p as u32,
                };
                let (mine_p, mine_c) = (self.thread[p] == self.me, self.thread[c] == self.me);
                match (mine_p, mine_c, &xb.remote[pi * nc + ci]) {
                    (true, true, _) => {
                        let (t, r) = local_link(&self.core, xb.spec, name, ends, c);
                        tx[pi].push(t);
                        rx[ci].push(r);
                    }
                    (true, false, Some(parts)) => {
                        self.core.slots[ends.producer as usize]
                            .consumers
                            .borrow_mut()
                            .push((c, name.consumer.clone()));
                        let peer = self.signals[self.thread[c]].clone();
                        let half = Rc::new(parts.tx(self.core.clone(), xb.spec, name, ends, peer));
                        self.remotes.push(half.clone());
                        tx[pi].push(Tx::Remote(half));
                    }
                    (false, true, Some(parts)) => {
                        let peer = self.signals[self.thread[p]].clone();
                        let half = Rc::new(parts.rx(self.core.clone(), xb.spec, name, ends, peer));
                        self.remotes.push(half.clone());
                        self.core.slots[ends.consumer as usize]
                            .inputs
                            .borrow_mut()
                            .push(half.clone());
                        rx[ci].push(Rx::Remote(half));
                    }
                    // A link between two other threads, or one a thread's own units never
                    // touch: nothing of it lives here.
                    _ => {}
                }
            }
        }
        Wired { tx, rx }
    }

    /// The context of unit `g` (of this thread) with these links, its items sent by
    /// `dispatch`.
    pub fn ctx<I, O>(
        &self,
        g: usize,
        inputs: Vec<Rx<I>>,
        outputs: Vec<Tx<O>>,
        dispatch: Dispatcher<O>,
        trace: Option<usize>,
    ) -> Ctx<I, O> {
        let u = self.local[g].expect("a unit of this thread");
        Ctx::new(self.core.clone(), u, inputs, outputs, trace).with_dispatch(dispatch)
    }
}
