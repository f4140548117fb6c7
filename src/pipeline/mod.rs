//! The timed pipeline: Figure 5 of Martinelli 2006 as units run by a deterministic
//! discrete-event executor (DESIGN.md §3). Each unit instance is an `async fn` that calls the
//! functional code of [`crate::raster`] and adds only time; the image is bit-identical to
//! the functional model's for every architecture configuration and every host partition.
//!
//! Which units each path instantiates, the boundaries between them and their dispatch
//! rules, and the units they share are [`crate::graph`]'s; `lembo-sim graph` prints them.
//!
//! - [`runtime`]: the framework: clocks, links, the executor, the timeline. It knows no
//!   unit.
//! - [`unit`](mod@unit): what a unit is to the builder ([`unit::Unit`]) and what a run offers it;
//!   [`items`]: what the links carry; [`tiles`]: the ROPs' screen interleave and frame.
//! - [`units`]: one file per box of Figure 5, each using only [`runtime::Ctx`] and its own
//!   context.
//! - [`crate::graph`]: which units each path instantiates and which boundaries carry links,
//!   written once; [`builder`] checks it and elaborates it ([`wiring`]: the links).
//! - this file: a run (plan, units' bodies, host threads) and the cycle report;
//!   [`discoid`]: the timed discoid passes.
//!
//! Model only what a scene requires: a scene without primitives instantiates no units,
//! and each path only its own.

pub mod builder;
pub mod discoid;
pub mod items;
pub mod rop_memory;
pub mod runtime;
pub mod tiles;
pub mod unit;
pub mod units;
pub mod wiring;

pub use crate::graph::{PrimitivePath, UnitInstance, UnitKind};
pub use builder::out_words;
pub use runtime::{Cycle, SimOptions};
pub use unit::{DiscoidPass, FetchReport, Source, VertexCacheCounts};

use crate::camera::View;
use crate::config::{ArchConfig, MemoryModel};
use crate::datapath::{Datapath, Real};
use crate::discoid::report::BlendReport;
use crate::error::{Error, Result};
use crate::frame::discoid::KeptFragment;
use crate::graph::{self, Graph, TessSource};
use crate::raster::Counts;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
use builder::Netlist;
use runtime::executor::{Board, Halt, HostThread, Recoveries};
use runtime::trace;
use serde::Serialize;
use tiles::{RopTiles, SharedFrame};
use unit::{FetchPlan, Finished, NoTriangles, RunInputs, UnitReport};
use wiring::HostWiring;

/// The cycle accounting of one unit over the frame \[cycles\].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitCycles {
    /// The instance's name (`Segmenter[2]`).
    pub name: String,
    /// Its kind.
    pub kind: UnitKind,
    /// Cycles issuing ops.
    pub busy: Cycle,
    /// Cycles waiting for an input to arrive (including after its last op).
    pub starved: Cycle,
    /// Cycles frozen because a FIFO downstream was full.
    pub blocked: Cycle,
    /// Items popped from its input FIFOs \[items\].
    pub items_in: u64,
    /// Items pushed to its output FIFOs \[items\].
    pub items_out: u64,
    /// Most items in any one of its input FIFOs at once \[items\].
    pub max_fifo_occupancy: u64,
}

/// `cycles` in report.json.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CycleReport {
    /// Cycle at which the last unit finished: the last write through the frame-buffer
    /// port, or a later unit that produced nothing \[cycles\].
    pub total: Cycle,
    /// The clock the frame rate is computed at \[MHz\].
    pub clock_mhz: f64,
    /// Frames per second at the clock; null for an empty frame.
    pub fps: Option<f64>,
    /// The unit with the most busy cycles (ties: the first in dataflow order); null when
    /// nothing was instantiated.
    pub bottleneck: Option<String>,
    /// Every instantiated unit's accounting, in dataflow order.
    pub units: Vec<UnitCycles>,
}

impl CycleReport {
    /// `cycles` as a percentage of the frame's total (0 for an empty frame's).
    pub fn percent(&self, cycles: Cycle) -> f64 {
        100.0 * cycles.as_f64() / self.total.0.max(1) as f64
    }
}

/// What a timed run produced.
pub struct TimedFrame {
    /// The image, with depth and winner ids.
    pub framebuffer: FrameBuffer,
    /// The functional counts, gathered from the units.
    pub counts: Counts,
    /// The units the run instantiated, in dataflow order.
    pub units: Vec<UnitInstance>,
    /// The frame's cycle accounting.
    pub cycles: CycleReport,
    /// Chrome trace-event JSON, when requested.
    pub trace: Option<String>,
    /// An accumulation pass's kept fragments and counters, over all ROPs.
    pub discoid: Option<(Vec<KeptFragment>, BlendReport)>,
    /// What the geometry fetch read; None for an empty frame.
    pub fetch: Option<FetchReport>,
    /// How often the executor needed a recovery (host statistics).
    pub recoveries: Recoveries,
    /// The caches, tile tables and DRAM, with the DRAM memory model; None with the port.
    pub memory: Option<rop_memory::MemoryReport>,
    /// The DRAM controller's requests in submission order, with the DRAM model when
    /// [`SimOptions::dram_requests`] asked for them.
    pub dram_requests: Option<Vec<crate::memory::trace::Request>>,
}

/// Renders `scene` on the timed pipeline of `arch`: its lembos on the lembo path, or a
/// triangle source (a tessellation) on the triangle path.
pub fn run_timed(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    arch: &ArchConfig,
    source: Source,
    options: &SimOptions,
) -> Result<TimedFrame> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => run_in::<f32>(scene, view, tol, arch, source, None, options),
        Datapath::F64 => run_in::<f64>(scene, view, tol, arch, source, None, options),
    }
}

/// Sets the run's abort flag if a host thread panics, so the others stop.
struct AbortOnPanic<'b>(&'b Board);

impl Drop for AbortOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.abort();
        }
    }
}

/// [`run_timed`] in datapath `R`, for a discoid pass when `discoid`: on the graph of the
/// source's path, or no units for a scene without primitives.
fn run_in<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    arch: &ArchConfig,
    source: Source,
    discoid: Option<DiscoidPass<R>>,
    options: &SimOptions,
) -> Result<TimedFrame> {
    // Model only what the scene requires: no primitives, no units.
    let path = match source {
        Source::Triangles(t) if t.chunks() == 0 => None,
        Source::Lembos if scene.lembo_count() == 0 => None,
        Source::Lembos => Some(PrimitivePath::Lembo),
        Source::Triangles(_) => Some(PrimitivePath::Triangle),
    };
    let Some(path) = path else {
        return Ok(empty_frame(scene, view, arch));
    };
    // A discoid pass's triangles are planar discoids in memory, whatever the tessellation.
    let tess = match discoid {
        Some(_) => TessSource::Memory,
        None => arch.tessellation.source,
    };
    let graph = Graph::of(path, tess).with_dram(arch.memory.model == MemoryModel::Dram);
    run_on::<R>(&graph, scene, view, tol, arch, source, discoid, options)
}

/// The frame buffer `scene` starts from: its background, nothing drawn.
fn blank(scene: &Scene, view: &View) -> FrameBuffer {
    let vp = view.viewport;
    let background = scene.background.map(crate::rop::shade::to_u8::<f64>);
    FrameBuffer::new(vp.width, vp.height, background, false)
}

/// The frame of a scene without primitives: its background, no units, no cycles.
fn empty_frame(scene: &Scene, view: &View, arch: &ArchConfig) -> TimedFrame {
    TimedFrame {
        framebuffer: blank(scene, view),
        counts: Counts::default(),
        units: Vec::new(),
        cycles: CycleReport {
            total: Cycle::ZERO,
            clock_mhz: arch.clock_mhz,
            fps: None,
            bottleneck: None,
            units: Vec::new(),
        },
        trace: None,
        discoid: None,
        fetch: None,
        memory: None,
        dram_requests: None,
        recoveries: Recoveries::default(),
    }
}

/// [`run_in`] on `graph` (its path's, or a test's).
#[allow(clippy::too_many_arguments)]
fn run_on<R: Real>(
    graph: &Graph,
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    arch: &ArchConfig,
    source: Source,
    discoid: Option<DiscoidPass<R>>,
    options: &SimOptions,
) -> Result<TimedFrame> {
    let vp = view.viewport;
    let mut fb = blank(scene, view);
    let plan = Netlist::new::<R>(graph, arch, options)?;
    let discoids = discoid.is_some();
    let trace_cap = options.trace_event_cap / plan.units.len();
    let trace = options.trace.then_some(trace_cap);
    let fetch = FetchPlan::new(arch, source, graph.source, scene.lembo_count(), discoids);
    // What a person watching sees advance: the primitives fetched, counted by the runtime
    // as they leave the source (`Dispatcher::with_progress`).
    crate::progress::add_total(fetch.primitives);
    let run = RunInputs {
        scene,
        view,
        arch,
        port: &arch.framebuffer,
        k: R::of(tol.k),
        perspective_tol: tol.perspective,
        fetch,
        triangles: match source {
            Source::Triangles(t) => t,
            Source::Lembos => &NoTriangles,
        },
        tiles: RopTiles::new(vp.width, vp.height, arch.rop.tile_px, arch.rop.count),
        discoid,
        frame: SharedFrame::new(&mut fb),
        dram_requests: options.dram_requests,
    };
    let (mut results, recoveries) = execute(&plan, options, &run, trace)?;
    results.sort_by_key(|(u, _)| *u);
    let mut frame = finish(arch, fb, plan.units, results, options, trace_cap)?;
    frame.recoveries = recoveries;
    if discoids {
        // The blend units sit in the ROPs: listed (and priced) with the units, their cycles
        // the ROPs'.
        let kinds = graph::kinds(graph.path, graph.source, true);
        frame.units = graph::instances(&kinds, |k| arch.unit(k).0);
    }
    Ok(frame)
}

/// Runs the units of `plan` on one host thread or several: every unit's result with the
/// recoveries the executor needed, or why the run stopped.
fn execute<'a, R: Real>(
    plan: &Netlist,
    options: &SimOptions,
    run: &'a RunInputs<'a, R>,
    trace: Option<usize>,
) -> Result<(Vec<(usize, Finished)>, Recoveries)> {
    let outcome = if plan.threads == 1 {
        let mut host = HostWiring::new(&plan.units, &plan.latency, &plan.thread, 0, options, &[]);
        let futures = plan.bodies(&mut host, run, trace);
        HostThread {
            core: host.core.clone(),
            futures,
            global: (0..plan.units.len()).collect(),
            remotes: host.remotes,
        }
        .run(None)
    } else {
        run_threads(plan, options, run, trace)?
    };
    match outcome {
        Ok(r) => Ok(r),
        Err(Halt::Deadlock(waiting)) => Err(Error::Deadlock {
            waiting: waiting.into_iter().map(|(_, w)| w).collect(),
        }),
        Err(Halt::Aborted) => Err(Error::Internal("the timed run was aborted".into())),
    }
}

/// How the executor left a run: every unit's result (by global index) with the recoveries
/// it needed, or why it stopped.
type Outcome = std::result::Result<(Vec<(usize, Finished)>, Recoveries), Halt>;

/// The units' results of a run over several host threads, one scoped OS thread each; a
/// panic or a failure on one aborts the others.
fn run_threads<'a, R: Real>(
    plan: &Netlist,
    options: &SimOptions,
    run: &'a RunInputs<'a, R>,
    trace: Option<usize>,
) -> Result<Outcome> {
    let (units, thread, threads) = (&plan.units, &plan.thread, plan.threads);
    let board = Board::new(threads, thread.to_vec());
    let outcome = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|me| {
                let board = &board;
                std::thread::Builder::new()
                    .name(format!("lembo-sim host {me}"))
                    .spawn_scoped(s, move || {
                        let _guard = AbortOnPanic(board);
                        let mut host = HostWiring::new(
                            &plan.units,
                            &plan.latency,
                            &plan.thread,
                            me,
                            options,
                            &board.signals,
                        );
                        let futures = plan.bodies(&mut host, run, trace);
                        let global = (0..units.len()).filter(|&g| thread[g] == me).collect();
                        let r = HostThread {
                            core: host.core.clone(),
                            futures,
                            global,
                            remotes: host.remotes,
                        }
                        .run(Some((board, me)));
                        if r.is_err() {
                            board.abort();
                        }
                        r
                    })
            })
            .collect();
        let mut all = Vec::new();
        let mut waiting = Vec::new();
        let mut failure = None;
        for h in handles {
            match h
                .map_err(|e| Error::Internal(format!("cannot start a host thread: {e}")))?
                .join()
            {
                Err(_) => {
                    failure = Some(Error::Internal(
                        "a host thread of the timed model panicked".into(),
                    ))
                }
                Ok(Ok((done, _))) => all.extend(done),
                Ok(Err(Halt::Deadlock(w))) => waiting.extend(w),
                Ok(Err(Halt::Aborted)) => {}
            }
        }
        if let Some(e) = failure {
            return Err(e);
        }
        if board.deadlocked() {
            waiting.sort();
            return Ok(Err(Halt::Deadlock(waiting)));
        }
        if all.len() != units.len() {
            return Err(Error::Internal("a unit stopped without a result".into()));
        }
        Ok(Ok((all, board.recoveries())))
    })?;
    Ok(outcome)
}

/// The frame's cycle report, counts and timeline from every unit's result.
fn finish(
    arch: &ArchConfig,
    fb: FrameBuffer,
    units: Vec<UnitInstance>,
    mut results: Vec<(usize, Finished)>,
    options: &SimOptions,
    trace_cap: usize,
) -> Result<TimedFrame> {
    if let Some((u, _)) = results.iter().find(|(_, f)| f.stats.out_of_order > 0) {
        return Err(Error::Internal(format!(
            "the timed model's {} took items out of merge order",
            units[*u].name
        )));
    }
    if let Some(e) = first_error(&mut results) {
        return Err(e);
    }
    let last = results
        .iter()
        .map(|(_, f)| f.stats.end)
        .max()
        .unwrap_or(Cycle::ZERO);
    let (total, direct) = shared_ports(
        &units,
        &results,
        last,
        arch.memory.model == MemoryModel::Dram,
    );
    let mut counts = Counts::default();
    let mut fetch = None;
    let (mut rops, mut dram, mut dram_requests) = (None::<rop_memory::RopMemoryStats>, None, None);
    for (_, f) in &mut results {
        counts += f.counts;
        match &mut f.own {
            Some(UnitReport::Fetch(report)) => fetch = fetch.or(Some(*report)),
            Some(UnitReport::RopMemory(m)) => rops.get_or_insert_with(Default::default).add(m),
            Some(UnitReport::Dram(d, c, requests)) => {
                dram = Some((*d, *c));
                dram_requests = requests.take();
            }
            _ => {}
        }
    }
    let memory = dram.map(|(d, c)| {
        rop_memory::MemoryReport::new(&arch.memory.dram_config(), rops.unwrap_or_default(), &d, &c)
    });
    counts.pixels_covered = fb.covered() as u64;
    let unit_cycles = unit_cycles(&units, &results, &direct, total);
    let trace = options.trace.then(|| {
        let tracks: Vec<trace::Track> = results
            .iter()
            .filter_map(|(u, f)| {
                f.trace.as_ref().map(|recorder| trace::Track {
                    name: &units[*u].name,
                    kind: units[*u].kind.name(),
                    recorder,
                })
            })
            .collect();
        trace::chrome_json(&tracks, arch.clock_mhz, total.0, trace_cap)
    });
    let cycles = CycleReport {
        total,
        clock_mhz: arch.clock_mhz,
        fps: (total > Cycle::ZERO).then(|| arch.clock_mhz * 1e6 / total.as_f64()),
        bottleneck: bottleneck(&unit_cycles),
        units: unit_cycles,
    };
    Ok(TimedFrame {
        framebuffer: fb,
        counts,
        units,
        cycles,
        trace,
        discoid: kept_fragments(&mut results),
        fetch,
        recoveries: Recoveries::default(),
        memory,
        dram_requests,
    })
}

/// The first functional error the units recorded, in scene order (taken out of them).
fn first_error(results: &mut [(usize, Finished)]) -> Option<Error> {
    let key = |e: &Error| match e {
        Error::SegmentCap {
            lembo, scanline, ..
        } => (*lembo, *scanline),
        _ => (usize::MAX, u32::MAX),
    };
    let mut first: Option<Error> = None;
    for (_, f) in results {
        if let Some(e) = f.error.take() {
            if first.as_ref().is_none_or(|f| key(&e) < key(f)) {
                first = Some(e);
            }
        }
    }
    first
}

/// The shared units of the graph ([`graph::SHARED`]): the frame's total, at least `last`
/// and at least each shared port's busy cycles with its direct clients' (whose busy cycles
/// are its accesses too), and the direct clients' busy cycles each port unit is charged.
/// With the DRAM controller (`dram`) the clients' reads go through it in time
/// ([`Boundary::dram_only`](graph::Boundary::dram_only)), so the frame is `last`.
fn shared_ports(
    units: &[UnitInstance],
    results: &[(usize, Finished)],
    last: Cycle,
    dram: bool,
) -> (Cycle, Vec<(UnitKind, u64)>) {
    if dram {
        return (last, Vec::new());
    }
    let of_kind = |kind: UnitKind| {
        results
            .iter()
            .filter(|(u, _)| units[*u].kind == kind)
            .map(|(_, f)| f.stats.busy)
            .sum::<u64>()
    };
    let mut total = last;
    let mut direct = Vec::new();
    for shared in graph::SHARED {
        let reads: u64 = shared.direct.iter().map(|&k| of_kind(k)).sum();
        total = total.max(Cycle(of_kind(shared.port) + reads));
        direct.push((shared.port, reads));
    }
    (total, direct)
}

/// Every unit's accounting over a frame of `total` cycles, a shared port's unit charged
/// its direct clients' accesses (`direct`) out of its idle cycles.
fn unit_cycles(
    units: &[UnitInstance],
    results: &[(usize, Finished)],
    direct: &[(UnitKind, u64)],
    total: Cycle,
) -> Vec<UnitCycles> {
    results
        .iter()
        .map(|(u, f)| {
            let st = &f.stats;
            let kind = units[*u].kind;
            let reads: u64 = direct
                .iter()
                .filter(|(port, _)| *port == kind)
                .map(|(_, r)| r)
                .sum();
            UnitCycles {
                name: units[*u].name.clone(),
                kind,
                busy: Cycle(st.busy + reads),
                starved: Cycle((st.starved + (total - st.end)).saturating_sub(reads)),
                blocked: Cycle(st.blocked),
                items_in: st.items_in,
                items_out: st.items_out,
                max_fifo_occupancy: st.max_fifo_occupancy,
            }
        })
        .collect()
}

/// The unit with the most busy cycles, the first in dataflow order on a tie.
fn bottleneck(units: &[UnitCycles]) -> Option<String> {
    units
        .iter()
        .fold(None::<&UnitCycles>, |best, u| match best {
            Some(b) if b.busy >= u.busy => Some(b),
            _ => Some(u),
        })
        .map(|u| u.name.clone())
}

/// An accumulation pass's kept fragments and counters over every ROP (taken out of them);
/// None when no unit kept any.
fn kept_fragments(results: &mut [(usize, Finished)]) -> Option<(Vec<KeptFragment>, BlendReport)> {
    let mut discoid: Option<(Vec<KeptFragment>, BlendReport)> = None;
    for (_, f) in results {
        if !matches!(f.own, Some(UnitReport::Kept(..))) {
            continue;
        }
        if let Some(UnitReport::Kept(pending, report)) = f.own.take() {
            let (all, sum) = discoid.get_or_insert_with(Default::default);
            all.extend(pending);
            sum.culled_backface += report.culled_backface;
            sum.discarded_beta_zero += report.discarded_beta_zero;
            sum.discarded_threshold += report.discarded_threshold;
        }
    }
    discoid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::BOUNDARIES;

    /// A kind may read from several boundaries: the ROPs fed by both paths' rasterizers
    /// (the triangle units idle on a lembo scene) merge the extra ports with the lembo
    /// rasterizers' and draw the lembo path's frame in the same cycles, unit for unit,
    /// over one host thread or three.
    #[test]
    fn a_unit_fed_by_two_boundaries_merges_them_as_one_crossbar() {
        use UnitKind::*;
        let mut scene = Scene::default_scene();
        scene.set_viewport(96, 96).unwrap();
        let view = View::new(&scene.camera, scene.viewport);
        let tol = Tolerance::from(0.5);
        let arch = ArchConfig::default();
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
        let graph = Graph {
            path: PrimitivePath::Lembo,
            kinds: &both,
            boundaries: &BOUNDARIES,
            source: TessSource::Memory,
            dram: false,
        };
        for threads in [1, 3] {
            let options = SimOptions {
                host_threads: threads,
                ..SimOptions::default()
            };
            let plain = run_in::<f32>(&scene, &view, tol, &arch, Source::Lembos, None, &options);
            let fanned = run_on::<f32>(
                &graph,
                &scene,
                &view,
                tol,
                &arch,
                Source::Lembos,
                None,
                &options,
            );
            let (plain, fanned) = (plain.unwrap(), fanned.unwrap());
            assert!(plain.framebuffer.color == fanned.framebuffer.color);
            assert_eq!(plain.counts, fanned.counts);
            assert_eq!(plain.cycles.total, fanned.cycles.total);
            for u in &plain.cycles.units {
                let f = fanned
                    .cycles
                    .units
                    .iter()
                    .find(|f| f.name == u.name)
                    .unwrap();
                assert_eq!(u, f, "{} over {threads} host threads", u.name);
            }
            // The triangle units are there, fed nothing.
            let extra: Vec<_> = fanned
                .cycles
                .units
                .iter()
                .filter(|u| matches!(u.kind, TriangleSetup | TriangleRasterizer))
                .collect();
            assert_eq!(extra.len(), 2);
            assert!(extra.iter().all(|u| u.items_in == 0 && u.items_out == 0));
        }
    }

    /// The ROPs write the shared frame in place, unsynchronised (`tiles::RopPixels`): they
    /// draw the same pixels over one host thread or two, with either memory model. Small
    /// enough for Miri and valgrind (`tests/unsafe/run`), which check those writes.
    #[test]
    fn the_rops_draw_the_same_frame_over_any_threads_and_memory_model() {
        let mut scene = Scene::default_scene();
        let size = if cfg!(miri) { 20 } else { 64 };
        scene.set_viewport(size, size).unwrap();
        let view = View::new(&scene.camera, scene.viewport);
        let mut frames = Vec::new();
        for model in [MemoryModel::Port, MemoryModel::Dram] {
            for threads in [1, 2] {
                let mut arch = ArchConfig::default();
                arch.memory.model = model;
                let options = SimOptions {
                    host_threads: threads,
                    ..SimOptions::default()
                };
                let frame = run_timed(
                    &scene,
                    &view,
                    0.5,
                    Datapath::F32,
                    &arch,
                    Source::Lembos,
                    &options,
                )
                .unwrap();
                frames.push(frame.framebuffer);
            }
        }
        let drawn = frames[0]
            .primitive
            .iter()
            .filter(|&&p| p != crate::rop::framebuffer::NO_PRIMITIVE)
            .count();
        assert!(drawn > (size * size / 8) as usize, "{drawn} pixels drawn");
        let bits = |fb: &FrameBuffer| fb.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
        let first = bits(&frames[0]);
        for f in &frames[1..] {
            assert!(f.color == frames[0].color && f.primitive == frames[0].primitive);
            assert!(bits(f) == first);
        }
    }
}
