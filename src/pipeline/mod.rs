//! The timed pipeline: Figure 5 of Martinelli 2006 as units run by a deterministic
//! discrete-event executor (DESIGN.md §3). Each unit instance is an `async fn` that calls the
//! functional code of [`crate::raster`] and adds only time; the image is bit-identical to
//! the functional model's for every architecture configuration and every host partition.
//!
//! ```text
//!  Setup ─► MinMax ─► IntervalManager ─┬► Segmenter[0..Ns] ─┬► Subsegmenter[0..Nb] ─┬► FragmentRasterizer[0..Nr] ─┬► Rop[0..Np] ─► FrameBuffer
//!                                      round-robin          round-robin             round-robin                   by screen tile   (memory port)
//! ```
//!
//! The triangle path instantiates instead
//! `TriangleSetup ─► TriangleRasterizer[0..Nt] ─► Rop[0..Np] ─► FrameBuffer`, the same ROPs
//! and port.
//!
//! - [`runtime`]: the framework: clocks, links, the executor, the timeline. It knows no
//!   unit.
//! - [`units`]: one file per box of Figure 5, each using only [`runtime::Ctx`].
//! - [`graph`]: which units each path instantiates and which boundaries carry links,
//!   written once.
//! - this file: elaboration (units, links, host threads) and the cycle report;
//!   [`discoid`]: the timed discoid passes.
//!
//! Model only what a scene requires: a scene without primitives instantiates no units,
//! and each path only its own.

pub mod discoid;
pub mod graph;
pub mod runtime;
pub mod units;

pub use graph::{fifo_entries, lembo_units, triangle_units, Path, UnitInstance, UnitKind};
pub use runtime::{Cycle, SimOptions};

use crate::camera::View;
use crate::config::ArchConfig;
use crate::datapath::{Datapath, Real};
use crate::discoid::blend::BlendMode;
use crate::discoid::render::{BlendReport, DiscoidTable, KeptFragment, Pass};
use crate::error::{Error, Result};
use crate::raster::setup::ScreenLembo;
use crate::raster::triangle::{ScreenTriangle, TriangleSource};
use crate::raster::Counts;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
use runtime::core::Core;
use runtime::executor::{Board, HostThread, Recoveries, Signal, Stop, UnitFuture};
use runtime::link::{local_link, Ends, RemoteEnd, RemoteParts, Rx, Tx};
use runtime::trace::{self, Recorder};
use runtime::{Ctx, LinkName, LinkSpec, UnitStats};
use serde::Serialize;
use std::ops::Range;
use std::rc::Rc;
use std::sync::{Arc, OnceLock};
use units::interval_manager::ScanInterval;
use units::minmax::ScanlineRange;
use units::rop::{RopItem, RopTiles, SharedFrame, WriteBurst};
use units::segmenter::ScanSegment;
use units::setup::LemboReady;
use units::subsegmenter::ScanSubsegment;

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
    /// How often the executor needed a recovery (host statistics).
    pub recoveries: Recoveries,
}

/// Read-only state the units share: the scene, the configuration and the lembo table.
pub struct Shared<'a, R> {
    /// The scene being drawn.
    pub scene: &'a Scene,
    /// Its camera and viewport.
    pub view: &'a View,
    /// The architecture the units' costs come from.
    pub arch: &'a ArchConfig,
    /// Tolerance k in the datapath's precision \[pixels\].
    pub k: R,
    /// Setup's perspective tolerance \[pixels\]; None: the paper's Setup.
    pub perspective_tol: Option<f64>,
    /// Background colour, 8 bits per channel.
    pub background: [u8; 3],
    /// Screen-space lembos by id, each whole or as the pieces Setup split it into, filled by
    /// Setup before it sends their ids downstream (empty in the triangle path).
    pub lembos: Vec<OnceLock<Vec<ScreenLembo<R>>>>,
    /// What this run draws; the triangle path's units read their triangles from it.
    pub source: Source<'a>,
    /// Which ROP owns each screen tile.
    pub tiles: RopTiles,
    /// The discoid pass the ROPs run; None for ordinary rendering.
    pub discoid: Option<DiscoidPass<'a, R>>,
}

/// What the ROPs need for a discoid pass.
pub struct DiscoidPass<'a, R> {
    /// Which of the passes this run is.
    pub pass: Pass,
    /// The discoids' texture coordinates and shading inputs by primitive id.
    pub table: &'a DiscoidTable<R>,
    /// Precision of the blend units.
    pub mode: BlendMode,
    /// The accumulation threshold t \[world units\].
    pub threshold: f64,
    /// The depth pass's result, whole frame: depth and winner per pixel (accumulation pass).
    pub depth: &'a [f32],
    /// The depth pass's winning primitive id per pixel.
    pub winner: &'a [u32],
}

impl<R> Shared<'_, R> {
    /// The screen-space lembo (or piece) `id`, which Setup filled before sending the id.
    #[inline]
    pub fn lembo(&self, id: PieceId) -> &ScreenLembo<R> {
        &self.lembos[id.lembo as usize]
            .get()
            .expect("Setup fills a lembo's entry before it sends the id")[id.piece as usize]
    }
}

/// An entry of the lembo table: piece `piece` of lembo `lembo` (piece 0 of a lembo Setup
/// kept whole).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PieceId {
    /// The lembo's id in the scene.
    pub lembo: u32,
    /// The piece's index among those Setup split the lembo into.
    pub piece: u32,
}

/// What a unit hands back when it ends.
pub struct Finished {
    /// Its busy, starved and blocked cycles and item counts.
    pub stats: UnitStats,
    /// Its timeline events, when traced.
    pub trace: Option<Recorder>,
    /// The unit's share of the functional counts.
    pub counts: Counts,
    /// A functional error the unit recorded (the run still ends normally).
    pub error: Option<Error>,
    /// A ROP's accumulation-pass output in a discoid pass: the fragments it kept and its
    /// counters.
    pub discoid: Option<(Vec<KeptFragment>, BlendReport)>,
}

impl Finished {
    /// Ends `ctx`'s outputs and collects its counters with the unit's `counts`.
    pub fn new<I, O>(ctx: Ctx<I, O>, counts: Counts) -> Self {
        let (stats, trace) = ctx.finish();
        Finished {
            stats,
            trace,
            counts,
            error: None,
            discoid: None,
        }
    }
}
/// What the timed pipeline draws.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// The scene's lembos, on the lembo path (Figure 5).
    Lembos,
    /// Triangles (a tessellation of the scene, or a discoid atlas's planar quads), on the
    /// triangle path.
    Triangles(&'a dyn TriangleSource),
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

/// The links of one boundary of [`graph::BOUNDARIES`]: producers `producers` to consumers
/// `consumers` (global unit indices), each link configured as `arch.links` says for that
/// boundary, with the channels of each link whose ends are on different host threads.
struct Crossbar<T> {
    producers: Range<usize>,
    consumers: Range<usize>,
    spec: LinkSpec,
    /// By producer position * consumers + consumer position.
    remote: Vec<Option<RemoteParts<T>>>,
}

impl<T> Crossbar<T> {
    fn new(
        units: &[UnitInstance],
        from: UnitKind,
        to: UnitKind,
        thread: &[usize],
        arch: &ArchConfig,
    ) -> Self {
        let c = arch.links.get(from, to);
        let of = |kind: UnitKind| {
            let first = units.iter().position(|u| u.kind == kind).unwrap_or(0);
            first..first + units.iter().filter(|u| u.kind == kind).count()
        };
        let (producers, consumers) = (of(from), of(to));
        let spec = LinkSpec {
            fifo_depth: c.fifo_depth,
            latency_cycles: c.latency_cycles,
        };
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
            remote,
        }
    }
}

/// Builds one host thread's share of the graph: its core and its ends of every link.
struct Builder<'p> {
    units: &'p [UnitInstance],
    thread: &'p [usize],
    me: usize,
    core: Rc<Core>,
    /// Local index of each global unit on this thread.
    local: Vec<Option<u32>>,
    remotes: Vec<Rc<dyn RemoteEnd>>,
    /// One per host thread; empty when there is only one.
    signals: &'p [Arc<Signal>],
}

impl<'p> Builder<'p> {
    fn new(
        units: &'p [(UnitInstance, u64)],
        names: &'p [UnitInstance],
        thread: &'p [usize],
        me: usize,
        perturb: Option<u64>,
        signals: &'p [Arc<Signal>],
    ) -> Self {
        let mut local = vec![None; units.len()];
        let mut mine = Vec::new();
        for (g, (u, latency)) in units.iter().enumerate() {
            if thread[g] == me {
                local[g] = Some(mine.len() as u32);
                mine.push((u.name.clone(), *latency));
            }
        }
        Builder {
            units: names,
            thread,
            me,
            core: Rc::new(Core::new(mine, perturb.map(|p| p ^ me as u64))),
            local,
            remotes: Vec::new(),
            signals,
        }
    }

    /// This thread's ends of `xb`'s links: `tx[p]` the outputs of producer position p,
    /// `rx[c]` the inputs of consumer position c (empty for units of other threads).
    #[allow(clippy::type_complexity)]
    fn wire<T: Send + 'static>(&mut self, xb: &Crossbar<T>) -> (Vec<Vec<Tx<T>>>, Vec<Vec<Rx<T>>>) {
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
                    port: ci as u32,
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
                    _ => {}
                }
            }
        }
        (tx, rx)
    }

    fn ctx<I, O>(
        &self,
        g: usize,
        inputs: Vec<Rx<I>>,
        outputs: Vec<Tx<O>>,
        trace: Option<usize>,
    ) -> Ctx<I, O> {
        let u = self.local[g].expect("a unit of this thread");
        Ctx::new(self.core.clone(), u, inputs, outputs, trace)
    }
}

/// The typed links of a run, one crossbar per boundary of its path (made once per run, so
/// the variants' sizes do not matter).
#[allow(clippy::large_enum_variant)]
enum Bars<R> {
    Lembo {
        setup: Crossbar<LemboReady>,
        minmax: Crossbar<ScanlineRange>,
        intervals: Crossbar<ScanInterval<R>>,
        segments: Crossbar<ScanSegment<R>>,
        subsegments: Crossbar<ScanSubsegment<R>>,
        spans: Crossbar<RopItem<R>>,
        bursts: Crossbar<WriteBurst>,
    },
    Triangle {
        triangles: Crossbar<Arc<ScreenTriangle<R>>>,
        pieces: Crossbar<RopItem<R>>,
        bursts: Crossbar<WriteBurst>,
    },
}

impl<R: Real> Bars<R> {
    fn new(path: Path, arch: &ArchConfig, units: &[UnitInstance], thread: &[usize]) -> Self {
        use UnitKind::*;
        match path {
            Path::Lembo => Bars::Lembo {
                setup: Crossbar::new(units, Setup, MinMax, thread, arch),
                minmax: Crossbar::new(units, MinMax, IntervalManager, thread, arch),
                intervals: Crossbar::new(units, IntervalManager, Segmenter, thread, arch),
                segments: Crossbar::new(units, Segmenter, Subsegmenter, thread, arch),
                subsegments: Crossbar::new(units, Subsegmenter, FragmentRasterizer, thread, arch),
                spans: Crossbar::new(units, FragmentRasterizer, Rop, thread, arch),
                bursts: Crossbar::new(units, Rop, FrameBuffer, thread, arch),
            },
            Path::Triangle => Bars::Triangle {
                triangles: Crossbar::new(units, TriangleSetup, TriangleRasterizer, thread, arch),
                pieces: Crossbar::new(units, TriangleRasterizer, Rop, thread, arch),
                bursts: Crossbar::new(units, Rop, FrameBuffer, thread, arch),
            },
        }
    }
}

/// Builds host thread `b.me`'s units: their links and their bodies, in local order.
fn build<'a, R: Real>(
    b: &mut Builder,
    bars: &Bars<R>,
    sh: &'a Shared<'a, R>,
    frame: &'a SharedFrame<'a>,
    trace: Option<usize>,
) -> Vec<UnitFuture<'a, Finished>> {
    use UnitKind::*;
    let mut futures: Vec<UnitFuture<'a, Finished>> = Vec::new();
    let n = b.units.len();
    let pos =
        |g: usize, kind: UnitKind| g - b.units.iter().position(|u| u.kind == kind).unwrap_or(0);
    match bars {
        Bars::Lembo {
            setup,
            minmax,
            intervals,
            segments,
            subsegments,
            spans,
            bursts,
        } => {
            let (mut s_tx, mut m_rx) = b.wire(setup);
            let (mut m_tx, mut i_rx) = b.wire(minmax);
            let (mut i_tx, mut g_rx) = b.wire(intervals);
            let (mut g_tx, mut b_rx) = b.wire(segments);
            let (mut b_tx, mut r_rx) = b.wire(subsegments);
            let (mut r_tx, rop_in) = b.wire(spans);
            let mut back = BackEnd::wire(b, rop_in, bursts);
            for g in (0..n).filter(|&g| b.local[g].is_some()) {
                let kind = b.units[g].kind;
                let i = pos(g, kind);
                let body: UnitFuture<'a, Finished> = match kind {
                    Setup => Box::pin(units::setup::run(
                        b.ctx(g, Vec::new(), take(&mut s_tx, i), trace),
                        sh,
                    )),
                    MinMax => Box::pin(units::minmax::run(
                        b.ctx(g, take(&mut m_rx, i), take(&mut m_tx, i), trace),
                        sh,
                    )),
                    IntervalManager => Box::pin(units::interval_manager::run(
                        b.ctx(g, take(&mut i_rx, i), take(&mut i_tx, i), trace),
                        sh,
                    )),
                    Segmenter => Box::pin(units::segmenter::run(
                        b.ctx(g, take(&mut g_rx, i), take(&mut g_tx, i), trace),
                        sh,
                    )),
                    Subsegmenter => Box::pin(units::subsegmenter::run(
                        b.ctx(g, take(&mut b_rx, i), take(&mut b_tx, i), trace),
                        sh,
                    )),
                    FragmentRasterizer => Box::pin(units::rasterizer::run(
                        b.ctx(g, take(&mut r_rx, i), take(&mut r_tx, i), trace),
                        sh,
                    )),
                    Rop | FrameBuffer => back.body(b, g, i, sh, frame, trace),
                    other => unreachable!("{other:?} is not on the lembo path"),
                };
                futures.push(body);
            }
        }
        Bars::Triangle {
            triangles,
            pieces,
            bursts,
        } => {
            let (mut s_tx, mut r_rx) = b.wire(triangles);
            let (mut r_tx, rop_in) = b.wire(pieces);
            let mut back = BackEnd::wire(b, rop_in, bursts);
            for g in (0..n).filter(|&g| b.local[g].is_some()) {
                let kind = b.units[g].kind;
                let i = pos(g, kind);
                let body: UnitFuture<'a, Finished> = match kind {
                    TriangleSetup => Box::pin(units::triangle_setup::run(
                        b.ctx(g, Vec::new(), take(&mut s_tx, i), trace),
                        sh,
                    )),
                    TriangleRasterizer => Box::pin(units::triangle_rasterizer::run(
                        b.ctx(g, take(&mut r_rx, i), take(&mut r_tx, i), trace),
                        sh,
                    )),
                    Rop | FrameBuffer => back.body(b, g, i, sh, frame, trace),
                    other => unreachable!("{other:?} is not on the triangle path"),
                };
                futures.push(body);
            }
        }
    }
    futures
}

/// The back end both paths share: the ROPs' inputs and outputs and the frame-buffer
/// port's inputs on one host thread.
struct BackEnd<R> {
    rop_in: Vec<Vec<Rx<RopItem<R>>>>,
    rop_out: Vec<Vec<Tx<WriteBurst>>>,
    port_in: Vec<Vec<Rx<WriteBurst>>>,
}

impl<R: Real> BackEnd<R> {
    fn wire(
        b: &mut Builder,
        rop_in: Vec<Vec<Rx<RopItem<R>>>>,
        bursts: &Crossbar<WriteBurst>,
    ) -> Self {
        let (rop_out, port_in) = b.wire(bursts);
        BackEnd {
            rop_in,
            rop_out,
            port_in,
        }
    }

    /// The body of unit `g`, ROP `i` or the port.
    fn body<'a>(
        &mut self,
        b: &Builder,
        g: usize,
        i: usize,
        sh: &'a Shared<'a, R>,
        frame: &'a SharedFrame<'a>,
        trace: Option<usize>,
    ) -> UnitFuture<'a, Finished> {
        match b.units[g].kind {
            UnitKind::Rop => Box::pin(units::rop::run(
                b.ctx(
                    g,
                    take(&mut self.rop_in, i),
                    take(&mut self.rop_out, i),
                    trace,
                ),
                sh,
                i,
                frame,
            )),
            _ => Box::pin(units::framebuffer::run(
                b.ctx(g, take(&mut self.port_in, i), Vec::new(), trace),
                &sh.arch.framebuffer,
            )),
        }
    }
}

/// The ends of position `i` of a crossbar side, taken once.
fn take<T>(v: &mut [Vec<T>], i: usize) -> Vec<T> {
    std::mem::take(&mut v[i])
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

fn run_in<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    arch: &ArchConfig,
    source: Source,
    discoid: Option<DiscoidPass<R>>,
    options: &SimOptions,
) -> Result<TimedFrame> {
    let vp = view.viewport;
    let background = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let n_lembos = scene.lembo_count();
    let mut fb = FrameBuffer::new(vp.width, vp.height, background, false);
    // Model only what the scene requires: no primitives, no units.
    let path = match source {
        Source::Triangles(t) if t.chunks() == 0 => None,
        Source::Lembos if n_lembos == 0 => None,
        Source::Lembos => Some(Path::Lembo),
        Source::Triangles(_) => Some(Path::Triangle),
    };
    let Some(path) = path else {
        return Ok(TimedFrame {
            framebuffer: fb,
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
            recoveries: Recoveries::default(),
        });
    };
    let planned = graph::units(path, arch);
    let units: Vec<UnitInstance> = planned.iter().map(|u| u.0.clone()).collect();
    let threads = options.host_threads.clamp(1, units.len());
    let thread = runtime::partition(units.len(), threads, options.partition_seed);
    let shared = Shared {
        scene,
        view,
        arch,
        k: R::of(tol.k),
        perspective_tol: tol.perspective,
        background,
        lembos: match path {
            Path::Lembo => (0..n_lembos).map(|_| OnceLock::new()).collect(),
            Path::Triangle => Vec::new(),
        },
        source,
        tiles: RopTiles::new(vp.width, vp.height, arch.rop.tile_px, arch.rop.count),
        discoid,
    };
    let trace_cap = options.trace_event_cap / units.len();
    let trace = options.trace.then_some(trace_cap);
    let bars = Bars::<R>::new(path, arch, &units, &thread);

    let results: Outcome = {
        let frame = SharedFrame::new(&mut fb);
        if threads == 1 {
            let mut b = Builder::new(&planned, &units, &thread, 0, options.perturb, &[]);
            let futures = build(&mut b, &bars, &shared, &frame, trace);
            HostThread {
                core: b.core.clone(),
                futures,
                global: (0..units.len()).collect(),
                remotes: b.remotes,
            }
            .run(None)
        } else {
            run_threads(
                &planned, &units, &thread, options, &bars, &shared, &frame, trace, threads,
            )?
        }
    };
    let (mut results, recoveries) = match results {
        Ok(r) => r,
        Err(Stop::Deadlock(waiting)) => {
            return Err(Error::Deadlock {
                waiting: waiting.into_iter().map(|(_, w)| w).collect(),
            })
        }
        Err(Stop::Aborted) => return Err(Error::Internal("the timed run was aborted".into())),
    };
    results.sort_by_key(|(u, _)| *u);
    let mut frame = finish(arch, fb, units, results, options, trace_cap)?;
    frame.recoveries = recoveries;
    Ok(frame)
}

/// How the executor left a run: every unit's result (by global index) with the recoveries
/// it needed, or why it stopped.
type Outcome = std::result::Result<(Vec<(usize, Finished)>, Recoveries), Stop>;

/// The units' results of a run over several host threads, one scoped OS thread each; a
/// panic or a failure on one aborts the others.
#[allow(clippy::too_many_arguments)]
fn run_threads<'a, R: Real>(
    planned: &[(UnitInstance, u64)],
    units: &[UnitInstance],
    thread: &[usize],
    options: &SimOptions,
    bars: &Bars<R>,
    shared: &'a Shared<'a, R>,
    frame: &'a SharedFrame<'a>,
    trace: Option<usize>,
    threads: usize,
) -> Result<Outcome> {
    let board = Board::new(threads, thread.to_vec());
    let outcome = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|me| {
                let (planned, units, thread, board) = (&planned, &units, &thread, &board);
                let (bars, shared, frame) = (&bars, &shared, &frame);
                std::thread::Builder::new()
                    .name(format!("lembo-sim host {me}"))
                    .spawn_scoped(s, move || {
                        let _guard = AbortOnPanic(board);
                        let mut b = Builder::new(
                            planned,
                            units,
                            thread,
                            me,
                            options.perturb,
                            &board.signals,
                        );
                        let futures = build(&mut b, bars, shared, frame, trace);
                        let global = (0..units.len()).filter(|&g| thread[g] == me).collect();
                        let r = HostThread {
                            core: b.core.clone(),
                            futures,
                            global,
                            remotes: b.remotes,
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
                Ok(Err(Stop::Deadlock(w))) => waiting.extend(w),
                Ok(Err(Stop::Aborted)) => {}
            }
        }
        if let Some(e) = failure {
            return Err(e);
        }
        if board.deadlocked() {
            waiting.sort();
            return Ok(Err(Stop::Deadlock(waiting)));
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
    // A recorded functional error: the first in scene order.
    let mut first_error: Option<Error> = None;
    for (_, f) in &mut results {
        if let Some(e) = f.error.take() {
            let key = |e: &Error| match e {
                Error::SegmentCap {
                    lembo, scanline, ..
                } => (*lembo, *scanline),
                _ => (usize::MAX, u32::MAX),
            };
            if first_error.as_ref().is_none_or(|f| key(&e) < key(f)) {
                first_error = Some(e);
            }
        }
    }
    if let Some(e) = first_error {
        return Err(e);
    }

    let total = results
        .iter()
        .map(|(_, f)| f.stats.end)
        .max()
        .unwrap_or(Cycle::ZERO);
    let mut counts = Counts::default();
    let mut unit_cycles = Vec::with_capacity(units.len());
    for (u, f) in &results {
        counts += f.counts;
        let st = &f.stats;
        unit_cycles.push(UnitCycles {
            name: units[*u].name.clone(),
            kind: units[*u].kind,
            busy: Cycle(st.busy),
            starved: Cycle(st.starved + (total - st.end)),
            blocked: Cycle(st.blocked),
            items_in: st.items_in,
            items_out: st.items_out,
            max_fifo_occupancy: st.max_fifo_occupancy,
        });
    }
    counts.pixels_covered = fb.covered() as u64;
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
    let bottleneck = unit_cycles
        .iter()
        .fold(None::<&UnitCycles>, |best, u| match best {
            Some(b) if b.busy >= u.busy => Some(b),
            _ => Some(u),
        })
        .map(|u| u.name.clone());
    let cycles = CycleReport {
        total,
        clock_mhz: arch.clock_mhz,
        fps: (total > Cycle::ZERO).then(|| arch.clock_mhz * 1e6 / total.as_f64()),
        bottleneck,
        units: unit_cycles,
    };
    let mut discoid: Option<(Vec<KeptFragment>, BlendReport)> = None;
    for (_, f) in &mut results {
        if let Some((pending, report)) = f.discoid.take() {
            let (all, sum) = discoid.get_or_insert_with(Default::default);
            all.extend(pending);
            sum.culled_backface += report.culled_backface;
            sum.discarded_beta_zero += report.discarded_beta_zero;
            sum.discarded_threshold += report.discarded_threshold;
        }
    }
    Ok(TimedFrame {
        framebuffer: fb,
        counts,
        units,
        cycles,
        trace,
        discoid,
        recoveries: Recoveries::default(),
    })
}
