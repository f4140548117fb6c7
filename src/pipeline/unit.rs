//! What a unit of the timed pipeline is to the builder (after DAM's contexts): a [`Unit`]
//! declares its kind, the item it reads and the item it writes, the size of its output
//! items in a FIFO, and how to start its body from a [`RunInputs`]. The body itself sees only its
//! own context: its links ([`Ctx`]), its configuration section, and what else it needs (its
//! tolerance, the scene source), never the whole architecture.
//!
//! [`Elaborate`] is the same declaration with the types erased, so that the builder can
//! take the units of a path from a list, make each boundary's links from its producer's
//! output type, and refuse a graph whose consumer reads another type before anything runs.

use super::items::Item;
use super::runtime::executor::UnitFuture;
use super::runtime::trace::Recorder;
use super::runtime::{Ctx, Dispatcher, LinkSpec, UnitStats};
use super::tiles::{RopTiles, SharedFrame};
use super::wiring::{Crossbar, HostWiring, Wired};
use crate::camera::View;
use crate::config::{ArchConfig, FrameBufferConfig};
use crate::datapath::Real;
use crate::discoid::blend::BlendMode;
use crate::discoid::report::BlendReport;
use crate::error::Error;
use crate::frame::discoid::{DiscoidTable, KeptFragment, Pass};
use crate::graph::{Dispatch, TessSource, UnitInstance, UnitKind};
use crate::raster::triangle::TriangleSource;
use crate::raster::Counts;
use crate::scene::Scene;
use std::any::{type_name, Any, TypeId};
use std::marker::PhantomData;

/// What a unit hands back when it ends: what every unit reports, and its own figures.
pub struct Finished {
    /// Its busy, starved and blocked cycles and item counts.
    pub stats: UnitStats,
    /// Its timeline events, when traced.
    pub trace: Option<Recorder>,
    /// The unit's share of the functional counts.
    pub counts: Counts,
    /// A functional error the unit recorded (the run still ends normally).
    pub error: Option<Error>,
    /// The figures only this unit keeps, if it has any.
    pub own: Option<UnitReport>,
}

/// A unit's own figures, each kind's its own record, read by the run's report.
pub enum UnitReport {
    /// The geometry fetch's account of what it read.
    Fetch(FetchReport),
    /// A ROP's accumulation-pass output in a discoid pass: the fragments it kept and its
    /// counters.
    Kept(Vec<KeptFragment>, BlendReport),
    /// A ROP's caches and tile tables, with the DRAM memory model.
    RopMemory(crate::pipeline::rop_memory::RopMemoryStats),
    /// The memory controller's DRAM, with the DRAM memory model, and its requests when
    /// they were asked for.
    Dram(
        crate::memory::dram::DramStats,
        crate::pipeline::rop_memory::ClientStats,
        Option<Vec<crate::memory::trace::Request>>,
    ),
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
            own: None,
        }
    }

    /// The same, with the unit's own figures `own`.
    pub fn with(mut self, own: UnitReport) -> Self {
        self.own = Some(own);
        self
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

/// The triangle source of a run on the lembo path: no triangles.
pub struct NoTriangles;

impl TriangleSource for NoTriangles {
    fn chunks(&self) -> usize {
        0
    }

    fn per_chunk(&self) -> u64 {
        0
    }

    fn chunk(&self, _: usize, out: &mut Vec<crate::lembo::tessellate::Triangle>) {
        out.clear();
    }

    fn bytes(&self, _: &crate::config::FetchConfig) -> u64 {
        0
    }
}

/// What the geometry fetch reads: `primitives` in submission order, `bytes` in all (in
/// batches of its consumers' `batch`, which its boundary hands it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FetchPlan {
    /// What it reads, as report.json `fetch.source` names it.
    pub source: &'static str,
    /// Primitives \[lembos or triangles\].
    pub primitives: u64,
    /// Their bytes in memory \[bytes\]; with a vertex cache, the whole indexed mesh (what
    /// a perfect cache would read).
    pub bytes: u64,
    /// Entries of each setup engine's post-transform vertex cache, when the primitives are
    /// the triangles of an indexed mesh: the fetch then reads a triangle's indices and the
    /// vertices its engine's cache misses, instead of a share of `bytes`.
    pub vertex_cache: Option<u32>,
}

/// What the geometry fetch read (report.json `fetch`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FetchReport {
    /// What it read: `lembos` (the lembo path, or lembos for on-chip tessellation:
    /// `onchip`), `memory` (a tessellated mesh) or `discoids`.
    pub source: &'static str,
    /// Primitives read \[lembos or triangles\].
    pub primitives: u64,
    /// Bytes read from memory \[bytes\].
    pub bytes: u64,
    /// The setup engines' post-transform vertex caches, over all engines; None when the
    /// primitives are not an indexed mesh's triangles.
    pub vertex_cache: Option<VertexCacheCounts>,
}

/// The post-transform vertex caches' lookups, summed over the setup engines.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VertexCacheCounts {
    /// Entries of each engine's cache \[vertices\].
    pub entries: u32,
    /// Vertex references found in the cache.
    pub hits: u64,
    /// Vertex references not found: each a vertex read (and transformed).
    pub misses: u64,
}

impl FetchPlan {
    /// What the geometry fetch reads of `source`, its primitives `tess` (a mesh in memory,
    /// or the lembos themselves for on-chip tessellation) or the scene's `lembos` (curved
    /// discoids when `discoids`), its bytes `arch.fetch`'s.
    pub fn new(
        arch: &ArchConfig,
        source: Source,
        tess: TessSource,
        lembos: usize,
        discoids: bool,
    ) -> Self {
        match (source, tess) {
            (Source::Triangles(t), TessSource::Memory) => FetchPlan {
                source: TessSource::Memory.name(),
                primitives: t.chunks() as u64 * t.per_chunk(),
                bytes: t.bytes(&arch.fetch),
                // A vertex cache for a source that is an indexed mesh.
                vertex_cache: t
                    .indexed()
                    .then_some(arch.tessellation.vertex_cache_entries),
            },
            // The lembos themselves, read for the on-chip tessellators.
            (Source::Triangles(t), TessSource::OnChip) => FetchPlan {
                source: TessSource::OnChip.name(),
                primitives: t.chunks() as u64,
                bytes: t.chunks() as u64 * arch.fetch.bytes_per_lembo,
                vertex_cache: None,
            },
            (Source::Lembos, _) => FetchPlan {
                source: "lembos",
                primitives: lembos as u64,
                bytes: lembos as u64
                    * match discoids {
                        true => crate::discoid::CURVED_DISCOID_BYTES,
                        false => arch.fetch.bytes_per_lembo,
                    },
                vertex_cache: None,
            },
        }
    }

    /// The bytes of primitives `first..end`: their share of the whole, so that batches add
    /// up to the bytes stored (an indexed mesh's shared vertices are read once).
    pub fn bytes_of(&self, first: u64, end: u64) -> u64 {
        let at = |p: u64| (self.bytes as u128 * p as u128 / self.primitives.max(1) as u128) as u64;
        at(end) - at(first)
    }
}

/// What the ROPs need for a discoid pass.
pub struct DiscoidPass<'a, R> {
    /// Which of the passes this run is.
    pub pass: Pass,
    /// The discoids' texture coordinates and shading inputs by primitive id.
    pub table: &'a DiscoidTable<R>,
    /// Precision of the blend units.
    pub mode: BlendMode,
    /// The ROP's blend unit's cycles per kept fragment in `mode` (the blend section's).
    pub blend_cycles: u64,
    /// The accumulation threshold t \[world units\].
    pub threshold: f64,
    /// The depth pass's result, whole frame: depth and winner per pixel (accumulation pass).
    pub depth: &'a [f32],
    /// The depth pass's winning primitive id per pixel.
    pub winner: &'a [u32],
}

/// What one run offers its units: each unit's [`Unit::spawn`] takes out its own context and
/// hands its body only that.
pub struct RunInputs<'a, R> {
    /// The scene being drawn.
    pub scene: &'a Scene,
    /// Its camera and viewport.
    pub view: &'a View,
    /// The architecture: each unit takes its own section.
    pub arch: &'a ArchConfig,
    /// The shared memory port's section ([`crate::graph::SHARED`]): its clients, the ROPs
    /// by their link and the geometry fetch directly, move their bytes on its terms.
    pub port: &'a FrameBufferConfig,
    /// Tolerance k in the datapath's precision \[pixels\].
    pub k: R,
    /// Setup's perspective tolerance \[pixels\]; None: the paper's Setup.
    pub perspective_tol: Option<f64>,
    /// What the geometry fetch reads.
    pub fetch: FetchPlan,
    /// The triangles this run draws (none on the lembo path).
    pub triangles: &'a dyn TriangleSource,
    /// Which ROP owns each screen tile.
    pub tiles: RopTiles,
    /// The discoid pass the ROPs run; None for ordinary rendering.
    pub discoid: Option<DiscoidPass<'a, R>>,
    /// The frame buffer the ROPs write in place.
    pub frame: SharedFrame<'a>,
    /// The DRAM controller keeps its requests ([`crate::pipeline::SimOptions::dram_requests`]).
    pub dram_requests: bool,
}

/// A box of Figure 5 as the builder sees it: one file of [`super::units`] each.
pub trait Unit<R: Real>: 'static {
    /// Its kind in the graph ([`crate::graph`]).
    const KIND: UnitKind;
    /// The item it reads from its input links; `()` for a unit without inputs (a source).
    type In: Send + 'static;
    /// The item it writes to its output links; `()` for a unit without outputs (a sink).
    type Out: Item;
    /// Datapath words one of its output items takes in a FIFO (32 bits each in f32, 64 in
    /// f64), counted from what the hardware would send, for the FIFOs' area and energy
    /// (DESIGN.md §12); 0 for a sink.
    const OUT_WORDS: u32;
    /// The primitives per batch it takes from a boundary dealt in batches (its own
    /// section's `batch`), which the runtime hands the producer of that boundary; None for
    /// a unit fed otherwise.
    fn batch(_arch: &ArchConfig) -> Option<u32> {
        None
    }
    /// The body of instance `index` of this kind, on its links `ctx`, with its context
    /// taken from `run`.
    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        index: usize,
    ) -> UnitFuture<'a, Finished>;
}

/// A [`Unit`] with its types erased, as the builder's list holds it.
pub trait Elaborate<R: Real> {
    /// Its kind.
    fn kind(&self) -> UnitKind;
    /// The type it reads, or None for a source.
    fn input(&self) -> Option<(TypeId, &'static str)>;
    /// The type it writes, or None for a sink.
    fn output(&self) -> Option<(TypeId, &'static str)>;
    /// [`Unit::OUT_WORDS`].
    fn out_words(&self) -> u32;
    /// Whether its output items say where on screen they lie ([`Item::ON_SCREEN`]).
    fn on_screen(&self) -> bool;
    /// [`Unit::batch`].
    fn batch(&self, arch: &ArchConfig) -> Option<u32>;
    /// The crossbar of its output links to every instance of `to` (a `Crossbar<Out>`),
    /// its links each producer's output ports from `port_base` on.
    fn crossbar(
        &self,
        units: &[UnitInstance],
        to: UnitKind,
        thread: &[usize],
        spec: LinkSpec,
        port_base: usize,
    ) -> Box<dyn Any + Send + Sync>;
    /// One host thread's ends of `xb`, one of this unit's crossbars (a `Wired<Out>`).
    fn wire(&self, host: &mut HostWiring, xb: &(dyn Any + Send + Sync)) -> Box<dyn Any>;
    /// The body of unit `g`, instance `index` of its kind, with its inputs taken from
    /// `inputs` (a `Wired<In>` per feeding boundary, in the graph's order: its ports, one
    /// boundary's after another's) and its outputs from `outputs` (per boundary it feeds,
    /// likewise), its items dispatched by the rule of the one its path takes.
    #[allow(clippy::too_many_arguments)]
    fn spawn<'a>(
        &self,
        host: &HostWiring,
        g: usize,
        index: usize,
        inputs: Vec<&mut dyn Any>,
        outputs: Vec<OutputBoundary<'_>>,
        run: &'a RunInputs<'a, R>,
        trace: Option<usize>,
    ) -> UnitFuture<'a, Finished>;
}

/// One boundary a unit feeds, as its body is spawned.
pub struct OutputBoundary<'w> {
    /// Its links (a `Wired<Out>`).
    pub wired: &'w mut dyn Any,
    /// Its dispatch rule.
    pub dispatch: Dispatch,
    /// Whether the run's path takes it: a unit sends along the first boundary it feeds
    /// that the path takes; the others carry nothing (a graph wiring both paths' engines).
    pub taken: bool,
    /// Its consumers' batch, under a rule of batches ([`Unit::batch`]).
    pub batch: Option<u32>,
    /// It leads to a shared unit the producer is a direct client of
    /// ([`crate::graph::Boundary::to_shared`]): sent on by [`Ctx::emit_shared`], beside the
    /// boundary the path takes.
    pub shared: bool,
}

/// The runtime's dispatcher of `out`'s rule over the output ports `ports` (a ROP per port
/// for a rule by screen tile, the tile interleave `tiles`; the consumers' batch for a rule
/// of batches).
fn dispatcher<O: Item>(
    out: &OutputBoundary,
    ports: std::ops::Range<usize>,
    tiles: &RopTiles,
) -> Dispatcher<O> {
    match out.dispatch {
        Dispatch::RoundRobin => Dispatcher::round_robin(ports),
        Dispatch::Batches => Dispatcher::round_robin(ports).with_batch(out.batch),
        Dispatch::ScreenTile => {
            let tiles = tiles.clone();
            Dispatcher::keyed(ports, move |item: &O| {
                let (i, j) = item
                    .pixel()
                    .expect("the graph check found the items on screen");
                tiles.owner(i, j).0
            })
        }
    }
}

/// The erased form of unit `U`.
pub struct ErasedUnit<U>(PhantomData<U>);

impl<U> ErasedUnit<U> {
    /// Unit `U`'s entry in the builder's list.
    pub const fn new() -> Self {
        ErasedUnit(PhantomData)
    }
}

impl<U> Default for ErasedUnit<U> {
    fn default() -> Self {
        ErasedUnit::new()
    }
}

/// `T`'s identity, or None for `()` (no link on that side).
fn link_type<T: 'static>() -> Option<(TypeId, &'static str)> {
    (TypeId::of::<T>() != TypeId::of::<()>()).then(|| (TypeId::of::<T>(), type_name::<T>()))
}

impl<R: Real, U: Unit<R>> Elaborate<R> for ErasedUnit<U> {
    fn kind(&self) -> UnitKind {
        U::KIND
    }

    fn input(&self) -> Option<(TypeId, &'static str)> {
        link_type::<U::In>()
    }

    fn output(&self) -> Option<(TypeId, &'static str)> {
        link_type::<U::Out>()
    }

    fn out_words(&self) -> u32 {
        U::OUT_WORDS
    }

    fn on_screen(&self) -> bool {
        <U::Out as Item>::ON_SCREEN
    }

    fn batch(&self, arch: &ArchConfig) -> Option<u32> {
        U::batch(arch)
    }

    fn crossbar(
        &self,
        units: &[UnitInstance],
        to: UnitKind,
        thread: &[usize],
        spec: LinkSpec,
        port_base: usize,
    ) -> Box<dyn Any + Send + Sync> {
        Box::new(Crossbar::<U::Out>::new(
            units,
            U::KIND,
            to,
            thread,
            spec,
            port_base,
        ))
    }

    fn wire(&self, host: &mut HostWiring, xb: &(dyn Any + Send + Sync)) -> Box<dyn Any> {
        let xb = xb
            .downcast_ref::<Crossbar<U::Out>>()
            .expect("a unit wires only the crossbars it made");
        Box::new(host.wire(xb))
    }

    fn spawn<'a>(
        &self,
        host: &HostWiring,
        g: usize,
        index: usize,
        inputs: Vec<&mut dyn Any>,
        outputs: Vec<OutputBoundary<'_>>,
        run: &'a RunInputs<'a, R>,
        trace: Option<usize>,
    ) -> UnitFuture<'a, Finished> {
        // The builder checked before elaboration that every consumer reads its producers'
        // type, so these casts only fail on a builder defect.
        let rx = inputs
            .into_iter()
            .flat_map(|w| {
                w.downcast_mut::<Wired<U::In>>()
                    .expect("the graph check matched the input type")
                    .take_rx(index)
            })
            .collect();
        let mut tx = Vec::new();
        let mut dispatch = None;
        let mut shared = None;
        for out in outputs {
            let links = out
                .wired
                .downcast_mut::<Wired<U::Out>>()
                .expect("the graph check matched the output type")
                .take_tx(index);
            let ports = tx.len()..tx.len() + links.len();
            tx.extend(links);
            if out.shared {
                shared = Some(ports.start);
            } else if out.taken && dispatch.is_none() {
                dispatch = Some(dispatcher(&out, ports, &run.tiles));
            }
        }
        // A unit its path takes no boundary out of is fed nothing, and sends nothing.
        let mut dispatch = dispatch.unwrap_or_else(|| Dispatcher::round_robin(0..0));
        // The source's items are the primitives fetched: the run's progress.
        if link_type::<U::In>().is_none() {
            dispatch = dispatch.with_progress(<U::Out as Item>::primitives);
        }
        U::spawn(
            host.ctx(g, rx, tx, dispatch, trace).with_shared(shared),
            run,
            index,
        )
    }
}
