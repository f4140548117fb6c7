//! The timed pipeline: Figure 5 of paper 001 as actors on bounded crossbeam channels
//! (DESIGN §3). Each unit instance is a host thread that calls the functional code of
//! [`crate::raster`] and adds only time; the image is bit-identical to the functional
//! model's for every architecture configuration.
//!
//! ```text
//!  Setup ─► MinMax ─► IntervalManager ─┬► Segmenter[0..Ns] ─┬► Subsegmenter[0..Nb] ─┬► FragmentRasterizer[0..Nr] ─┬► Rop[0..Np] ─► FrameBuffer
//!                                      round-robin          round-robin             round-robin                   by screen tile   (memory port)
//! ```
//!
//! The triangle path (`run_timed` with a triangle source) instantiates instead
//! `TriangleSetup ─► TriangleRasterizer[0..Nt] ─► Rop[0..Np] ─► FrameBuffer`, the same ROPs
//! and port ([`triangle_setup`], [`triangle_rasterizer`]).
//!
//! Every arrow of a crossbar is its own link (FIFO depth and latency from the
//! architecture's `links`); a unit with several inputs merges them by (arrival, port).
//!
//! - [`link`]: `Timed` items, credits, watermarks: the timing semantics of a FIFO.
//! - [`actor`]: the per-unit clock ([`actor::Ctx`]), host protocol and deadlock watchdog.
//! - one file per unit, in dataflow order: [`setup`], [`minmax`], [`interval_manager`],
//!   [`segmenter`], [`subsegmenter`], [`rasterizer`], [`rop`], [`framebuffer`].
//! - [`trace`]: the Chrome trace-event timeline.
//!
//! Model only what a scene requires: a scene without lembos instantiates no units, and each
//! path only its own.

pub mod actor;
pub mod discoid;
pub mod framebuffer;
pub mod interval_manager;
pub mod link;
pub mod minmax;
pub mod rasterizer;
pub mod rop;
pub mod segmenter;
pub mod setup;
pub mod subsegmenter;
pub mod trace;
pub mod triangle_rasterizer;
pub mod triangle_setup;

use crate::camera::View;
use crate::config::{ArchConfig, LinkConfig};
use crate::datapath::{Datapath, Real};
use crate::discoid::blend::BlendMode;
use crate::discoid::render::{BlendReport, DiscoidTable, Pass, Pending};
use crate::error::{Error, Result};
use crate::raster::setup::ScreenLembo;
use crate::raster::triangle::TriangleSource;
use crate::raster::{Counts, Tolerance};
use crate::rop::FrameBuffer;
use crate::scene::Scene;
pub use actor::SimOptions;
use actor::{ActorError, Ctx, Monitor, UnitStats};
use link::{link, Cycle, LinkName, LinkSpec, Rx, Tx};
use rop::{RopTiles, TileStore};
use serde::Serialize;
use std::sync::OnceLock;
use std::thread::{Scope, ScopedJoinHandle};
use trace::Recorder;

/// The kinds of unit, in dataflow order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum UnitKind {
    Setup,
    MinMax,
    IntervalManager,
    Segmenter,
    Subsegmenter,
    FragmentRasterizer,
    TriangleSetup,
    TriangleRasterizer,
    Rop,
    /// A ROP's discoid blend unit (listed for scenes with discoids; its cycles are its
    /// ROP's).
    BlendUnit,
    FrameBuffer,
}

impl UnitKind {
    pub fn name(self) -> &'static str {
        match self {
            UnitKind::Setup => "Setup",
            UnitKind::MinMax => "MinMax",
            UnitKind::IntervalManager => "IntervalManager",
            UnitKind::Segmenter => "Segmenter",
            UnitKind::Subsegmenter => "Subsegmenter",
            UnitKind::FragmentRasterizer => "FragmentRasterizer",
            UnitKind::TriangleSetup => "TriangleSetup",
            UnitKind::TriangleRasterizer => "TriangleRasterizer",
            UnitKind::Rop => "Rop",
            UnitKind::BlendUnit => "BlendUnit",
            UnitKind::FrameBuffer => "FrameBuffer",
        }
    }
}

/// One instantiated unit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitInstance {
    /// `Segmenter[2]`, or the kind's name for a single unit.
    pub name: String,
    pub kind: UnitKind,
}

/// The cycle accounting of one unit over the frame [cycles].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitCycles {
    pub name: String,
    pub kind: UnitKind,
    /// Cycles issuing ops.
    pub busy: u64,
    /// Cycles waiting for an input to arrive (including after its last op).
    pub starved: u64,
    /// Cycles frozen because a FIFO downstream was full.
    pub blocked: u64,
    /// Items popped from its input FIFOs [items].
    pub items_in: u64,
    /// Items pushed to its output FIFOs [items].
    pub items_out: u64,
    /// Most items in any one of its input FIFOs at once [items].
    pub max_fifo_occupancy: u64,
}

/// `cycles` in report.json.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CycleReport {
    /// Cycle at which the last unit finished: the last write through the frame-buffer
    /// port, or a later unit that produced nothing [cycles].
    pub total: u64,
    pub clock_mhz: f64,
    /// Frames per second at the clock; null for an empty frame.
    pub fps: Option<f64>,
    /// The unit with the most busy cycles (ties: the first in dataflow order); null when
    /// nothing was instantiated.
    pub bottleneck: Option<String>,
    pub units: Vec<UnitCycles>,
}

/// What a timed run produced.
pub struct TimedFrame {
    pub framebuffer: FrameBuffer,
    pub counts: Counts,
    pub units: Vec<UnitInstance>,
    pub cycles: CycleReport,
    /// Chrome trace-event JSON, when requested.
    pub trace: Option<String>,
    /// An accumulation pass's kept fragments and counters, over all ROPs.
    pub discoid: Option<(Vec<Pending>, BlendReport)>,
}

/// Read-only state the units share: the scene, the configuration and the lembo table.
pub struct Shared<'a, R> {
    pub scene: &'a Scene,
    pub view: &'a View,
    pub arch: &'a ArchConfig,
    pub k: R,
    /// Setup's perspective tolerance [pixels]; None: the paper's Setup.
    pub perspective_tol: Option<f64>,
    pub background: [u8; 3],
    /// Screen-space lembos by id, each whole or as the pieces Setup split it into, filled by
    /// Setup before it sends their ids downstream (empty in the triangle path).
    pub lembos: Vec<OnceLock<Vec<ScreenLembo<R>>>>,
    /// The triangles of the triangle path; None in the lembo path.
    pub triangles: Option<&'a dyn TriangleSource>,
    pub tiles: RopTiles,
    /// The discoid pass the ROPs run; None for ordinary rendering.
    pub discoid: Option<DiscoidPass<'a, R>>,
}

/// What the ROPs need for a discoid pass.
pub struct DiscoidPass<'a, R> {
    pub pass: Pass,
    pub table: &'a DiscoidTable<R>,
    pub mode: BlendMode,
    /// [world units]
    pub threshold: f64,
    /// The depth pass's result, whole frame: depth and winner per pixel (accumulation pass).
    pub depth: &'a [f32],
    pub winner: &'a [u32],
}

impl<R> Shared<'_, R> {
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
    pub lembo: u32,
    pub piece: u32,
}

/// What a unit hands back when it ends.
pub struct Finished {
    pub stats: UnitStats,
    pub trace: Option<Recorder>,
    /// The unit's share of the functional counts.
    pub counts: Counts,
    /// A functional error the unit recorded (the run still ends normally).
    pub error: Option<Error>,
    /// A ROP's accumulation-pass output in a discoid pass: the fragments it kept and its
    /// counters.
    pub discoid: Option<(Vec<Pending>, BlendReport)>,
}

impl Finished {
    pub fn new<I: Send + 'static, O: Send + 'static>(
        ctx: Ctx<I, O>,
        counts: Counts,
    ) -> std::result::Result<Self, ActorError> {
        let (stats, trace) = ctx.finish()?;
        Ok(Finished {
            stats,
            trace,
            counts,
            error: None,
            discoid: None,
        })
    }
}

/// Renders `scene` on the timed pipeline of `arch`: the lembo path, or with a
/// triangle source (a tessellation) the triangle path.
pub fn run_timed(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    arch: &ArchConfig,
    triangles: Option<&dyn TriangleSource>,
    options: &SimOptions,
) -> Result<TimedFrame> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => run_in::<f32>(scene, view, tol, arch, triangles, None, options),
        Datapath::F64 => run_in::<f64>(scene, view, tol, arch, triangles, None, options),
    }
}

/// Appends `n` units of `kind`, named `Kind[i]` when `indexed`.
fn add_units(units: &mut Vec<UnitInstance>, kind: UnitKind, n: u32, indexed: bool) {
    for i in 0..n {
        let name = if indexed {
            format!("{}[{i}]", kind.name())
        } else {
            kind.name().to_string()
        };
        units.push(UnitInstance { name, kind });
    }
}

/// The units a lembo scene instantiates, in dataflow order.
pub fn lembo_units(arch: &ArchConfig) -> Vec<UnitInstance> {
    let mut units = Vec::new();
    add_units(&mut units, UnitKind::Setup, 1, false);
    add_units(&mut units, UnitKind::MinMax, 1, false);
    add_units(&mut units, UnitKind::IntervalManager, 1, false);
    add_units(&mut units, UnitKind::Segmenter, arch.segmenter.count, true);
    add_units(
        &mut units,
        UnitKind::Subsegmenter,
        arch.subsegmenter.count,
        true,
    );
    add_units(
        &mut units,
        UnitKind::FragmentRasterizer,
        arch.rasterizer.count,
        true,
    );
    add_units(&mut units, UnitKind::Rop, arch.rop.count, true);
    add_units(&mut units, UnitKind::FrameBuffer, 1, false);
    units
}

/// The units the triangle path instantiates, in dataflow order.
pub fn triangle_units(arch: &ArchConfig) -> Vec<UnitInstance> {
    let mut units = Vec::new();
    add_units(&mut units, UnitKind::TriangleSetup, 1, false);
    let n = arch.triangle_rasterizer.count;
    add_units(&mut units, UnitKind::TriangleRasterizer, n, true);
    add_units(&mut units, UnitKind::Rop, arch.rop.count, true);
    add_units(&mut units, UnitKind::FrameBuffer, 1, false);
    units
}

/// The FIFO entries of every link `units` instantiate: each boundary's crossbar has one
/// link per (producer, consumer) pair, each `fifo_depth` entries deep; a boundary between
/// kinds absent from `units` has no links. Item sizes are not modelled, so this counts
/// entries, not bytes [entries].
pub fn fifo_entries(arch: &ArchConfig, units: &[UnitInstance]) -> u64 {
    use UnitKind::*;
    let l = &arch.links;
    let boundaries = [
        (&l.setup_to_minmax, Setup, MinMax),
        (&l.minmax_to_interval_manager, MinMax, IntervalManager),
        (&l.interval_manager_to_segmenter, IntervalManager, Segmenter),
        (&l.segmenter_to_subsegmenter, Segmenter, Subsegmenter),
        (
            &l.subsegmenter_to_rasterizer,
            Subsegmenter,
            FragmentRasterizer,
        ),
        (&l.rasterizer_to_rop, FragmentRasterizer, Rop),
        (&l.rop_to_framebuffer, Rop, FrameBuffer),
        (
            &l.triangle_setup_to_rasterizer,
            TriangleSetup,
            TriangleRasterizer,
        ),
        (&l.triangle_rasterizer_to_rop, TriangleRasterizer, Rop),
    ];
    let count = |kind: UnitKind| units.iter().filter(|u| u.kind == kind).count() as u64;
    boundaries
        .iter()
        .map(|(link, from, to)| count(*from) * count(*to) * link.fifo_depth as u64)
        .sum()
}

fn spec(c: &LinkConfig) -> LinkSpec {
    LinkSpec {
        fifo_depth: c.fifo_depth,
        latency_cycles: c.latency_cycles,
    }
}

/// Links from every producer to every consumer: `tx[p][c]`, `rx[c][p]`.
#[allow(clippy::type_complexity)]
fn crossbar<T>(
    c: &LinkConfig,
    producers: &[UnitInstance],
    consumers: &[UnitInstance],
) -> (Vec<Vec<Tx<T>>>, Vec<Vec<Rx<T>>>) {
    let mut tx: Vec<Vec<Tx<T>>> = producers.iter().map(|_| Vec::new()).collect();
    let mut rx: Vec<Vec<Rx<T>>> = consumers.iter().map(|_| Vec::new()).collect();
    for (p, producer) in producers.iter().enumerate() {
        for (q, consumer) in consumers.iter().enumerate() {
            let (t, r) = link(
                spec(c),
                LinkName {
                    producer: producer.name.clone(),
                    consumer: consumer.name.clone(),
                },
            );
            tx[p].push(t);
            rx[q].push(r);
        }
    }
    (tx, rx)
}

type Handle<'s, T> = ScopedJoinHandle<'s, std::result::Result<T, ActorError>>;
/// A unit's thread: its result and, for a ROP, its pixels.
type UnitHandle<'s> = Handle<'s, (Finished, Option<TileStore>)>;

/// Marks a unit done when its thread ends, also by panic (then the run is aborted).
struct DoneGuard<'m> {
    monitor: &'m Monitor,
    unit: usize,
}

impl Drop for DoneGuard<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.monitor.abort();
        }
        self.monitor.done(self.unit);
    }
}

/// Spawns one unit's thread.
fn spawn<'s, 'e: 's, T: Send + 's>(
    scope: &'s Scope<'s, 'e>,
    monitor: &'e Monitor,
    unit: usize,
    body: impl FnOnce() -> std::result::Result<T, ActorError> + Send + 's,
) -> Result<Handle<'s, T>> {
    std::thread::Builder::new()
        .name(monitor.name(unit).to_string())
        .spawn_scoped(scope, move || {
            let _guard = DoneGuard { monitor, unit };
            let result = body();
            if let Err(ActorError::Disconnected(_)) = result {
                monitor.abort();
            }
            result
        })
        .map_err(|e| Error::Internal(format!("cannot start a unit thread: {e}")))
}

/// Joins a unit's thread.
fn join<T>(h: Handle<'_, T>, name: &str) -> Result<std::result::Result<T, ActorError>> {
    h.join()
        .map_err(|_| Error::Internal(format!("unit {name} panicked")))
}

fn run_in<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    arch: &ArchConfig,
    triangles: Option<&dyn TriangleSource>,
    discoid: Option<DiscoidPass<R>>,
    options: &SimOptions,
) -> Result<TimedFrame> {
    let vp = view.viewport;
    let background = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let n_lembos = scene.lembo_count();
    // Model only what the scene requires: no primitives, no units.
    let units = match triangles {
        Some(t) if t.chunks() == 0 => Vec::new(),
        None if n_lembos == 0 => Vec::new(),
        None => lembo_units(arch),
        Some(_) => triangle_units(arch),
    };
    if units.is_empty() {
        let fb = FrameBuffer::new(vp.width, vp.height, background, false);
        return Ok(TimedFrame {
            framebuffer: fb,
            counts: Counts::default(),
            units,
            cycles: CycleReport {
                total: 0,
                clock_mhz: arch.clock_mhz,
                fps: None,
                bottleneck: None,
                units: Vec::new(),
            },
            trace: None,
            discoid: None,
        });
    }
    let shared = Shared {
        scene,
        view,
        arch,
        k: R::of(tol.k),
        perspective_tol: tol.perspective,
        background,
        lembos: match triangles {
            None => (0..n_lembos).map(|_| OnceLock::new()).collect(),
            Some(_) => Vec::new(),
        },
        triangles,
        tiles: RopTiles::new(vp.width, vp.height, arch.rop.tile_px, arch.rop.count),
        discoid,
    };
    let monitor = Monitor::new(units.iter().map(|u| u.name.clone()).collect());
    let trace_cap = options.trace_event_cap / units.len();

    // Unit indices by kind, in the order of `lembo_units` or `triangle_units`.
    let of = |kind: UnitKind| -> Vec<usize> {
        (0..units.len())
            .filter(|&u| units[u].kind == kind)
            .collect()
    };
    let rop_ids = of(UnitKind::Rop);
    let fb_id = units.len() - 1;
    let pick =
        |ids: &[usize]| -> Vec<UnitInstance> { ids.iter().map(|&u| units[u].clone()).collect() };
    let l = &arch.links;
    let (rop_tx, mut fb_rx) = crossbar(&l.rop_to_framebuffer, &pick(&rop_ids), &units[fb_id..]);

    let results: Result<Vec<(usize, Finished, Option<TileStore>)>> = std::thread::scope(|s| {
        let sh = &shared;
        let mon = &monitor;
        macro_rules! ctx {
            ($unit:expr, $latency:expr, $inputs:expr, $outputs:expr) => {
                Ctx::new($unit, $inputs, $outputs, $latency, mon, options, trace_cap)
            };
        }
        let mut handles: Vec<(usize, UnitHandle<'_>)> = Vec::new();
        let plain = |r: std::result::Result<Finished, ActorError>| r.map(|f| (f, None));

        // The front end, up to the links into the ROPs.
        let rop_rx = match triangles {
            None => {
                let (seg_ids, sub_ids, ras_ids) = (
                    of(UnitKind::Segmenter),
                    of(UnitKind::Subsegmenter),
                    of(UnitKind::FragmentRasterizer),
                );
                let (mut setup_tx, mut minmax_rx) =
                    crossbar(&l.setup_to_minmax, &units[0..1], &units[1..2]);
                let (mut minmax_tx, mut im_rx) =
                    crossbar(&l.minmax_to_interval_manager, &units[1..2], &units[2..3]);
                let (mut im_tx, seg_rx) = crossbar(
                    &l.interval_manager_to_segmenter,
                    &units[2..3],
                    &pick(&seg_ids),
                );
                let (seg_tx, sub_rx) = crossbar(
                    &l.segmenter_to_subsegmenter,
                    &pick(&seg_ids),
                    &pick(&sub_ids),
                );
                let (sub_tx, ras_rx) = crossbar(
                    &l.subsegmenter_to_rasterizer,
                    &pick(&sub_ids),
                    &pick(&ras_ids),
                );
                let (ras_tx, rop_rx) =
                    crossbar(&l.rasterizer_to_rop, &pick(&ras_ids), &pick(&rop_ids));

                let c = ctx!(0, arch.setup.latency_cycles, Vec::new(), setup_tx.remove(0));
                handles.push((0, spawn(s, mon, 0, move || plain(setup::run(c, sh)))?));
                let c = ctx!(
                    1,
                    arch.minmax.latency_cycles,
                    minmax_rx.remove(0),
                    minmax_tx.remove(0)
                );
                handles.push((1, spawn(s, mon, 1, move || plain(minmax::run(c, sh)))?));
                let c = ctx!(
                    2,
                    arch.interval_manager.latency_cycles,
                    im_rx.remove(0),
                    im_tx.remove(0)
                );
                handles.push((
                    2,
                    spawn(s, mon, 2, move || plain(interval_manager::run(c, sh)))?,
                ));
                for ((&u, rx), tx) in seg_ids.iter().zip(seg_rx).zip(seg_tx) {
                    let c = ctx!(u, arch.segmenter.latency_cycles, rx, tx);
                    handles.push((u, spawn(s, mon, u, move || plain(segmenter::run(c, sh)))?));
                }
                for ((&u, rx), tx) in sub_ids.iter().zip(sub_rx).zip(sub_tx) {
                    let c = ctx!(u, arch.subsegmenter.latency_cycles, rx, tx);
                    handles.push((
                        u,
                        spawn(s, mon, u, move || plain(subsegmenter::run(c, sh)))?,
                    ));
                }
                for ((&u, rx), tx) in ras_ids.iter().zip(ras_rx).zip(ras_tx) {
                    let c = ctx!(u, arch.rasterizer.latency_cycles, rx, tx);
                    handles.push((u, spawn(s, mon, u, move || plain(rasterizer::run(c, sh)))?));
                }
                rop_rx
            }
            Some(_) => {
                let tr_ids = of(UnitKind::TriangleRasterizer);
                let (mut setup_tx, tr_rx) = crossbar(
                    &l.triangle_setup_to_rasterizer,
                    &units[0..1],
                    &pick(&tr_ids),
                );
                let (tr_tx, rop_rx) = crossbar(
                    &l.triangle_rasterizer_to_rop,
                    &pick(&tr_ids),
                    &pick(&rop_ids),
                );
                let c = ctx!(
                    0,
                    arch.triangle_setup.latency_cycles,
                    Vec::new(),
                    setup_tx.remove(0)
                );
                handles.push((
                    0,
                    spawn(s, mon, 0, move || plain(triangle_setup::run(c, sh)))?,
                ));
                for ((&u, rx), tx) in tr_ids.iter().zip(tr_rx).zip(tr_tx) {
                    let c = ctx!(u, arch.triangle_rasterizer.latency_cycles, rx, tx);
                    handles.push((
                        u,
                        spawn(s, mon, u, move || plain(triangle_rasterizer::run(c, sh)))?,
                    ));
                }
                rop_rx
            }
        };
        for (r, ((&u, rx), tx)) in rop_ids.iter().zip(rop_rx).zip(rop_tx).enumerate() {
            let c = ctx!(u, arch.rop.latency_cycles, rx, tx);
            handles.push((
                u,
                spawn(s, mon, u, move || {
                    rop::run(c, sh, r).map(|(f, store)| (f, Some(store)))
                })?,
            ));
        }
        let c = ctx!(fb_id, 1, fb_rx.remove(0), Vec::new());
        let fbc = &arch.framebuffer;
        handles.push((
            fb_id,
            spawn(s, mon, fb_id, move || plain(framebuffer::run(c, fbc)))?,
        ));

        let mut done = Vec::new();
        let mut failure: Option<Error> = None;
        for (u, h) in handles {
            match join(h, &units[u].name)? {
                Ok((f, store)) => done.push((u, f, store)),
                Err(ActorError::Aborted) => {}
                Err(ActorError::Disconnected(link)) => {
                    failure.get_or_insert(Error::Internal(format!(
                        "link {link} disconnected before it ended"
                    )));
                }
            }
        }
        if let Some(waiting) = monitor.deadlock() {
            return Err(Error::Deadlock { waiting });
        }
        if let Some(e) = failure {
            return Err(e);
        }
        if done.len() != units.len() {
            return Err(Error::Internal("a unit stopped without a result".into()));
        }
        Ok(done)
    });
    let mut results = results?;
    results.sort_by_key(|(u, _, _)| *u);

    // A recorded functional error: the first in scene order.
    let mut first_error: Option<Error> = None;
    for (_, f, _) in &mut results {
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
        .map(|(_, f, _)| f.stats.end)
        .max()
        .unwrap_or(Cycle::ZERO);
    let mut counts = Counts::default();
    let mut fb = FrameBuffer::new(vp.width, vp.height, background, false);
    let mut unit_cycles = Vec::with_capacity(units.len());
    for (u, f, store) in &results {
        counts += f.counts;
        if let Some(store) = store {
            store.write_into(&shared.tiles, &mut fb);
        }
        let st = &f.stats;
        unit_cycles.push(UnitCycles {
            name: units[*u].name.clone(),
            kind: units[*u].kind,
            busy: st.busy,
            starved: st.starved + (total - st.end),
            blocked: st.blocked,
            items_in: st.items_in,
            items_out: st.items_out,
            max_fifo_occupancy: st.max_fifo_occupancy,
        });
    }
    counts.pixels_covered = fb.covered() as u64;
    let trace = options.trace.then(|| {
        let tracks: Vec<trace::Track> = results
            .iter()
            .filter_map(|(u, f, _)| {
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
        total: total.0,
        clock_mhz: arch.clock_mhz,
        fps: (total.0 > 0).then(|| arch.clock_mhz * 1e6 / total.0 as f64),
        bottleneck,
        units: unit_cycles,
    };
    let mut discoid: Option<(Vec<Pending>, BlendReport)> = None;
    for (_, f, _) in &mut results {
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
    })
}
