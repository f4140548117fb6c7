//! The unit graph, described once: the kinds of unit, which kinds each path instantiates,
//! and which boundaries between kinds carry links, with each link's defaults. Elaboration
//! (`pipeline`), the architecture file's `links` (`config`), the report's
//! unit list, the FIFO entry count, the counting runs' operation tables and the sweep's
//! column order all read it, so adding a unit means adding it here and writing its body in
//! `pipeline/units/`.
//!
//! A leaf of the crate: it imports nothing of it, so the functional model (which charges
//! operations to unit kinds), the configuration and the timed pipeline can all depend on it.
//!
//! Every boundary is a crossbar: one link (FIFO depth and latency from the architecture's
//! `links`) from every producer instance to every consumer instance; which link a producer
//! pushes an item on is the boundary's [`Dispatch`] rule, applied by the runtime, so no
//! unit body chooses a destination.

use serde::{Deserialize, Serialize};
use std::sync::LazyLock;

/// The kinds of unit, in dataflow order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum UnitKind {
    /// Reads the scene's primitives from memory through the memory port and deals them to
    /// the setup engines in batches.
    GeometryFetch,
    /// Projects lembos and sets up their screen quadratics (Martinelli 2006 section 4).
    Setup,
    /// Finds a lembo's y range (section 5).
    MinMax,
    /// Finds each scanline's intervals (section 5.1).
    IntervalManager,
    /// Walks intervals in segments of midpoint error k (section 5.2).
    Segmenter,
    /// Splits segments so x is linear (section 5.3).
    Subsegmenter,
    /// Generates fragments along subsegments (section 5.3).
    FragmentRasterizer,
    /// The triangle path's on-chip tessellator: a lembo's n² domain triangles and their
    /// domain points (the `onchip` triangle source).
    Tessellator,
    /// Evaluates each new domain point's position and normal from its lembo's quadratic
    /// functions (the `onchip` triangle source).
    DomainEval,
    /// The triangle path's setup.
    TriangleSetup,
    /// The triangle path's quad rasterizer.
    TriangleRasterizer,
    /// Depth test, shading and frame-buffer write, by screen tile.
    Rop,
    /// A ROP's discoid blend unit (listed for scenes with discoids; its cycles are its
    /// ROP's).
    BlendUnit,
    /// The frame-buffer memory port.
    FrameBuffer,
}

/// Every kind, in dataflow order.
pub const KINDS: [UnitKind; 14] = [
    UnitKind::GeometryFetch,
    UnitKind::Setup,
    UnitKind::MinMax,
    UnitKind::IntervalManager,
    UnitKind::Segmenter,
    UnitKind::Subsegmenter,
    UnitKind::FragmentRasterizer,
    UnitKind::Tessellator,
    UnitKind::DomainEval,
    UnitKind::TriangleSetup,
    UnitKind::TriangleRasterizer,
    UnitKind::Rop,
    UnitKind::BlendUnit,
    UnitKind::FrameBuffer,
];

/// What the graph says of one kind: its entry.
struct KindInfo {
    /// The name in reports.
    name: &'static str,
    /// Whether the architecture replicates it from the start.
    replicated: bool,
    /// The kind this one sits inside, if any: listed and priced, its cycles its host's, and
    /// not elaborated as a unit of its own.
    inside: Option<UnitKind>,
    /// The DRAM traffic whose bytes are priced on this kind, if any.
    dram: Option<Traffic>,
    /// Whether each of its units holds the frame buffer's colour and depth caches under the
    /// DRAM memory model (`memory.model = "dram"`).
    frame_caches: bool,
    /// The architecture fields that set how fast it works.
    rates: &'static [Rate],
    /// What else its design-point key names, if anything ([`Variant`]).
    variant: Option<Variant>,
}

/// What changes what a kind computes besides its kind, so that the design point (the
/// operations a kind does per busy cycle, DESIGN.md §12) keeps a key for each: the
/// triangle rasterizer's reciprocal (per quad or per pixel), the blend unit's mode, the
/// ROP's path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// The triangle rasterizer's `reciprocal` setting.
    Reciprocal,
    /// The blend mode of a discoid frame.
    BlendMode,
    /// The primitive path.
    Path,
}

/// One of a kind's rates: an architecture field, by its dotted path, whose value sets how
/// fast the kind works (how the cost model scales the kind's datapath from the baseline's,
/// DESIGN.md §12). `{mode}` in a path stands for the blend mode's name (`f32` when none).
/// A kind without a rate (the fetch, the memory port: they compute nothing) runs at the
/// baseline's speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rate {
    /// Cycles an item: the kind is faster when it is smaller.
    CyclesPerItem(&'static str),
    /// Items a cycle: the kind is faster when it is larger.
    ItemsPerCycle(&'static str),
}

/// Traffic through the memory port, as the frame's cost prices it: each kind of traffic's
/// bytes are priced as DRAM on the one kind that declares it ([`UnitKind::dram`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traffic {
    /// The ROPs' frame-buffer reads and writes, and a discoid frame's accumulation targets.
    Frame,
    /// The primitives the geometry fetch reads.
    Geometry,
}

impl UnitKind {
    /// The graph's entry for this kind.
    const fn info(self) -> KindInfo {
        use UnitKind::*;
        let (name, replicated, inside) = match self {
            GeometryFetch => ("GeometryFetch", false, None),
            Setup => ("Setup", false, None),
            MinMax => ("MinMax", false, None),
            IntervalManager => ("IntervalManager", false, None),
            Segmenter => ("Segmenter", true, None),
            Subsegmenter => ("Subsegmenter", true, None),
            FragmentRasterizer => ("FragmentRasterizer", true, None),
            Tessellator => ("Tessellator", false, None),
            DomainEval => ("DomainEval", false, None),
            TriangleSetup => ("TriangleSetup", false, None),
            TriangleRasterizer => ("TriangleRasterizer", true, None),
            Rop => ("Rop", true, None),
            BlendUnit => ("BlendUnit", true, Some(Rop)),
            FrameBuffer => ("FrameBuffer", false, None),
        };
        let dram = match self {
            GeometryFetch => Some(Traffic::Geometry),
            FrameBuffer => Some(Traffic::Frame),
            _ => None,
        };
        let frame_caches = matches!(self, Rop);
        use Rate::{CyclesPerItem as Cycles, ItemsPerCycle as Items};
        let rates: &'static [Rate] = match self {
            GeometryFetch | FrameBuffer => &[],
            Setup => &[Cycles("setup.cycles_per_lembo")],
            // Not `cull_cycles_per_lembo`: the back-face test's cycles, which the design
            // point leaves out (a lower bound, DESIGN.md §12).
            MinMax => &[Cycles("minmax.cycles_per_lembo")],
            IntervalManager => &[
                Cycles("interval_manager.cycles_per_scanline"),
                Cycles("interval_manager.cycles_per_interval"),
            ],
            Segmenter => &[Cycles("segmenter.cycles_per_segment")],
            Subsegmenter => &[Cycles("subsegmenter.cycles_per_subsegment")],
            FragmentRasterizer => &[
                Cycles("rasterizer.cycles_per_subsegment"),
                Items("rasterizer.fragments_per_cycle"),
            ],
            Tessellator => &[Cycles("tessellator.cycles_per_triangle")],
            DomainEval => &[Cycles("domain_eval.cycles_per_vertex")],
            // Not `culled_per_cycle`: a culled triangle does only the area test (2
            // multiplies, 5 adds) before it leaves, so culling faster widens that test
            // alone, which the design point leaves out (a lower bound, DESIGN.md §12).
            TriangleSetup => &[
                Cycles("triangle_setup.cycles_per_triangle"),
                Cycles("triangle_setup.cycles_per_clipped_piece"),
            ],
            TriangleRasterizer => &[Items("triangle_rasterizer.pixels_per_cycle")],
            Rop => &[Items("rop.fragments_per_cycle")],
            BlendUnit => &[Cycles("blend.cycles_per_fragment_{mode}")],
        };
        let variant = match self {
            TriangleRasterizer => Some(Variant::Reciprocal),
            BlendUnit => Some(Variant::BlendMode),
            Rop => Some(Variant::Path),
            _ => None,
        };
        KindInfo {
            name,
            replicated,
            inside,
            dram,
            frame_caches,
            rates,
            variant,
        }
    }

    /// What else the design point keys this kind by ([`Variant`]).
    pub fn variant(self) -> Option<Variant> {
        self.info().variant
    }

    /// The architecture fields that set how fast this kind works ([`Rate`]).
    pub fn rates(self) -> &'static [Rate] {
        self.info().rates
    }

    /// The kind's name, as in reports.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Whether the architecture replicates this kind from the start (its instances are
    /// named `Kind[i]` even when single). MinMax and the IntervalManager are replicable too
    /// but named `Kind[i]` only when there is more than one.
    pub fn replicated(self) -> bool {
        self.info().replicated
    }

    /// The kind whose units this kind's units sit inside (a blend unit in its ROP), which
    /// does their work in its own cycles; None for a unit the pipeline elaborates.
    pub fn inside(self) -> Option<UnitKind> {
        self.info().inside
    }

    /// The DRAM traffic whose bytes are priced on this kind (the frame's on the memory
    /// port, the primitives' on the geometry fetch that reads them); None for most.
    pub fn dram(self) -> Option<Traffic> {
        self.info().dram
    }

    /// Whether each unit of this kind holds the frame buffer's colour and depth caches
    /// under the DRAM memory model (the ROPs: priced as SRAM on them).
    pub fn frame_caches(self) -> bool {
        self.info().frame_caches
    }
}

/// A unit several kinds share (DESIGN.md §3, "One memory port"): its clients by link are
/// the kinds with a boundary into it; its `direct` clients reach it without a link, each
/// timing its own accesses on the port's clock (`pipeline::units::framebuffer::PortClock`),
/// so their busy cycles are the port's too: the port's reported busy cycles include them
/// and the frame lasts at least the port's busy cycles.
#[derive(Clone, Copy, Debug)]
pub struct SharedPort {
    /// The unit that serves the clients.
    pub port: UnitKind,
    /// The clients that reach it without a link.
    pub direct: &'static [UnitKind],
}

impl SharedPort {
    /// Every client of the port among `kinds`: the producers of the boundaries into it,
    /// then its direct clients, in dataflow order.
    pub fn clients(&self, kinds: &[UnitKind]) -> Vec<UnitKind> {
        let mut clients: Vec<UnitKind> = BOUNDARIES
            .iter()
            .filter(|b| b.to == self.port)
            .map(|b| b.from)
            .chain(self.direct.iter().copied())
            .filter(|k| kinds.contains(k))
            .collect();
        clients.sort();
        clients.dedup();
        clients
    }
}

/// Every shared unit: the one memory port, which the ROPs reach by their link and the
/// geometry fetch reads through directly: as a bound on the message port, and by its link
/// `fetch_to_framebuffer` when the port is the DRAM controller ([`Boundary::dram_only`]).
pub const SHARED: &[SharedPort] = &[SharedPort {
    port: UnitKind::FrameBuffer,
    direct: &[UnitKind::GeometryFetch],
}];

/// The kinds a scene with discoids adds to either path, each inside a kind of the path;
/// their operations are in the blend mode's number format, not the datapath's.
pub const DISCOID_KINDS: [UnitKind; 1] = [UnitKind::BlendUnit];

/// Which primitives a scene's surfaces are drawn as, by the functional model and the timed
/// pipeline alike: the crate's one path type (`--path`, a sweep's `path`, report.json's
/// `settings.path`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PrimitivePath {
    /// Lembos by the extreme method (Figure 5; the default).
    #[default]
    Lembo,
    /// The tessellated scene as triangles.
    Triangle,
}

/// Where the triangle path's triangles come from: the architecture's `tessellation.source`
/// (DESIGN.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TessSource {
    /// A mesh tessellated ahead of the frame and stored in memory: the geometry fetch reads
    /// its indices and, through a post-transform vertex cache, its vertices.
    #[default]
    Memory,
    /// The lembos themselves, read from memory and tessellated on chip: a Tessellator makes
    /// each lembo's domain triangles and a DomainEval evaluates their vertices (the DX11
    /// tessellator and domain-shader split).
    OnChip,
}

impl TessSource {
    /// Its name in architecture files and reports (`memory`, `onchip`).
    pub fn name(self) -> &'static str {
        match self {
            TessSource::Memory => "memory",
            TessSource::OnChip => "onchip",
        }
    }
}

impl PrimitivePath {
    /// The path's name in reports and on the command line (`lembo`, `triangle`).
    pub const fn name(self) -> &'static str {
        match self {
            PrimitivePath::Lembo => "lembo",
            PrimitivePath::Triangle => "triangle",
        }
    }

    /// The path whose units `kinds` are: the triangle path if any of them is a kind only
    /// it has, else the lembo path.
    pub fn of_kinds(kinds: impl IntoIterator<Item = UnitKind>) -> PrimitivePath {
        let lembo = PrimitivePath::Lembo.kinds(TessSource::Memory);
        let triangle_only = |k: &UnitKind| {
            !lembo.contains(k)
                && [TessSource::Memory, TessSource::OnChip]
                    .iter()
                    .any(|&s| PrimitivePath::Triangle.kinds(s).contains(k))
        };
        if kinds.into_iter().any(|k| triangle_only(&k)) {
            PrimitivePath::Triangle
        } else {
            PrimitivePath::Lembo
        }
    }

    /// The kinds this path instantiates when the triangle path's triangles come from
    /// `source`, in dataflow order: derived from [`BOUNDARIES`] ([`derive_kinds`]), once.
    pub fn kinds(self, source: TessSource) -> &'static [UnitKind] {
        static KINDS: LazyLock<[Vec<UnitKind>; 3]> = LazyLock::new(|| {
            [
                derive_kinds(PrimitivePath::Lembo, TessSource::Memory),
                derive_kinds(PrimitivePath::Triangle, TessSource::Memory),
                derive_kinds(PrimitivePath::Triangle, TessSource::OnChip),
            ]
        });
        let i = match (self, source) {
            (PrimitivePath::Lembo, _) => 0,
            (PrimitivePath::Triangle, TessSource::Memory) => 1,
            (PrimitivePath::Triangle, TessSource::OnChip) => 2,
        };
        &KINDS[i]
    }
}

/// Every kind a path's primitives pass through: from the geometry fetch, which reads every
/// primitive, along each boundary the path and source take ([`Boundary::taken_by`]), in
/// dataflow order (a kind after every kind that feeds it; among kinds ready together, the
/// one whose boundary comes first in [`BOUNDARIES`]).
pub fn derive_kinds(path: PrimitivePath, source: TessSource) -> Vec<UnitKind> {
    let taken: Vec<&Boundary> = BOUNDARIES
        .iter()
        .filter(|b| b.taken_by(path, source))
        .collect();
    // The kinds reachable from the fetch.
    let mut reached = vec![UnitKind::GeometryFetch];
    let mut i = 0;
    while i < reached.len() {
        let from = reached[i];
        for b in taken.iter().filter(|b| b.from == from) {
            if !reached.contains(&b.to) {
                reached.push(b.to);
            }
        }
        i += 1;
    }
    // Kahn's order over the boundaries among them.
    let mut order = Vec::with_capacity(reached.len());
    while order.len() < reached.len() {
        let next = reached
            .iter()
            .copied()
            .filter(|k| !order.contains(k))
            .find(|k| {
                taken
                    .iter()
                    .filter(|b| b.to == *k && reached.contains(&b.from))
                    .all(|b| order.contains(&b.from))
            })
            .expect("the boundaries of a path form no cycle");
        order.push(next);
    }
    order
}

/// One FIFO between two units: a bounded queue with a transit latency (DESIGN.md §3).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct LinkConfig {
    /// Capacity \[items\]: a producer that has pushed `fifo_depth` items the consumer has not
    /// yet popped waits for a credit. At least 1.
    pub fifo_depth: u32,
    /// Transit time \[cycles\]: an item pushed at cycle p can be popped at p + latency_cycles
    /// at the earliest. At least 1 (a register between two units).
    pub latency_cycles: u64,
}

impl LinkConfig {
    /// A link `fifo_depth` items deep with a transit time of `latency_cycles`.
    pub const fn new(fifo_depth: u32, latency_cycles: u64) -> LinkConfig {
        LinkConfig {
            fifo_depth,
            latency_cycles,
        }
    }
}

impl Default for LinkConfig {
    /// A shallow FIFO behind one register stage, for a link read on its own. Within an
    /// architecture each boundary has its own defaults, in [`BOUNDARIES`].
    fn default() -> LinkConfig {
        LinkConfig::new(4, 1)
    }
}

/// Which consumer of a boundary each item a producer sends goes to: declared on the
/// boundary, applied by the runtime as the item leaves (`pipeline::runtime::Dispatcher`), so
/// that no unit body computes a destination port. Every consumer merges its inputs by
/// (arrival, port) (DESIGN.md §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dispatch {
    /// Round-robin by item: the n-th item a producer sends goes to consumer n mod N (each
    /// producer counts its own items, from consumer 0).
    RoundRobin,
    /// Batches in submission order: the producer cuts its primitives into batches of its
    /// consumers' `batch` and the n-th batch goes to consumer n mod N (DESIGN.md §13,
    /// "Front ends"), so each engine draws its primitives in scene order.
    Batches,
    /// By screen tile: each item to the consumer (a ROP) that owns the screen tile of its
    /// first pixel (`pipeline::tiles::RopTiles`).
    ScreenTile,
}

impl Dispatch {
    /// Its name in the graph's diagram.
    pub fn name(self) -> &'static str {
        match self {
            Dispatch::RoundRobin => "round-robin",
            Dispatch::Batches => "batches",
            Dispatch::ScreenTile => "screen tile",
        }
    }
}

/// One boundary of the graph: the crossbar of links from every instance of `from` to every
/// instance of `to`.
#[derive(Clone, Copy, Debug)]
pub struct Boundary {
    /// Its link's name in the architecture file's `links` and in reports.
    pub key: &'static str,
    /// The producing kind.
    pub from: UnitKind,
    /// The consuming kind.
    pub to: UnitKind,
    /// The link each of its crossbar's links has unless the architecture says otherwise.
    pub default: LinkConfig,
    /// Which consumer each item goes to.
    pub dispatch: Dispatch,
    /// The path whose primitives alone take it, for a boundary out of a kind both paths
    /// have (the geometry fetch feeds the lembo path's setup engines or the triangle
    /// path's); None: every path with both kinds.
    pub path: Option<PrimitivePath>,
    /// The triangle source whose graphs alone wire it, when its two kinds meet in graphs of
    /// both sources but it belongs to one (the fetch feeds the triangle setup engines
    /// directly only from a mesh in memory); None: every graph with both kinds.
    pub only: Option<TessSource>,
    /// Wired only when the frame buffer is the DRAM controller (`memory.model = "dram"`):
    /// the geometry fetch's reads to it, which the message port takes as a bound instead
    /// ([`SHARED`]).
    pub dram_only: bool,
}

impl Boundary {
    /// Whether the primitives of `path`, triangles from `source`, take this boundary.
    pub fn taken_by(&self, path: PrimitivePath, source: TessSource) -> bool {
        self.path.is_none_or(|p| p == path) && self.only.is_none_or(|only| only == source)
    }

    /// Whether it leads to a shared unit from one of its direct clients ([`SHARED`]): a
    /// second boundary out of the client, which sends on it beside the one its path takes
    /// (the geometry fetch's reads to the DRAM controller).
    pub fn to_shared(&self) -> bool {
        SHARED
            .iter()
            .any(|s| s.port == self.to && s.direct.contains(&self.from))
    }

    /// Whether a graph of `kinds`, its triangles from `source`, wires this boundary; `dram`
    /// when its frame buffer is the DRAM controller.
    pub fn wired_in(&self, kinds: &[UnitKind], source: TessSource, dram: bool) -> bool {
        kinds.contains(&self.from)
            && kinds.contains(&self.to)
            && self.only.is_none_or(|only| only == source)
            && (dram || !self.dram_only)
    }
}

/// Every boundary of both paths (the lembo path's in dataflow order, then the triangle
/// path's, then the geometry fetch's, then the on-chip tessellation's): the one place a
/// link is named and given its defaults and its [`Dispatch`]: round-robin by item unless
/// the boundary says otherwise (batches out of the geometry fetch and the domain
/// evaluators, by screen tile into the ROPs).
pub const BOUNDARIES: [Boundary; 15] = {
    use UnitKind::*;
    const fn b(
        key: &'static str,
        from: UnitKind,
        to: UnitKind,
        depth: u32,
        latency: u64,
    ) -> Boundary {
        Boundary {
            key,
            from,
            to,
            default: LinkConfig::new(depth, latency),
            dispatch: Dispatch::RoundRobin,
            path: None,
            only: None,
            dram_only: false,
        }
    }
    const fn tiled(b: Boundary) -> Boundary {
        Boundary {
            dispatch: Dispatch::ScreenTile,
            ..b
        }
    }
    const fn batches(b: Boundary) -> Boundary {
        Boundary {
            dispatch: Dispatch::Batches,
            ..b
        }
    }
    [
        // Depth 8, latency 1: an item is a whole projected lembo (twelve vectors), a wide
        // entry, so few are buffered; adjacent units on one die, one register stage.
        b("setup_to_minmax", Setup, MinMax, 8, 1),
        // Depth 8, latency 1: as setup_to_minmax, a lembo with its scanline range.
        b("minmax_to_interval_manager", MinMax, IntervalManager, 8, 1),
        // Depth 32, latency 1: intervals are narrow (two roots and a scanline), and 32
        // absorb a lembo's burst of intervals against the segmenters' variable rate.
        b(
            "interval_manager_to_segmenter",
            IntervalManager,
            Segmenter,
            32,
            1,
        ),
        // Depth 32, latency 1: narrow segments; the subsegmenter's work per segment varies
        // with curvature, so the FIFO smooths it.
        b("segmenter_to_subsegmenter", Segmenter, Subsegmenter, 32, 1),
        // Depth 32, latency 1: narrow subsegments, one per rasterizer start.
        b(
            "subsegmenter_to_rasterizer",
            Subsegmenter,
            FragmentRasterizer,
            32,
            1,
        ),
        // Depth 64, latency 2: a full crossbar from every rasterizer to every ROP costs one
        // cycle of arbitration on top of the register stage; an item is a span of at most
        // one tile row, and GPU ROP input queues hold tens of such quads or spans.
        tiled(b("rasterizer_to_rop", FragmentRasterizer, Rop, 64, 2)),
        // Depth 32, latency 4: the request queue of the memory controller, and the wires
        // and arbitration to reach it from the ROPs. DRAM access latency itself is not
        // modelled.
        b("rop_to_framebuffer", Rop, FrameBuffer, 32, 4),
        // Depth 32, latency 1: set-up triangles to the triangle rasterizers, as
        // subsegmenter_to_rasterizer in the lembo path.
        b(
            "triangle_setup_to_rasterizer",
            TriangleSetup,
            TriangleRasterizer,
            32,
            1,
        ),
        // Depth 64, latency 2: as rasterizer_to_rop; an item is a quad-row piece.
        tiled(b(
            "triangle_rasterizer_to_rop",
            TriangleRasterizer,
            Rop,
            64,
            2,
        )),
        // Depth 4, latency 40: a batch read from DRAM reaches its setup engine 80 ns after
        // the read was issued at 500 MHz (a DRAM access latency, row miss, of DDR4); four
        // batches in flight per engine keep it fed across that latency down to batches of
        // about 10 primitives at a cycle each.
        Boundary {
            path: Some(PrimitivePath::Lembo),
            ..batches(b("fetch_to_setup", GeometryFetch, Setup, 4, 40))
        },
        // As fetch_to_setup, a batch of triangles to its triangle setup engine, from a mesh
        // in memory (on-chip tessellation feeds the engines from its domain evaluators).
        Boundary {
            path: Some(PrimitivePath::Triangle),
            only: Some(TessSource::Memory),
            ..batches(b(
                "fetch_to_triangle_setup",
                GeometryFetch,
                TriangleSetup,
                4,
                40,
            ))
        },
        // As fetch_to_setup, a batch of lembos to its tessellator.
        Boundary {
            path: Some(PrimitivePath::Triangle),
            only: Some(TessSource::OnChip),
            ..batches(b("fetch_to_tessellator", GeometryFetch, Tessellator, 4, 40))
        },
        // Depth 8, latency 1: a lembo's tessellation (its lattice of domain points), a wide
        // entry like setup_to_minmax's.
        b("tessellator_to_domain_eval", Tessellator, DomainEval, 8, 1),
        // Depth 32, latency 1: batches of a lembo's evaluated triangles to the setup
        // engines, narrow entries (the vertices sit in the domain evaluator's output
        // buffer, as a DX11 domain shader's do).
        batches(b(
            "domain_eval_to_triangle_setup",
            DomainEval,
            TriangleSetup,
            32,
            1,
        )),
        // Depth 16, latency 4: the geometry fetch's read requests to the DRAM controller
        // (`memory.model = "dram"`), beside the ROPs' (as rop_to_framebuffer). The run
        // lengthens the latency to what lets the controller order them against the ROPs'
        // traffic (`pipeline::builder::fetch_request_latency`, DESIGN.md §11).
        Boundary {
            dram_only: true,
            ..b("fetch_to_framebuffer", GeometryFetch, FrameBuffer, 16, 4)
        },
    ]
};

/// The links' names, in the order of [`BOUNDARIES`].
pub const LINK_KEYS: [&str; BOUNDARIES.len()] = {
    let mut keys = [""; BOUNDARIES.len()];
    let mut i = 0;
    while i < keys.len() {
        keys[i] = BOUNDARIES[i].key;
        i += 1;
    }
    keys
};

/// The index in [`BOUNDARIES`] of the boundary from `from` to `to`, if there is one.
pub fn boundary(from: UnitKind, to: UnitKind) -> Option<usize> {
    BOUNDARIES.iter().position(|b| (b.from, b.to) == (from, to))
}

/// One instantiated unit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitInstance {
    /// `Segmenter[2]`, or the kind's name for a unit the architecture does not replicate.
    pub name: String,
    /// Its kind.
    pub kind: UnitKind,
}

/// The kinds `path` instantiates (its triangles from `source`), in dataflow order, with the
/// [`DISCOID_KINDS`] whose host is on the path when the scene has discoids.
pub fn kinds(path: PrimitivePath, source: TessSource, discoids: bool) -> Vec<UnitKind> {
    let mut kinds = path.kinds(source).to_vec();
    if discoids {
        let hosted = DISCOID_KINDS
            .iter()
            .filter(|k| k.inside().is_some_and(|host| kinds.contains(&host)));
        kinds = kinds.iter().chain(hosted).copied().collect();
        kinds.sort();
    }
    kinds
}

/// The units of `kinds` when kind `k` has `count(k)` instances, in the order of `kinds`.
pub fn instances(kinds: &[UnitKind], count: impl Fn(UnitKind) -> u32) -> Vec<UnitInstance> {
    let mut units = Vec::new();
    for &kind in kinds {
        let n = count(kind);
        for i in 0..n {
            // A replicable front-end unit keeps its plain name while single, as in
            // Figure 5 (and in every report before it could be replicated).
            let name = if kind.replicated() || n > 1 {
                format!("{}[{i}]", kind.name())
            } else {
                kind.name().to_string()
            };
            units.push(UnitInstance { name, kind });
        }
    }
    units
}

/// How many units `path` instantiates (its triangles from `source`) when kind `k` has
/// `count(k)` instances, saturating (so that an unvalidated count cannot overflow).
pub fn instance_count(
    path: PrimitivePath,
    source: TessSource,
    count: impl Fn(UnitKind) -> u32,
) -> u32 {
    path.kinds(source)
        .iter()
        .map(|&k| count(k))
        .fold(0, u32::saturating_add)
}

/// A graph to elaborate: the kinds it instantiates, in dataflow order, and the boundaries
/// that may join them (those with both ends among the kinds carry links). [`Graph::of`] is
/// each path's; the pipeline's builder checks any description before it runs one
/// (`pipeline::builder::check`), so a broken one is refused with a [`GraphError`].
#[derive(Clone, Copy, Debug)]
pub struct Graph<'g> {
    /// The path whose primitives it draws: a producer feeding several kinds sends along the
    /// boundary this path takes ([`Boundary::taken_by`]); the others carry nothing.
    pub path: PrimitivePath,
    /// The kinds, in dataflow order.
    pub kinds: &'g [UnitKind],
    /// The boundaries.
    pub boundaries: &'g [Boundary],
    /// Where its triangles come from, for the boundaries of one source ([`Boundary::only`]).
    pub source: TessSource,
    /// Its frame buffer is the DRAM controller, which the geometry fetch reads through
    /// ([`Boundary::dram_only`]).
    pub dram: bool,
}

impl Graph<'static> {
    /// The graph of `path` with the triangle path's triangles from `source`: its kinds and
    /// [`BOUNDARIES`].
    pub fn of(path: PrimitivePath, source: TessSource) -> Self {
        Graph {
            path,
            kinds: path.kinds(source),
            boundaries: &BOUNDARIES,
            source,
            dram: false,
        }
    }

    /// The same graph with its frame buffer the DRAM controller when `dram`.
    pub fn with_dram(self, dram: bool) -> Self {
        Graph { dram, ..self }
    }
}

impl Graph<'_> {
    /// The boundaries with both ends among the graph's kinds (and of its source, if of
    /// one): its links.
    pub fn wired(&self) -> impl Iterator<Item = &Boundary> + '_ {
        self.boundaries
            .iter()
            .filter(|b| b.wired_in(self.kinds, self.source, self.dram))
    }

    /// [`Self::wired`] in dataflow order: by producer, then consumer.
    pub fn in_dataflow_order(&self) -> Vec<&Boundary> {
        let at = |k: UnitKind| self.kinds.iter().position(|&x| x == k);
        let mut wired: Vec<&Boundary> = self.wired().collect();
        wired.sort_by_key(|b| (at(b.from), at(b.to)));
        wired
    }
}

/// What `lembo-sim graph` prints: the graph of `path` (its triangles from `source`) as
/// text: its kinds in dataflow order, its boundaries with their dispatch rules and default
/// links, and its shared units with their clients. Generated from [`BOUNDARIES`],
/// [`SHARED`] and the kinds' entries, so it cannot go stale.
pub fn diagram(path: PrimitivePath, source: TessSource) -> String {
    use std::fmt::Write as _;
    let graph = Graph::of(path, source);
    let mut out = String::new();
    let _ = writeln!(out, "{}", title(path, source));
    let _ = writeln!(out, "\nkinds, in dataflow order ([N]: always replicated):");
    for &k in graph.kinds {
        let _ = writeln!(out, "  {}", kind_label(k));
    }
    for k in DISCOID_KINDS {
        if let Some(host) = k.inside().filter(|h| graph.kinds.contains(h)) {
            let _ = writeln!(
                out,
                "  {} (inside each {}, with discoids)",
                kind_label(k),
                host.name()
            );
        }
    }
    let _ = writeln!(
        out,
        "\nboundaries (a crossbar of links each; default FIFO depth, latency):"
    );
    let rows: Vec<[String; 4]> = graph
        .in_dataflow_order()
        .into_iter()
        .map(|b| {
            [
                b.key.to_string(),
                format!("{} -> {}", b.from.name(), b.to.name()),
                b.dispatch.name().to_string(),
                format!(
                    "depth {}, latency {}",
                    b.default.fifo_depth, b.default.latency_cycles
                ),
            ]
        })
        .collect();
    let width = |c: usize| rows.iter().map(|r| r[c].len()).max().unwrap_or(0);
    let (w0, w1, w2) = (width(0), width(1), width(2));
    for [key, ends, rule, link] in &rows {
        let _ = writeln!(out, "  {key:w0$}  {ends:w1$}  {rule:w2$}  {link}");
    }
    let _ = writeln!(out, "\nshared units:");
    for shared in SHARED.iter().filter(|s| graph.kinds.contains(&s.port)) {
        let clients: Vec<String> = shared
            .clients(graph.kinds)
            .iter()
            .map(|c| {
                let dram_link = BOUNDARIES
                    .iter()
                    .find(|b| b.dram_only && b.from == *c && b.to == shared.port);
                let how = match (shared.direct.contains(c), dram_link) {
                    (true, Some(b)) => format!("direct; by link {} under the DRAM model", b.key),
                    (true, None) => "direct".to_string(),
                    (false, _) => "by link".to_string(),
                };
                format!("{} ({how})", c.name())
            })
            .collect();
        let _ = writeln!(out, "  {}: {}", shared.port.name(), clients.join(", "));
    }
    out
}

/// [`diagram`] as a Graphviz `dot` graph: a box per kind, an edge per boundary labelled
/// with its name and dispatch rule, a dashed edge from each direct client of a shared unit.
pub fn dot(path: PrimitivePath, source: TessSource) -> String {
    use std::fmt::Write as _;
    let graph = Graph::of(path, source);
    let mut out = String::new();
    let _ = writeln!(out, "digraph lembo_sim {{");
    let _ = writeln!(out, "  label=\"{}\";", title(path, source));
    let _ = writeln!(out, "  rankdir=LR;");
    let _ = writeln!(out, "  node [shape=box];");
    for &k in graph.kinds {
        let _ = writeln!(out, "  {} [label=\"{}\"];", k.name(), kind_label(k));
    }
    for b in graph.in_dataflow_order() {
        let _ = writeln!(
            out,
            "  {} -> {} [label=\"{}\\n{}\"];",
            b.from.name(),
            b.to.name(),
            b.key,
            b.dispatch.name()
        );
    }
    for shared in SHARED.iter().filter(|s| graph.kinds.contains(&s.port)) {
        for c in shared.direct.iter().filter(|c| graph.kinds.contains(c)) {
            let _ = writeln!(
                out,
                "  {} -> {} [style=dashed, label=\"shares\"];",
                c.name(),
                shared.port.name()
            );
        }
    }
    let _ = writeln!(out, "}}");
    out
}

/// The diagram's title: the path, and for the triangle path where its triangles come from.
fn title(path: PrimitivePath, source: TessSource) -> String {
    match path {
        PrimitivePath::Lembo => "lembo path".to_string(),
        PrimitivePath::Triangle => format!("triangle path, triangles from {}", source.name()),
    }
}

/// A kind's name in the diagram: `Kind[N]` when the architecture replicates it.
fn kind_label(k: UnitKind) -> String {
    if k.replicated() {
        format!("{}[N]", k.name())
    } else {
        k.name().to_string()
    }
}

/// Why a graph description cannot be elaborated: a defect of the description or of a unit's
/// declaration, found before anything runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GraphError {
    /// A kind the graph instantiates has no unit body to elaborate.
    NoBody {
        /// The kind.
        kind: UnitKind,
    },
    /// A kind appears twice in the graph's kinds.
    Repeated {
        /// The kind.
        kind: UnitKind,
    },
    /// A unit reads items, but no boundary of the graph feeds it.
    Unfed {
        /// The unit's kind.
        kind: UnitKind,
    },
    /// A unit writes items, but no boundary of the graph takes them.
    Undrained {
        /// The unit's kind.
        kind: UnitKind,
    },
    /// A boundary feeds a unit that reads nothing (a source), or leaves one that writes
    /// nothing (a sink).
    NoPort {
        /// The boundary's name.
        boundary: &'static str,
        /// The unit without the port.
        kind: UnitKind,
    },
    /// Two boundaries join the same two kinds (a kind may feed several kinds and be fed
    /// by several, but by one crossbar each).
    Fanned {
        /// The producing kind.
        kind: UnitKind,
        /// The first boundary.
        first: &'static str,
        /// The second boundary.
        second: &'static str,
    },
    /// A boundary's consumer reads another item type than its producer writes.
    ItemMismatch {
        /// The boundary's name.
        boundary: &'static str,
        /// The producer's output type.
        written: &'static str,
        /// The consumer's input type.
        read: &'static str,
    },
    /// A boundary runs against the dataflow order of the graph's kinds (or from a kind to
    /// itself), which would make the graph cyclic.
    BackEdge {
        /// The boundary's name.
        boundary: &'static str,
    },
    /// A boundary dispatched by screen tile carries items that do not say where on screen
    /// they lie.
    NotOnScreen {
        /// The boundary's name.
        boundary: &'static str,
    },
    /// A boundary of the graph has no link configuration in the architecture.
    NoLink {
        /// The boundary's name.
        boundary: &'static str,
    },
}

impl std::fmt::Display for GraphError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GraphError::NoBody { kind } => write!(f, "{} has no unit body", kind.name()),
            GraphError::Repeated { kind } => write!(f, "{} is listed twice", kind.name()),
            GraphError::Unfed { kind } => {
                write!(f, "{} reads items but no boundary feeds it", kind.name())
            }
            GraphError::Undrained { kind } => {
                write!(f, "{} writes items but no boundary takes them", kind.name())
            }
            GraphError::NoPort { boundary, kind } => write!(
                f,
                "boundary {boundary} reaches {}, which has no port on that side",
                kind.name()
            ),
            GraphError::Fanned {
                kind,
                first,
                second,
            } => write!(
                f,
                "{} feeds one kind by two boundaries, {first} and {second}",
                kind.name()
            ),
            GraphError::ItemMismatch {
                boundary,
                written,
                read,
            } => write!(
                f,
                "boundary {boundary} carries {written} but its consumer reads {read}"
            ),
            GraphError::BackEdge { boundary } => write!(
                f,
                "boundary {boundary} runs against the dataflow order (the graph must be acyclic)"
            ),
            GraphError::NotOnScreen { boundary } => write!(
                f,
                "boundary {boundary} is dispatched by screen tile but its items have no pixel"
            ),
            GraphError::NoLink { boundary } => {
                write!(f, "boundary {boundary} has no link configuration")
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each path's kinds, derived from the boundaries, start at the geometry fetch, end at a
    /// sink, and are in dataflow order: every kind but the fetch is fed by a boundary the
    /// path takes from a kind before it, and no boundary the path takes runs backwards. The
    /// graphs themselves are pinned by ARCHITECTURE.md's generated section (a docs test),
    /// so this test names no kind but the fetch and holds for any graph.
    #[test]
    fn each_paths_kinds_follow_from_the_boundaries() {
        for (path, source) in [
            (PrimitivePath::Lembo, TessSource::Memory),
            (PrimitivePath::Triangle, TessSource::Memory),
            (PrimitivePath::Triangle, TessSource::OnChip),
        ] {
            let kinds = path.kinds(source);
            let at = |k: UnitKind| kinds.iter().position(|&x| x == k);
            let taken: Vec<&Boundary> = BOUNDARIES
                .iter()
                .filter(|b| b.taken_by(path, source) && at(b.from).is_some())
                .collect();
            assert_eq!(kinds.first(), Some(&UnitKind::GeometryFetch), "{path:?}");
            let last = *kinds.last().unwrap();
            assert!(taken.iter().all(|b| b.from != last), "{last:?} is no sink");
            for (i, &k) in kinds.iter().enumerate().skip(1) {
                assert!(
                    taken.iter().any(|b| b.to == k && at(b.from) < Some(i)),
                    "{path:?} {source:?}: {k:?} is fed by no kind before it"
                );
            }
            for b in &taken {
                assert!(at(b.from) < at(b.to), "{} runs backwards", b.key);
            }
            let mut unique = kinds.to_vec();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), kinds.len(), "{path:?}: a kind twice");
        }
        assert_eq!(
            PrimitivePath::Lembo.kinds(TessSource::OnChip),
            PrimitivePath::Lembo.kinds(TessSource::Memory)
        );
        // A boundary no path takes would be a unit no graph has.
        for b in BOUNDARIES {
            let taken = [
                (PrimitivePath::Lembo, TessSource::Memory),
                (PrimitivePath::Triangle, TessSource::Memory),
                (PrimitivePath::Triangle, TessSource::OnChip),
            ]
            .into_iter()
            .any(|(p, s)| b.taken_by(p, s) && p.kinds(s).contains(&b.from));
            assert!(taken, "{} is taken by no path", b.key);
        }
    }

    /// Every kind a path instantiates is fed by a boundary from the kind before it (the
    /// graph is a chain of crossbars), and every boundary joins kinds of one path.
    #[test]
    fn graph_boundaries_chain_each_path() {
        let graphs = [
            PrimitivePath::Lembo.kinds(TessSource::Memory),
            PrimitivePath::Triangle.kinds(TessSource::Memory),
            PrimitivePath::Triangle.kinds(TessSource::OnChip),
        ];
        for kinds in graphs {
            for pair in kinds.windows(2) {
                assert!(
                    BOUNDARIES
                        .iter()
                        .any(|b| (b.from, b.to) == (pair[0], pair[1])),
                    "{pair:?}"
                );
            }
        }
        for b in BOUNDARIES {
            assert!(graphs
                .iter()
                .any(|k| k.contains(&b.from) && k.contains(&b.to)));
            assert_eq!(
                boundary(b.from, b.to),
                LINK_KEYS.iter().position(|k| *k == b.key)
            );
        }
        assert!(KINDS.windows(2).all(|w| w[0] < w[1]));
    }
}
