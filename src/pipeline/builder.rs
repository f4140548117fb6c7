//! Elaboration, after DAM's `ProgramBuilder`: the graph description ([`crate::graph`]) drives
//! it. [`Netlist::new`] checks the description against the units' declarations
//! ([`super::units::bodies`]) before anything runs (every kind has a body, every boundary
//! joins a writer and a reader of the same item type in dataflow order, every unit's ports
//! are connected) and refuses a bad one with a [`GraphError`]; then it instantiates each
//! kind as the architecture says and makes each boundary's typed links. Each host thread
//! then takes its units' bodies from the plan ([`Netlist::bodies`]).
//!
//! A kind may read from several boundaries and write to several, all of its one item type
//! (a memory port fed by the ROPs and by a geometry fetch, a geometry fetch feeding the
//! setup engines and the memory port): its input ports are every feeding boundary's
//! links, boundary by boundary in the graph's order, each boundary's producers in order,
//! all merged by (arrival, port) as one crossbar's are; its output ports likewise, each
//! boundary's a contiguous group. Its items go along the first boundary it feeds that the
//! graph's path takes, dispatched by that boundary's rule ([`crate::graph::Dispatch`]);
//! the others carry nothing.

use super::runtime::executor::UnitFuture;
use super::runtime::{LinkSpec, SimOptions};
use super::unit::{Elaborate, Finished, OutputBoundary, RunInputs};
use super::units::bodies;
use super::wiring::HostWiring;
use crate::config::ArchConfig;
use crate::datapath::Real;
use crate::graph::{self, Dispatch, Graph, GraphError, UnitInstance, UnitKind};
use std::any::Any;

/// How a checked graph is wired: per kind (in the graph's order), the index of its body in
/// [`bodies`] and of the boundaries (in the graph's) that feed it and that it feeds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ports {
    /// The kinds, in dataflow order.
    pub kinds: Vec<UnitKind>,
    /// Each kind's body.
    body: Vec<usize>,
    /// Each kind's input boundaries, in the graph's order; none for a source.
    input: Vec<Vec<usize>>,
    /// Each kind's output boundaries, in the graph's order; none for a sink.
    output: Vec<Vec<usize>>,
}

/// Checks `graph` against the units' declarations in `R`'s datapath; the wiring it implies.
pub fn check<R: Real>(graph: &Graph) -> Result<Ports, GraphError> {
    check_with(graph, &bodies::<R>())
}

fn check_with<R: Real>(
    graph: &Graph,
    bodies: &[Box<dyn Elaborate<R>>],
) -> Result<Ports, GraphError> {
    let kinds = graph.kinds;
    let mut body = Vec::with_capacity(kinds.len());
    for (i, &kind) in kinds.iter().enumerate() {
        if kinds[..i].contains(&kind) {
            return Err(GraphError::Repeated { kind });
        }
        let b = bodies.iter().position(|b| b.kind() == kind);
        body.push(b.ok_or(GraphError::NoBody { kind })?);
    }
    let at = |kind: UnitKind| kinds.iter().position(|&k| k == kind);
    let mut input: Vec<Vec<usize>> = vec![Vec::new(); kinds.len()];
    let mut output: Vec<Vec<usize>> = vec![Vec::new(); kinds.len()];
    for (bi, b) in graph.boundaries.iter().enumerate() {
        let (Some(p), Some(c)) = (at(b.from), at(b.to)) else {
            // A boundary of another path.
            continue;
        };
        if !b.wired_in(kinds, graph.source, graph.dram) {
            // A boundary of the other triangle source.
            continue;
        }
        if p >= c {
            return Err(GraphError::BackEdge { boundary: b.key });
        }
        let written = bodies[body[p]].output().ok_or(GraphError::NoPort {
            boundary: b.key,
            kind: b.from,
        })?;
        let read = bodies[body[c]].input().ok_or(GraphError::NoPort {
            boundary: b.key,
            kind: b.to,
        })?;
        if written.0 != read.0 {
            return Err(GraphError::ItemMismatch {
                boundary: b.key,
                written: written.1,
                read: read.1,
            });
        }
        if b.dispatch == Dispatch::ScreenTile && !bodies[body[p]].on_screen() {
            return Err(GraphError::NotOnScreen { boundary: b.key });
        }
        if let Some(&first) = output[p].iter().find(|&&o| graph.boundaries[o].to == b.to) {
            return Err(GraphError::Fanned {
                kind: b.from,
                first: graph.boundaries[first].key,
                second: b.key,
            });
        }
        output[p].push(bi);
        input[c].push(bi);
    }
    for (i, &kind) in kinds.iter().enumerate() {
        let unit = &bodies[body[i]];
        if unit.input().is_some() && input[i].is_empty() {
            return Err(GraphError::Unfed { kind });
        }
        if unit.output().is_some() && output[i].is_empty() {
            return Err(GraphError::Undrained { kind });
        }
    }
    Ok(Ports {
        kinds: kinds.to_vec(),
        body,
        input,
        output,
    })
}

/// A checked graph instantiated on an architecture, partitioned over host threads, with
/// every boundary's links made: what each host thread elaborates its units from.
pub struct Netlist {
    /// Every unit, in dataflow order (each kind's instances together).
    pub units: Vec<UnitInstance>,
    /// Each unit's latency \[cycles\].
    pub latency: Vec<u64>,
    /// Each unit's host thread.
    pub thread: Vec<usize>,
    /// Host threads.
    pub threads: usize,
    ports: Ports,
    /// The global index of each kind's first unit.
    first: Vec<usize>,
    /// Each boundary's crossbar (a `Crossbar<T>` of its item type) and the index of its
    /// producer's kind, for the boundaries with links.
    crossbars: Vec<Option<(usize, Box<dyn Any + Send + Sync>)>>,
    /// Each boundary's dispatch rule, whether the graph's path takes it, the batch its
    /// consumers take under a rule of batches, and whether it leads to a shared unit.
    rules: Vec<(Dispatch, bool, Option<u32>, bool)>,
}

impl Netlist {
    /// Checks `graph` and instantiates it on `arch` over the host threads `options` asks for.
    pub fn new<R: Real>(
        graph: &Graph,
        arch: &ArchConfig,
        options: &SimOptions,
    ) -> Result<Netlist, GraphError> {
        let bodies = bodies::<R>();
        let ports = check_with(graph, &bodies)?;
        let units = graph::instances(&ports.kinds, |k| arch.unit(k).0);
        let latency = units.iter().map(|u| arch.unit(u.kind).1).collect();
        let first = ports
            .kinds
            .iter()
            .map(|&k| {
                units
                    .iter()
                    .position(|u| u.kind == k)
                    .unwrap_or(units.len())
            })
            .collect();
        let threads = options.host_threads.clamp(1, units.len().max(1));
        let thread = options.partition(units.len());
        let mut crossbars: Vec<Option<(usize, Box<dyn Any + Send + Sync>)>> =
            graph.boundaries.iter().map(|_| None).collect();
        for (p, out) in ports.output.iter().enumerate() {
            // Each boundary's links take the producer's next ports.
            let mut port_base = 0;
            for &bi in out {
                let b = &graph.boundaries[bi];
                let link = arch
                    .links
                    .by_key(b.key)
                    .ok_or(GraphError::NoLink { boundary: b.key })?;
                let mut spec = LinkSpec {
                    fifo_depth: link.fifo_depth,
                    latency_cycles: link.latency_cycles,
                };
                if b.to_shared() {
                    spec.latency_cycles =
                        spec.latency_cycles
                            .max(fetch_request_latency(&ports.kinds, b.to, arch));
                }
                let xb = bodies[ports.body[p]].crossbar(&units, b.to, &thread, spec, port_base);
                port_base += units.iter().filter(|u| u.kind == b.to).count();
                crossbars[bi] = Some((p, xb));
            }
        }
        // A boundary dealt in batches deals its consumers' batch (their own section's).
        let at = |kind: UnitKind| ports.kinds.iter().position(|&k| k == kind);
        let rules = graph
            .boundaries
            .iter()
            .map(|b| {
                let batch = match b.dispatch {
                    Dispatch::Batches => at(b.to).and_then(|k| bodies[ports.body[k]].batch(arch)),
                    _ => None,
                };
                (
                    b.dispatch,
                    b.taken_by(graph.path, graph.source),
                    batch,
                    b.to_shared(),
                )
            })
            .collect();
        Ok(Netlist {
            units,
            latency,
            thread,
            threads,
            ports,
            first,
            crossbars,
            rules,
        })
    }

    /// The bodies of `host`'s units, by local index, with their ends of every link.
    pub fn bodies<'a, R: Real>(
        &self,
        host: &mut HostWiring,
        run: &'a RunInputs<'a, R>,
        trace: Option<usize>,
    ) -> Vec<UnitFuture<'a, Finished>> {
        let bodies = bodies::<R>();
        let mut wired: Vec<Option<Box<dyn Any>>> = self
            .crossbars
            .iter()
            .map(|xb| {
                xb.as_ref()
                    .map(|(p, xb)| bodies[self.ports.body[*p]].wire(host, xb.as_ref()))
            })
            .collect();
        let mut futures = Vec::new();
        for g in (0..self.units.len()).filter(|&g| host.is_local(g)) {
            let k = self
                .ports
                .kinds
                .iter()
                .position(|&k| k == self.units[g].kind)
                .expect("every unit is of a kind of the plan");
            let take = |wired: &mut Vec<Option<Box<dyn Any>>>, boundaries: &[usize]| {
                boundaries
                    .iter()
                    .filter_map(|&b| wired[b].take().map(|w| (b, w)))
                    .collect::<Vec<_>>()
            };
            let mut rx = take(&mut wired, &self.ports.input[k]);
            let mut tx = take(&mut wired, &self.ports.output[k]);
            futures.push(
                bodies[self.ports.body[k]].spawn(
                    host,
                    g,
                    g - self.first[k],
                    rx.iter_mut().map(|(_, w)| w.as_mut()).collect(),
                    tx.iter_mut()
                        .map(|(b, w)| OutputBoundary {
                            wired: w.as_mut(),
                            dispatch: self.rules[*b].0,
                            taken: self.rules[*b].1,
                            batch: self.rules[*b].2,
                            shared: self.rules[*b].3,
                        })
                        .collect(),
                    run,
                    trace,
                ),
            );
            for (b, w) in rx.into_iter().chain(tx) {
                wired[b] = Some(w);
            }
        }
        futures
    }
}

/// The latency the links from a shared unit's direct clients to it need at least, so that it
/// can order their items against those of its other inputs: one more than the cycles the
/// executor may date a unit's pops before the credit that let it go on, summed over every
/// other kind of the graph (`latency - 1` each, [`super::runtime::core::recover`]).
///
/// A geometry fetch's read reaches the DRAM controller after it, while the ROPs' traffic
/// that the fetch's batches lead to comes round the loop of credits (controller, ROP, ...,
/// setup, fetch) whose frozen pipelines each date their next pop up to `latency - 1` before
/// the credit; shorter, the controller could not prove that a read it has not yet received
/// comes after a ROP item it holds, and the run would stop on that loop.
pub fn fetch_request_latency(kinds: &[UnitKind], shared: UnitKind, arch: &ArchConfig) -> u64 {
    1 + kinds
        .iter()
        .filter(|&&k| k != shared)
        .map(|&k| arch.unit(k).1.saturating_sub(1))
        .sum::<u64>()
}

/// The datapath words one item of `kind`'s output takes in a FIFO ([`super::unit::Unit::OUT_WORDS`];
/// 0 for a sink or a kind without a body).
pub fn out_words(kind: UnitKind) -> u32 {
    bodies::<f32>()
        .iter()
        .find(|b| b.kind() == kind)
        .map_or(0, |b| b.out_words())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::{Boundary, LinkConfig, PrimitivePath, TessSource, BOUNDARIES};
    use UnitKind::*;

    fn boundary(key: &'static str, from: UnitKind, to: UnitKind) -> Boundary {
        Boundary {
            key,
            from,
            to,
            default: LinkConfig::default(),
            dispatch: Dispatch::RoundRobin,
            path: None,
            only: None,
            dram_only: false,
        }
    }

    /// Both paths' graphs (the triangle path's with either source) check in both
    /// datapaths: the geometry fetch the source, the frame-buffer port the sink, every
    /// other unit fed and drained by the boundary from and to its neighbour (the fetch
    /// feeds the triangle setup engines directly only from a mesh in memory).
    #[test]
    fn builder_accepts_both_paths() {
        let graphs = [
            (PrimitivePath::Lembo, TessSource::Memory),
            (PrimitivePath::Triangle, TessSource::Memory),
            (PrimitivePath::Triangle, TessSource::OnChip),
        ];
        for (path, source) in graphs {
            let ports = check::<f32>(&Graph::of(path, source)).unwrap();
            assert_eq!(check::<f64>(&Graph::of(path, source)).unwrap(), ports);
            let n = ports.kinds.len();
            assert!(
                ports.input[0].is_empty(),
                "{path:?}: the first unit is a source"
            );
            assert!(
                ports.output[n - 1].is_empty(),
                "{path:?}: the last unit is a sink"
            );
            let ends = |bs: &[usize]| -> Vec<(UnitKind, UnitKind)> {
                bs.iter()
                    .map(|&b| (BOUNDARIES[b].from, BOUNDARIES[b].to))
                    .collect()
            };
            assert_eq!(ports.kinds[0], GeometryFetch);
            for i in 0..n - 1 {
                assert_eq!(ports.output[i].len(), 1);
                assert_eq!(
                    ends(&ports.output[i]),
                    [(ports.kinds[i], ports.kinds[i + 1])]
                );
                assert_eq!(ports.input[i + 1], ports.output[i]);
            }
        }
    }

    /// Each way of mis-wiring the lembo path is refused, before anything runs, with the
    /// error that names it.
    /// The builder's check of a lembo-path graph of `kinds` and `boundaries`.
    fn check_lembo(kinds: &[UnitKind], boundaries: &[Boundary]) -> Result<Ports, GraphError> {
        check::<f32>(&Graph {
            path: PrimitivePath::Lembo,
            kinds,
            boundaries,
            source: TessSource::Memory,
            dram: false,
        })
    }

    #[test]
    fn builder_refuses_a_miswired_graph_with_a_named_error() {
        let lembo = PrimitivePath::Lembo.kinds(TessSource::Memory);
        let check = check_lembo;
        // A boundary left out: the segmenters' output goes nowhere.
        let without: Vec<Boundary> = BOUNDARIES
            .iter()
            .filter(|b| b.key != "segmenter_to_subsegmenter")
            .copied()
            .collect();
        assert_eq!(
            check(lembo, &without),
            Err(GraphError::Undrained { kind: Segmenter })
        );
        // Setup wired straight to the segmenters, which read intervals, not lembos.
        let skipped = [
            boundary("setup_to_segmenter", Setup, Segmenter),
            boundary("segmenter_to_subsegmenter", Segmenter, Subsegmenter),
        ];
        match check(&[Setup, Segmenter, Subsegmenter], &skipped) {
            Err(GraphError::ItemMismatch {
                boundary,
                written,
                read,
            }) => {
                assert_eq!(boundary, "setup_to_segmenter");
                assert!(written.contains("LemboReady<f32>"), "{written}");
                assert!(read.contains("ScanInterval<f32>"), "{read}");
            }
            other => panic!("{other:?}"),
        }
        // A boundary against the dataflow order would close a cycle.
        let mut back = BOUNDARIES.to_vec();
        back.push(boundary(
            "subsegmenter_to_segmenter",
            Subsegmenter,
            Segmenter,
        ));
        assert_eq!(
            check(lembo, &back),
            Err(GraphError::BackEdge {
                boundary: "subsegmenter_to_segmenter"
            })
        );
        // A blend unit sits inside a ROP and has no body of its own.
        let mut with_blend = lembo.to_vec();
        with_blend.insert(with_blend.len() - 1, BlendUnit);
        assert_eq!(
            check(&with_blend, &BOUNDARIES),
            Err(GraphError::NoBody { kind: BlendUnit })
        );
        assert_eq!(
            check(&[Setup, Setup], &BOUNDARIES),
            Err(GraphError::Repeated { kind: Setup })
        );
        // Two boundaries between the same two kinds would make two crossbars of one pair.
        let first = BOUNDARIES[0];
        let mut twice = BOUNDARIES.to_vec();
        twice.insert(1, boundary("first_again", first.from, first.to));
        assert_eq!(
            check(lembo, &twice),
            Err(GraphError::Fanned {
                kind: first.from,
                first: first.key,
                second: "first_again"
            })
        );
        // The frame-buffer port is a sink: a boundary out of it has no port to leave by.
        let out_of_sink = [
            boundary("rop_to_framebuffer", Rop, FrameBuffer),
            boundary("framebuffer_to_setup", FrameBuffer, TriangleSetup),
        ];
        assert_eq!(
            check(&[Rop, FrameBuffer, TriangleSetup], &out_of_sink),
            Err(GraphError::NoPort {
                boundary: "framebuffer_to_setup",
                kind: FrameBuffer
            })
        );
        // A unit that reads but is fed by nothing.
        assert_eq!(
            check(&[MinMax, IntervalManager], &BOUNDARIES),
            Err(GraphError::Unfed { kind: MinMax })
        );
    }

    /// Both rasterizers into the ROPs: a ROP reads from both boundaries, its ports the
    /// lembo rasterizers' then the triangle rasterizers'.
    #[test]
    fn a_rop_reads_both_rasterizers_boundaries_in_dataflow_order() {
        // Every kind with a body of its own that a graph of triangles from memory has:
        // both paths' units (the on-chip tessellation's are fed only from on-chip sources).
        let both: Vec<UnitKind> = crate::graph::KINDS
            .into_iter()
            .filter(|k| k.inside().is_none())
            .filter(|k| {
                [
                    crate::graph::PrimitivePath::Lembo,
                    crate::graph::PrimitivePath::Triangle,
                ]
                .iter()
                .any(|p| p.kinds(TessSource::Memory).contains(k))
            })
            .collect();
        let ports = check_lembo(&both, &BOUNDARIES).unwrap();
        let rop = both.iter().position(|&k| k == Rop).unwrap();
        let keys: Vec<&str> = ports.input[rop]
            .iter()
            .map(|&b| BOUNDARIES[b].key)
            .collect();
        assert_eq!(keys, ["rasterizer_to_rop", "triangle_rasterizer_to_rop"]);
    }

    /// A boundary the architecture has no link for is refused by the plan, and the error
    /// reaches the caller as a simulator fault (exit status 1), not a panic.
    #[test]
    fn plan_refuses_a_boundary_without_a_link() {
        let renamed: Vec<Boundary> = BOUNDARIES
            .iter()
            .enumerate()
            .map(|(i, b)| match i {
                0 => boundary("renamed", b.from, b.to),
                _ => *b,
            })
            .collect();
        let graph = Graph {
            path: PrimitivePath::Lembo,
            kinds: PrimitivePath::Lembo.kinds(TessSource::Memory),
            boundaries: &renamed,
            source: TessSource::Memory,
            dram: false,
        };
        let e = Netlist::new::<f32>(&graph, &ArchConfig::default(), &SimOptions::default())
            .err()
            .unwrap();
        assert_eq!(
            e,
            GraphError::NoLink {
                boundary: "renamed"
            }
        );
        let e = crate::error::Error::from(e);
        assert_eq!(e.exit_code(), 1);
        assert!(e.to_string().contains("mis-wired"), "{e}");
    }

    /// Every boundary's items take at least one word in a FIFO, the producing unit's
    /// declaration, and a kind without a boundary out of it (a sink, a unit inside another)
    /// takes none. The words themselves are priced as FIFO area (cost::model), so the
    /// design-point and cost goldens pin each kind's.
    #[test]
    fn out_words_are_the_hardware_items() {
        for b in BOUNDARIES {
            assert!(out_words(b.from) >= 1, "{}", b.key);
        }
        for k in crate::graph::KINDS {
            if !BOUNDARIES.iter().any(|b| b.from == k) {
                assert_eq!(out_words(k), 0, "{k:?}");
            }
        }
    }

    /// A plan instantiates the architecture's counts, each kind's instances together, and
    /// makes links only for the path's boundaries.
    #[test]
    fn plan_instantiates_the_architecture() {
        let mut arch = ArchConfig::default();
        arch.segmenter.count = 3;
        arch.rop.count = 2;
        let plan = Netlist::new::<f64>(
            &Graph::of(PrimitivePath::Lembo, TessSource::Memory),
            &arch,
            &SimOptions {
                host_threads: 2,
                ..SimOptions::default()
            },
        )
        .unwrap();
        // Each kind of the path as many times as the architecture says, together, named
        // `Kind[i]` when replicated or more than one.
        let mut expected = Vec::new();
        for &kind in PrimitivePath::Lembo.kinds(TessSource::Memory) {
            let (n, latency) = arch.unit(kind);
            for i in 0..n {
                let name = if kind.replicated() || n > 1 {
                    format!("{}[{i}]", kind.name())
                } else {
                    kind.name().to_string()
                };
                expected.push((name, latency));
            }
        }
        let units: Vec<(String, u64)> = plan
            .units
            .iter()
            .zip(&plan.latency)
            .map(|(u, &l)| (u.name.clone(), l))
            .collect();
        assert_eq!(units, expected);
        let named = |prefix: &str| units.iter().filter(|u| u.0.starts_with(prefix)).count();
        assert_eq!((named("Segmenter["), named("Rop[")), (3, 2));
        assert_eq!(plan.threads, 2);
        let linked: Vec<&str> = BOUNDARIES
            .iter()
            .zip(&plan.crossbars)
            .filter(|(_, xb)| xb.is_some())
            .map(|(b, _)| b.key)
            .collect();
        let kinds = PrimitivePath::Lembo.kinds(TessSource::Memory);
        let taken: Vec<&str> = BOUNDARIES
            .iter()
            .filter(|b| b.wired_in(kinds, TessSource::Memory, false))
            .map(|b| b.key)
            .collect();
        assert_eq!(linked, taken);
    }
}
