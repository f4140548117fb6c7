//! The timed model's runtime: what a unit is, how links keep time and how units are run.
//! The units themselves live in [`super::units`] and use only [`Ctx`].
//!
//! - [`cycle`]: [`Cycle`] and [`Timed`].
//! - [`link`]: FIFOs with depth, latency and credits, inside a host thread or across.
//! - [`ctx`]: a unit's clock and its ops (`next_input`, `work`, `emit`) and the busy,
//!   starved and blocked accounting; [`dispatch`]: which port an emitted item leaves by
//!   (the boundary's rule).
//! - [`core`]: one host thread's units, their ready queue and the bounds merges read.
//! - [`executor`]: runs the units deterministically, smallest local clock first, on one
//!   host thread or partitioned over several; recovery and deadlock reports.
//! - [`trace`]: the Chrome trace-event timeline.

pub mod core;
pub mod ctx;
pub mod cycle;
pub mod dispatch;
pub mod executor;
pub mod link;
pub mod signal;
pub mod trace;

pub use ctx::{ceil_div, Ctx, UnitStats};
pub use cycle::{Cycle, Timed};
pub use dispatch::Dispatcher;
pub use link::{LinkName, LinkSpec};

/// Host-side options of a timed run; none of them changes a simulated result.
#[derive(Clone, Debug)]
pub struct SimOptions {
    /// Host threads the units are partitioned over (>= 1; `--host-threads`).
    pub host_threads: usize,
    /// Test hook (the `testkit` feature only): partition the units over the host threads
    /// at random (seeded) instead of in contiguous runs of the dataflow order.
    #[cfg(feature = "testkit")]
    pub partition_seed: Option<u64>,
    /// Test hook (the `testkit` feature only): run units in a random order (seeded)
    /// instead of smallest clock first, to show that results do not depend on the
    /// schedule.
    #[cfg(feature = "testkit")]
    pub perturb: Option<u64>,
    /// Record a timeline of unit activity (for `--trace-out`).
    pub trace: bool,
    /// Most timeline events kept over all units; beyond it events are coarsened.
    pub trace_event_cap: usize,
    /// Keep the DRAM controller's requests (`TimedFrame::dram_requests`), in DRAMsim3's
    /// trace form, to run another DRAM simulator on the same frame.
    pub dram_requests: bool,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            host_threads: 1,
            #[cfg(feature = "testkit")]
            partition_seed: None,
            #[cfg(feature = "testkit")]
            perturb: None,
            trace: false,
            trace_event_cap: 200_000,
            dram_requests: false,
        }
    }
}

impl SimOptions {
    /// Which host thread runs each of `units` units: [`partition`], or with the
    /// `partition_seed` test hook a seeded random assignment.
    pub fn partition(&self, units: usize) -> Vec<usize> {
        #[cfg(feature = "testkit")]
        if let Some(seed) = self.partition_seed {
            return partition_at_random(units, self.host_threads, seed);
        }
        partition(units, self.host_threads)
    }
}

/// Which host thread runs each of `units` units: contiguous runs of the dataflow order, as
/// even as the count allows. Threads beyond the unit count get none.
pub fn partition(units: usize, threads: usize) -> Vec<usize> {
    let threads = threads.clamp(1, units.max(1));
    (0..units).map(|u| u * threads / units.max(1)).collect()
}

/// The `partition_seed` test hook: each unit on a host thread drawn at random from `seed`
/// (some threads may get none).
#[cfg(feature = "testkit")]
fn partition_at_random(units: usize, threads: usize, seed: u64) -> Vec<usize> {
    let threads = threads.clamp(1, units.max(1));
    let mut rng = crate::testkit::SplitMix64::new(seed);
    (0..units)
        .map(|_| rng.below(threads as u64) as usize)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::runtime::core::Core;
    use crate::pipeline::runtime::executor::{Halt, HostThread, UnitFuture};
    use crate::pipeline::runtime::link::{local_link, Ends, Rx, Tx};
    use std::rc::Rc;

    fn spec(d: u32, l: u64) -> LinkSpec {
        LinkSpec {
            fifo_depth: d,
            latency_cycles: l,
        }
    }

    /// A local link from unit `p` (output `port`) to unit `c` of `core`.
    fn local<T: 'static>(core: &Rc<Core>, p: u32, port: u32, c: u32, d: u32) -> (Tx<T>, Rx<T>) {
        let name = LinkName {
            producer: core.slots[p as usize].name.clone(),
            consumer: core.slots[c as usize].name.clone(),
        };
        let ends = Ends {
            producer: p,
            port,
            consumer: c,
            from: p,
        };
        local_link(core, spec(d, 1), name, ends, c as usize)
    }

    fn thread<'a, F>(core: Rc<Core>, futures: Vec<UnitFuture<'a, F>>) -> HostThread<'a, F> {
        let n = futures.len();
        HostThread {
            core,
            futures,
            global: (0..n).collect(),
            remotes: Vec::new(),
        }
    }

    /// Source: 3 ops of 2 cycles, latency 3, into a FIFO of depth 1 and latency 1; sink: 5
    /// busy cycles per item. By hand (p push, q pop):
    ///   op0 issues 0, ready 0+2-1+3 = 4, p0 = 4;  sink: arrives 5, q0 = 5, busy 5..10
    ///   op1 issues 2, ready 6, credit q0 = 5, p1 = 6;  arrives 7, q1 = 10, busy 10..15
    ///   op2 issues 4, ready 8, credit q1 = 10, p2 = 10: frozen 2 cycles; q2 = 15, busy 15..20
    /// Source: busy 6, blocked 2, ends at 8. Sink: busy 15, starved 5, ends at 20.
    #[test]
    fn executor_cycles_of_a_tiny_pipeline_are_exact() {
        let core = Rc::new(Core::new(vec![("Source".into(), 3), ("Sink".into(), 1)]));
        let (tx, rx) = local::<u32>(&core, 0, 0, 1, 1);
        let mut src = Ctx::<(), u32>::new(core.clone(), 0, Vec::new(), vec![tx], None);
        let mut snk = Ctx::<u32, ()>::new(core.clone(), 1, vec![rx], Vec::new(), None);
        let futures: Vec<UnitFuture<'_, (UnitStats, Vec<u32>)>> = vec![
            Box::pin(async move {
                for n in 0..3 {
                    src.emit(2, n).await;
                }
                (src.finish().0, Vec::new())
            }),
            Box::pin(async move {
                let mut seen = Vec::new();
                while let Some(n) = snk.next_input().await {
                    seen.push(n);
                    snk.work(5);
                }
                (snk.finish().0, seen)
            }),
        ];
        let out = thread(core, futures).run(None).unwrap().0;
        let (src, snk) = (&out[0].1 .0, &out[1].1);
        assert_eq!(
            (src.busy, src.starved, src.blocked, src.end),
            (6, 0, 2, Cycle(8))
        );
        let (s, seen) = snk;
        assert_eq!(seen, &[0, 1, 2]);
        assert_eq!((s.busy, s.starved, s.blocked, s.end), (15, 5, 0, Cycle(20)));
        assert_eq!((src.items_out, s.items_in), (3, 3));
        assert_eq!(s.max_fifo_occupancy, 1);
    }

    /// Two sources into one merging sink: items are taken by (arrival, port), whatever
    /// order the executor runs the units in. A: items at arrival 2, 5, 8 (port 0); B:
    /// arrival 2, 3 (port 1). Merge order: A0 (2, port 0), B0 (2, port 1), B1 (3), A1 (5),
    /// A2 (8).
    #[test]
    fn executor_merge_takes_items_by_arrival_then_port() {
        for perturb in [None, Some(1), Some(7), Some(99)] {
            let core = Rc::new(
                Core::new(vec![("A".into(), 1), ("B".into(), 1), ("Sink".into(), 1)])
                    .perturbed(perturb),
            );
            let (ta, ra) = local::<(char, u32)>(&core, 0, 0, 2, 8);
            let (tb, rb) = local::<(char, u32)>(&core, 1, 0, 2, 8);
            let mut a = Ctx::<(), (char, u32)>::new(core.clone(), 0, Vec::new(), vec![ta], None);
            let mut b = Ctx::<(), (char, u32)>::new(core.clone(), 1, Vec::new(), vec![tb], None);
            let mut sink =
                Ctx::<(char, u32), ()>::new(core.clone(), 2, vec![ra, rb], Vec::new(), None);
            let futures: Vec<UnitFuture<'_, Vec<(char, u32)>>> = vec![
                Box::pin(async move {
                    for n in 0..3 {
                        a.work(if n == 0 { 1 } else { 2 });
                        a.emit(1, ('A', n)).await;
                    }
                    a.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    b.work(1);
                    b.emit(1, ('B', 0)).await;
                    b.emit(1, ('B', 1)).await;
                    b.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    let mut order = Vec::new();
                    while let Some(item) = sink.next_input().await {
                        order.push(item);
                    }
                    sink.finish();
                    order
                }),
            ];
            let out = thread(core, futures).run(None).unwrap().0;
            assert_eq!(
                out[2].1,
                [('A', 0), ('B', 0), ('B', 1), ('A', 1), ('A', 2)],
                "perturb {perturb:?}"
            );
        }
    }

    /// A unit that pushes once its inputs end (a ROP writing back its caches) can push
    /// before any item its inputs would bring: A sends M one item and ends at 1; M, of
    /// latency 20, forwards nothing and ends at 3; W pushes one item when that end reaches
    /// it (at 4), arriving at the sink at 6; B's item arrives at 11. The sink must take W's
    /// first in every host order, which it can prove only if W's bound follows its input's
    /// end ([`Ctx::pushes_at_end`]): bounded by the items alone, W looks idle until M's
    /// next item could come (after 20 cycles of M's latency), and some order takes B's first.
    #[test]
    fn executor_bounds_a_unit_that_pushes_at_the_end_of_its_inputs() {
        let run = |declared: bool, perturb: Option<u64>| {
            let names = ["A", "M", "W", "B", "Sink"];
            let latency = [1, 20, 1, 1, 1];
            let units = names.iter().zip(latency).map(|(n, l)| (n.to_string(), l));
            let core = Rc::new(Core::new(units.collect()).perturbed(perturb));
            let (ta, ra) = local::<char>(&core, 0, 0, 1, 8);
            let (tm, rm) = local::<char>(&core, 1, 0, 2, 8);
            let (tw, rw) = local::<char>(&core, 2, 0, 4, 8);
            let (tb, rb) = local::<char>(&core, 3, 0, 4, 8);
            let mut a = Ctx::<(), char>::new(core.clone(), 0, Vec::new(), vec![ta], None);
            let mut m = Ctx::<char, char>::new(core.clone(), 1, vec![ra], vec![tm], None);
            let mut w = Ctx::<char, char>::new(core.clone(), 2, vec![rm], vec![tw], None);
            let mut b = Ctx::<(), char>::new(core.clone(), 3, Vec::new(), vec![tb], None);
            let mut sink = Ctx::<char, ()>::new(core.clone(), 4, vec![rw, rb], Vec::new(), None);
            let futures: Vec<UnitFuture<'_, Vec<char>>> = vec![
                Box::pin(async move {
                    a.emit(1, 'a').await;
                    a.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    while m.next_input().await.is_some() {
                        m.work(1);
                    }
                    m.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    if declared {
                        w.pushes_at_end();
                    }
                    while w.next_input().await.is_some() {}
                    w.wait_for_end_of_inputs();
                    w.emit(1, 'w').await;
                    w.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    b.work(9);
                    b.emit(1, 'b').await;
                    b.finish();
                    Vec::new()
                }),
                Box::pin(async move {
                    let mut order = Vec::new();
                    while let Some(item) = sink.next_input().await {
                        order.push(item);
                    }
                    let out_of_order = sink.finish().0.out_of_order;
                    order.push(if out_of_order > 0 { '!' } else { '.' });
                    order
                }),
            ];
            thread(core, futures).run(None).unwrap().0[4].1.clone()
        };
        let orders = [None, Some(1), Some(2), Some(3), Some(7), Some(99)];
        for perturb in orders {
            assert_eq!(run(true, perturb), ['w', 'b', '.'], "perturb {perturb:?}");
        }
        // Undeclared, the bound is wrong and some host order shows it.
        assert!(orders.iter().any(|&p| run(false, p) != ['w', 'b', '.']));
    }

    /// Two units wired into a loop, each waiting for the other's first item: the run stops
    /// at once with a deadlock naming both and what they wait for.
    #[test]
    fn executor_miswired_loop_is_reported_as_a_deadlock() {
        let core = Rc::new(Core::new(vec![("Left".into(), 1), ("Right".into(), 1)]));
        let (t1, r1) = local::<u32>(&core, 0, 0, 1, 2);
        let (t2, r2) = local::<u32>(&core, 1, 0, 0, 2);
        let mk = |unit: u32, rx, tx| -> UnitFuture<'static, ()> {
            let mut c = Ctx::<u32, u32>::new(core.clone(), unit, vec![rx], vec![tx], None);
            Box::pin(async move {
                while let Some(n) = c.next_input().await {
                    c.emit(1, n).await;
                }
                c.finish();
            })
        };
        let futures = vec![mk(0, r2, t1), mk(1, r1, t2)];
        let err = thread(core, futures).run(None).unwrap_err();
        assert_eq!(
            err,
            Halt::Deadlock(vec![
                (0, "Left waits for input from [Right]".to_string()),
                (1, "Right waits for input from [Left]".to_string()),
            ])
        );
    }

    /// The same loop with each unit on its own host thread, joined by links between
    /// threads: the board sees both threads idle with nothing held and reports both units.
    #[test]
    fn executor_miswired_loop_across_host_threads_is_reported_as_a_deadlock() {
        use crate::pipeline::runtime::executor::Board;
        use crate::pipeline::runtime::link::RemoteParts;
        let names = ["Left", "Right"];
        let board = Board::new(2, vec![0, 1]);
        let parts = [
            RemoteParts::<u32>::new(spec(2, 1)),
            RemoteParts::<u32>::new(spec(2, 1)),
        ];
        let started = std::time::Instant::now();
        let results: Vec<_> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..2usize)
                .map(|me| {
                    let (board, parts) = (&board, &parts);
                    s.spawn(move || {
                        let other = 1 - me;
                        let core = Rc::new(Core::new(vec![(names[me].into(), 1)]));
                        let name = |p: usize, c: usize| LinkName {
                            producer: names[p].into(),
                            consumer: names[c].into(),
                        };
                        let out = Ends {
                            producer: 0,
                            port: 0,
                            consumer: u32::MAX,
                            from: me as u32,
                        };
                        let inp = Ends {
                            producer: u32::MAX,
                            port: 0,
                            consumer: 0,
                            from: other as u32,
                        };
                        let peer = board.signals[other].clone();
                        let tx = Rc::new(parts[me].tx(
                            core.clone(),
                            spec(2, 1),
                            name(me, other),
                            out,
                            peer.clone(),
                        ));
                        let rx = Rc::new(parts[other].rx(
                            core.clone(),
                            spec(2, 1),
                            name(other, me),
                            inp,
                            peer,
                        ));
                        core.slots[0]
                            .consumers
                            .borrow_mut()
                            .push((other, names[other].into()));
                        core.slots[0].inputs.borrow_mut().push(rx.clone());
                        let mut c = Ctx::<u32, u32>::new(
                            core.clone(),
                            0,
                            vec![Rx::Remote(rx.clone())],
                            vec![Tx::Remote(tx.clone())],
                            None,
                        );
                        let body: UnitFuture<'static, ()> = Box::pin(async move {
                            while let Some(n) = c.next_input().await {
                                c.emit(1, n).await;
                            }
                            c.finish();
                        });
                        HostThread {
                            core,
                            futures: vec![body],
                            global: vec![me],
                            remotes: vec![tx, rx],
                        }
                        .run(Some((board, me)))
                        .map(|_| ())
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert!(started.elapsed() < std::time::Duration::from_secs(5));
        assert!(board.deadlocked());
        let mut waiting: Vec<(usize, String)> = results
            .into_iter()
            .flat_map(|r| match r {
                Err(Halt::Deadlock(w)) => w,
                other => panic!("{other:?}"),
            })
            .collect();
        waiting.sort();
        assert_eq!(
            waiting,
            [
                (0, "Left waits for input from [Right]".to_string()),
                (1, "Right waits for input from [Left]".to_string()),
            ]
        );
    }

    #[test]
    fn partitions_cover_every_unit_with_valid_threads() {
        assert_eq!(partition(5, 2), [0, 0, 0, 1, 1]);
        assert_eq!(partition(3, 8), [0, 1, 2]);
        assert_eq!(partition(4, 1), [0, 0, 0, 0]);
        let p = partition_at_random(20, 3, 5);
        assert!(p.iter().all(|&t| t < 3));
        assert_eq!(p, partition_at_random(20, 3, 5));
        // Random: not the contiguous runs, and another seed gives another assignment.
        assert_ne!(p, partition(20, 3));
        assert_ne!(p, partition_at_random(20, 3, 6));
        // Through the options, with and without the hook.
        let options = |partition_seed| SimOptions {
            host_threads: 3,
            partition_seed,
            ..SimOptions::default()
        };
        assert_eq!(options(None).partition(20), partition(20, 3));
        assert_eq!(options(Some(5)).partition(20), p);
    }
}
