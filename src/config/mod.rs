//! The architecture configuration of the timed pipeline (DESIGN.md §3): how many instances of
//! each unit of Martinelli 2006 Figure 5 there are, what each costs per item, and the depth and
//! latency of the FIFOs between them. Files live in `sim/arch/*.json`; `sim/arch/README.md`
//! states each unit's cost model in words.
//!
//! ```text
//!  Setup ─► MinMax ─► IntervalManager ─► Segmenter ×n ─► Subsegmenter ×n
//!        ─► FragmentRasterizer ×n ─► ROP ×n ─► FrameBuffer port        (─► = one link)
//!  TriangleSetup ─► TriangleRasterizer ×n ─► (the same) ROP ×n       (the triangle path)
//! ```
//!
//! Every unit has a `latency_cycles` (an output is ready that long after the operation that
//! produces it issues) and one or more `cycles_per_*` initiation intervals (how long the
//! unit is busy per item before it can take the next). Every stage boundary has one
//! [`LinkConfig`](crate::graph::LinkConfig), shared by every link of the crossbar between the two stages.
//!
//! A file is parsed with `#[serde(default, deny_unknown_fields)]`, so a file may state only
//! what it changes; unknown fields are refused with [`Error::Parse`] naming their path
//! (`segmenter.cnt`), and values outside what the simulator accepts with [`Error::Invalid`]
//! naming the dotted field path (`links.rasterizer_to_rop.fifo_depth`). A validated
//! configuration is not re-checked downstream.
//!
//! Not modelled here: clock domains (one clock for every unit), per-link overrides within a
//! crossbar, and DRAM timing beyond a bandwidth-limited port.

use crate::error::{read_text_file, Error, Result};
use crate::graph::{self, PrimitivePath, TessSource, UnitInstance, UnitKind};

mod links;
mod ratio;
use crate::json::parse_strict;
pub use links::LinksConfig;
pub use ratio::Ratio;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The embedded `sim/arch/baseline.json`.
const BASELINE_JSON: &str = include_str!("../../sim/arch/baseline.json");

/// The largest accepted instance count of a replicated unit. Beyond it the host would run
/// hundreds of actor threads for no architectural insight.
pub const MAX_UNIT_COUNT: u32 = 64;
/// The largest accepted latency or initiation interval \[cycles\]. Far above any plausible
/// hardware figure; it keeps cycle arithmetic far from overflow.
pub const MAX_CYCLES: u64 = 1_000_000;
/// The largest accepted `fragments_per_cycle` of a rasterizer or ROP.
pub const MAX_FRAGMENTS_PER_CYCLE: u64 = 64;
/// The largest accepted ROP interleave tile side \[pixels\].
pub const MAX_TILE_PX: u32 = 256;
/// The largest accepted `bytes_*` figure of the frame buffer \[bytes\].
pub const MAX_BYTES: u64 = 4096;
/// The largest accepted batch of primitives dealt to one front-end engine \[primitives\].
pub const MAX_BATCH: u32 = 65_536;
/// The largest accepted FIFO depth \[items\]. Deeper FIFOs would only cost host memory.
pub const MAX_FIFO_DEPTH: u32 = 4096;
/// The largest accepted post-transform vertex cache \[entries\]. GPUs' hold tens to a few
/// hundred; beyond this the host's cache lookups would only cost time.
pub const MAX_VERTEX_CACHE: u32 = 4096;
/// The longest accepted frame-buffer access slot \[cycles\]: a DRAM access (row open,
/// column access, precharge) is tens of cycles at most.
pub const MAX_ACCESS_CYCLES: u64 = 64;
/// The largest accepted clock \[MHz\].
pub const MAX_CLOCK_MHZ: f64 = 100_000.0;
/// The longest accepted configuration name \[characters\].
pub const MAX_NAME_CHARS: usize = 64;

/// The whole architecture: units in dataflow order, then the links between them.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct ArchConfig {
    /// Name of the configuration, shown in reports. Default `"baseline"`; a file that
    /// leaves it out is named by its file name ([`ArchConfig::load`]).
    pub name: String,
    /// Clock of every unit \[MHz\], used only to turn cycles into frames per second. Default
    /// 500: the class of a mid-2000s GPU core (the GeForce 6800 GT of the papers' figures
    /// runs at about 400 MHz), rounded so that one cycle is 2 ns.
    pub clock_mhz: f64,
    /// The projection unit (one instance); defaults in [`SetupConfig`].
    pub setup: SetupConfig,
    /// The y-range, cull and clip unit (one instance); defaults in [`MinMaxConfig`].
    pub minmax: MinMaxConfig,
    /// The scanline root finder (one instance); defaults in [`IntervalManagerConfig`].
    pub interval_manager: IntervalManagerConfig,
    /// The curve walkers (replicated); defaults in [`SegmenterConfig`].
    pub segmenter: SegmenterConfig,
    /// The linearity splitters (replicated); defaults in [`SubsegmenterConfig`].
    pub subsegmenter: SubsegmenterConfig,
    /// The fragment generators (replicated); defaults in [`RasterizerConfig`].
    pub rasterizer: RasterizerConfig,
    /// Where the triangle path's triangles come from, and the vertex cache of a mesh in
    /// memory; defaults in [`TessellationConfig`].
    pub tessellation: TessellationConfig,
    /// What the geometry fetch reads per primitive; defaults in [`FetchConfig`].
    pub fetch: FetchConfig,
    /// The on-chip tessellators (the `onchip` source); defaults in [`TessellatorConfig`].
    pub tessellator: TessellatorConfig,
    /// The on-chip domain evaluators (the `onchip` source); defaults in
    /// [`DomainEvalConfig`].
    pub domain_eval: DomainEvalConfig,
    /// The triangle path's setup unit (one instance); defaults in [`TriangleSetupConfig`].
    pub triangle_setup: TriangleSetupConfig,
    /// The triangle path's edge-function rasterizers (replicated); defaults in
    /// [`TriangleRasterizerConfig`].
    pub triangle_rasterizer: TriangleRasterizerConfig,
    /// The depth-test and shading units (replicated, screen-interleaved); defaults in
    /// [`RopConfig`].
    pub rop: RopConfig,
    /// The discoid blend units in the ROPs; defaults in [`BlendConfig`].
    pub blend: BlendConfig,
    /// The frame-buffer memory port (one instance); defaults in [`FrameBufferConfig`].
    pub framebuffer: FrameBufferConfig,
    /// The FIFOs between stages, one setting per boundary; defaults in [`LinksConfig`].
    pub links: LinksConfig,
}

/// Setup: projects a lembo's six control points and six normals to screen space.
/// Replicable: the scene's lembos are dealt to the instances in batches of `batch`, in
/// submission order (batch b to instance b mod count), as a GPU's front end deals batches
/// of primitives to its geometry engines. Item: one lembo.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct SetupConfig {
    /// Number of instances. Default 1, Martinelli's Figure 5.
    pub count: u32,
    /// Lembos per batch dealt to one instance \[primitives\]. Default 32: each engine then
    /// reads runs of consecutive lembos (neighbours in a mesh share edges), and a batch's
    /// 192 busy cycles dwarf the dealing; only matters when `count` > 1.
    pub batch: u32,
    /// Cycles from accepting a lembo to its projected form being ready \[cycles\]. Default
    /// 20: a pipelined 4x4 matrix-vector multiply (about 6 stages of multiply-add), a
    /// reciprocal for the perspective divide (about 10 stages) and the viewport transform
    /// and format conversion (about 4).
    pub latency_cycles: u64,
    /// Initiation interval per lembo \[cycles\]. Default 6: twelve vectors (six points and
    /// six normals) through a transform unit that takes two vectors per cycle.
    pub cycles_per_lembo: u64,
}

/// MinMax: the lembo's screen-space y range, the cull test and the clip of the scanline
/// range to the viewport. Replicable; Setup deals whole lembos (pieces) among instances
/// round-robin. Item: one lembo.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct MinMaxConfig {
    /// Number of instances. Default 1, Martinelli's Figure 5: at 2 cycles a lembo against
    /// the interval manager's 3 a scanline, one MinMax keeps up.
    pub count: u32,
    /// Cycles from accepting a lembo to its scanline range being ready \[cycles\]. Default 8:
    /// the stationary point of each quadratic domain edge needs a divide (about 5 stages),
    /// then a compare tree over the candidates and the clip (about 3).
    pub latency_cycles: u64,
    /// Initiation interval per lembo \[cycles\]. Default 2: three edge extremum candidates
    /// through a divider that starts two per cycle; the six control points' comparisons
    /// overlap with them.
    pub cycles_per_lembo: u64,
    /// Whether MinMax culls lembos (and pieces) whose whole surface faces away from the eye
    /// (DESIGN.md §5, "Back-face culling"): `"off"`, `"on"`, or `"auto"` (default), which
    /// culls when every object of the scene is a closed, consistently oriented mesh, as a
    /// GPU culls what the application marks cullable. A scene of discoids refuses `"on"`.
    pub cull_backfaces: CullBackfaces,
    /// Further busy cycles per lembo (or piece) for the back-face test when the run culls
    /// \[cycles\], culled or not; 0 folds the test into `cycles_per_lembo`. Default 2: the
    /// test's 15 facing coefficients take 36 three-term dot products and 9 cross products
    /// (about 170 multiplies and 130 adds, `raster::facing`), which MinMax's datapath, sized
    /// for its divides and compares, issues over two more cycles.
    pub cull_cycles_per_lembo: u64,
}

/// Whether a path culls back faces (`minmax.cull_backfaces` on the lembo path,
/// `triangle_setup.cull_backfaces` on the triangle path; DESIGN.md §5).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum CullBackfaces {
    /// Never: both sides are drawn (and shaded two-sided), the model before culling.
    Off,
    /// Always; the front is the scene's outward winding when every object is closed,
    /// else counter-clockwise (OpenGL's default front face).
    On,
    /// When every object of the scene is a closed, consistently oriented mesh (every edge
    /// shared by exactly two triangles running it in opposite directions), the front
    /// being its outward side.
    #[default]
    Auto,
}

impl CullBackfaces {
    /// Its name in architecture files and reports.
    pub fn name(self) -> &'static str {
        match self {
            CullBackfaces::Off => "off",
            CullBackfaces::On => "on",
            CullBackfaces::Auto => "auto",
        }
    }
}

/// IntervalManager: for each scanline y_j of a lembo, the roots of the three domain edges
/// with Y = y_j, paired into intervals of the parameter domain. Replicable; MinMax deals
/// whole lembos (pieces, with all their scanlines) among instances round-robin, so an
/// instance walks a lembo's scanlines in order. Items: one scanline, and one interval
/// emitted.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct IntervalManagerConfig {
    /// Number of instances. Default 1, Figure 5's single interval manager (on scenes of
    /// small lembos it is the bottleneck whatever k is: raise it to see what a replicated
    /// front end buys).
    pub count: u32,
    /// Cycles from issuing a scanline to its intervals being ready \[cycles\]. Default 12: a
    /// pipelined quadratic solver, a square root (about 8 stages) and a divide overlapped
    /// with it, then the sort and pairing of the roots (about 4).
    pub latency_cycles: u64,
    /// Initiation interval per scanline \[cycles\]. Default 3: a pipelined quadratic solver
    /// delivers one root pair per cycle after a fixed latency; three domain edges => 3
    /// cycles per scanline.
    pub cycles_per_scanline: u64,
    /// Extra cycles per interval emitted \[cycles\]. Default 1: an interval is one output word
    /// and the output port writes one word per cycle.
    pub cycles_per_interval: u64,
}

/// Segmenter: walks the curve Y(u,v) = y_j across an interval in steps whose midpoint
/// error is exactly k. Replicated; intervals are dispatched among instances. Item: one
/// segment emitted.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct SegmenterConfig {
    /// Number of instances. Default 2: the segmenter iterates (one step per segment) where
    /// the interval manager does fixed work per scanline, so it is the first stage that
    /// needs replication to keep up.
    pub count: u32,
    /// Cycles from accepting an interval to its first segment being ready \[cycles\]. Default
    /// 16: the step solves a quadratic for the next endpoint (square root and divide, about
    /// 12 stages) and evaluates the midpoint error (about 4).
    pub latency_cycles: u64,
    /// Initiation interval per segment \[cycles\]. Default 2: each step issues an endpoint
    /// solve and a midpoint error evaluation on one shared pipelined evaluator, two issue
    /// slots per segment.
    pub cycles_per_segment: u64,
}

/// Subsegmenter: splits a segment so that x(t) is linear within k on each piece.
/// Replicated. Item: one subsegment emitted.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct SubsegmenterConfig {
    /// Number of instances. Default 2: one per segmenter, so that each segmenter's output
    /// has a subsegmenter to go to without waiting.
    pub count: u32,
    /// Cycles from accepting a segment to its first subsegment being ready \[cycles\].
    /// Default 8: a quadratic evaluation of x(t) (about 5 stages of multiply-add) and the
    /// comparison of its deviation with k (about 3).
    pub latency_cycles: u64,
    /// Initiation interval per subsegment \[cycles\]. Default 1: the split points come from a
    /// fully pipelined evaluator, one per cycle.
    pub cycles_per_subsegment: u64,
}

/// FragmentRasterizer: walks a subsegment's pixel centres, computing u, v, z and the normal
/// by increments. Replicated. Items: one subsegment, and one fragment span (the fragments
/// of one subsegment inside one ROP tile).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct RasterizerConfig {
    /// Number of instances. Default 4: one per ROP, so that fragment generation and
    /// fragment testing have the same peak rate.
    pub count: u32,
    /// Cycles from accepting a subsegment to its first span being ready \[cycles\]. Default
    /// 4: the first fragment's values from the increment setup, through an adder pipeline.
    pub latency_cycles: u64,
    /// Initiation interval per subsegment for the increment setup \[cycles\]. Default 1: the
    /// start values and forward differences of u, v, z and the normal come from one
    /// pipelined evaluation per subsegment.
    pub cycles_per_subsegment: u64,
    /// Fragments produced per cycle; a span of n fragments costs ceil(n / this) cycles.
    /// Default 1: each fragment is one add per interpolated quantity, one fragment per
    /// cycle as in a classic scan converter.
    pub fragments_per_cycle: u64,
}

/// Where the triangle path's triangles come from (DESIGN.md §5, "Tessellation paid for").
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct TessellationConfig {
    /// `memory`: a mesh tessellated before the frame, read by the geometry fetch as
    /// indices and, on a vertex cache miss, vertices; `onchip`: the lembos are read and
    /// tessellated by Tessellator and DomainEval units. Default `memory`.
    pub source: TessSource,
    /// Entries of each triangle setup engine's post-transform vertex cache (FIFO
    /// replacement, one per engine, so a batch dealt to another engine starts cold), with
    /// the `memory` source \[vertices\]. Default 32: post-transform caches of GPUs of the
    /// papers' era held tens of entries, and 32 hold the two lattice rows a tessellated
    /// lembo's triangles straddle up to n = 15.
    pub vertex_cache_entries: u32,
}

/// GeometryFetch (DESIGN.md §3, "Geometry fetch"): the bytes of a primitive as it is
/// stored in memory, read through the memory port (`framebuffer`) at the start of a frame
/// and priced as DRAM (`cost.geometry_bytes`). Discoids keep their own fixed records.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct FetchConfig {
    /// Bytes of one lembo as stored and read for Setup or the Tessellators \[bytes\].
    /// Default 144 (`lembo::LEMBO_BYTES`): six points and six normals in f32.
    pub bytes_per_lembo: u64,
    /// Bytes of one vertex of a mesh tessellated in memory, read on each post-transform
    /// vertex cache miss \[bytes\]. Default 24 (`lembo::tessellate::VERTEX_BYTES`):
    /// a position and a normal in f32.
    pub bytes_per_vertex: u64,
    /// Bytes of one triangle's indices in a mesh tessellated in memory \[bytes\]. Default 12
    /// (`lembo::tessellate::INDEX_BYTES_PER_TRIANGLE`): three 32-bit indices.
    pub index_bytes_per_triangle: u64,
}

impl Default for FetchConfig {
    fn default() -> FetchConfig {
        FetchConfig {
            // The model's storage formats (a unit test holds them equal); `config` imports
            // only leaves, so the figures are written here.
            bytes_per_lembo: 144,
            bytes_per_vertex: 24,
            index_bytes_per_triangle: 12,
        }
    }
}

impl FetchConfig {
    /// Bytes of an indexed mesh of `triangles` triangles and `vertices` vertices
    /// \[bytes\].
    pub fn mesh_bytes(&self, triangles: u64, vertices: u64) -> u64 {
        triangles * self.index_bytes_per_triangle + vertices * self.bytes_per_vertex
    }
}

/// Tessellator (the `onchip` source): makes a lembo's n² domain triangles (their
/// connectivity and their (n + 1)(n + 2)/2 domain points), as the fixed-function
/// tessellator of a DX11 GPU does. Replicable: the geometry fetch deals batches of
/// lembos to the instances in submission order. Item: one lembo.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct TessellatorConfig {
    /// Number of instances. Default 1.
    pub count: u32,
    /// Lembos per batch dealt to one instance \[primitives\]. Default 4: a batch of four
    /// 144-byte lembos is nine cycles of the memory port.
    pub batch: u32,
    /// Cycles from accepting a lembo to its first domain points being ready \[cycles\].
    /// Default 8: the lattice step (a reciprocal of n) and the first row's indices.
    pub latency_cycles: u64,
    /// Initiation interval per triangle generated \[cycles\], a multiple of 1/64
    /// ([`Ratio`]: 0.5 is two triangles a cycle); a lembo of t triangles costs
    /// ceil(t * this) cycles, at least one. Default 1: a DX11 tessellator emits about one
    /// triangle (with its new domain point) per clock.
    pub cycles_per_triangle: Ratio,
}

/// DomainEval (the `onchip` source): evaluates each domain point of a lembo's tessellation,
/// position and unit normal, from the lembo's quadratic functions (the DX11 domain
/// shader's work), and passes the lembo's triangles in batches of `triangle_setup.batch`
/// to the triangle setup engines in turn. Replicable: the tessellators deal lembos to the
/// instances round-robin. Item: one vertex evaluated.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct DomainEvalConfig {
    /// Number of instances. Default 1.
    pub count: u32,
    /// Cycles from accepting a lembo to its first vertices being ready \[cycles\]. Default
    /// 16: the six quadratic basis functions (about 4 stages), two weighted sums of six
    /// vectors (about 6) and the normal's normalisation (a reciprocal square root, about 6).
    pub latency_cycles: u64,
    /// Initiation interval per vertex evaluated \[cycles\], a multiple of 1/64 ([`Ratio`]:
    /// 0.5 is two vertices a cycle). Default 1: one fully pipelined evaluator. Each lembo's
    /// (n + 1)(n + 2)/2 points are evaluated: patches are independent, so a point on an edge
    /// two lembos share is evaluated by both, as a domain shader does.
    pub cycles_per_vertex: Ratio,
}

/// TriangleSetup (the triangle path, DESIGN.md §5): projects a triangle's three vertices,
/// snaps them to 16.8 fixed point and sets up the integer edge functions and the
/// perspective-correct attribute planes. Replicable: triangles are dealt to the instances
/// in batches of `batch`, in submission order (batch b to instance b mod count), as GPUs
/// since 2010 deal batches of primitives to several geometry and setup engines, each about
/// one primitive per clock. Item: one triangle.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct TriangleSetupConfig {
    /// Number of instances. Default 1.
    pub count: u32,
    /// Triangles per batch dealt to one instance \[primitives\]. Default 32 (a batch of
    /// vertex work of a GPU's front end); only matters when `count` > 1.
    pub batch: u32,
    /// Cycles from accepting a triangle to its setup being ready \[cycles\]. Default 20, as
    /// the lembo Setup: a transform and perspective divide per vertex (about 16 stages) and
    /// the edge-function and plane setup (about 4).
    pub latency_cycles: u64,
    /// Initiation interval per triangle \[cycles\]. Default 1: DESIGN.md §5's "setup 1 triangle
    /// per cycle", the rate of GPUs of the papers' era and since.
    pub cycles_per_triangle: u64,
    /// Culled triangles disposed of per `cycles_per_triangle` \[triangles\]: a triangle
    /// culled whole (back-facing, outside the view, or covering no pixel centre), not
    /// clipped, leaves the engine after its cull test without edge-function or plane setup,
    /// so an engine can cull faster than it sets up. Default 1 (culled triangles cost
    /// what drawn ones do, the papers' era). Later GPUs cull faster than they draw: AMD's
    /// RDNA whitepaper (2019) gives its primitive units two culled primitives a clock
    /// against one drawn (as recalled, not checked here), and Mesa's piglit culling test
    /// (M. Olšák, 2019) measured a Radeon drawing 2.8 G triangles/s and culling 4.8 G/s of
    /// triangles outside the view.
    pub culled_per_cycle: u64,
    /// Further busy cycles per piece of a clipped triangle \[cycles\]: a triangle crossing
    /// the near or far plane, or with a vertex beyond the 16.8 range (±32767 pixels), is
    /// clipped against the two depth planes and the four guard-band planes (those it
    /// crosses) and its polygon fanned into 1 to 7 triangles, each set up (and culled or
    /// emitted) as a triangle of its own, so it costs `cycles_per_triangle` plus this per
    /// fan triangle. Default 1: each piece takes the snap and edge-function stage
    /// for one cycle, as a triangle does; meanwhile the polygon's new vertices (at most
    /// fan + 2; a plane distance, a divide and a blend each, then the projection) fit in
    /// the three vertex slots per cycle of the transform stage, which the pieces leave idle.
    pub cycles_per_clipped_piece: u64,
    /// Whether setup culls triangles facing away from the eye by their snapped signed area,
    /// at `culled_per_cycle` (DESIGN.md §5, "Back-face culling"): `"off"`, `"on"`, or
    /// `"auto"` (default), as [`MinMaxConfig::cull_backfaces`].
    pub cull_backfaces: CullBackfaces,
}

/// TriangleRasterizer (the triangle path, DESIGN.md §5): tests 2x2 pixel quads against the
/// integer edge functions with the top-left fill rule. Replicated; triangles are dispatched
/// round-robin. Items: one triangle, and one quad-row piece (a triangle's quads in one
/// pair of pixel rows inside one ROP tile).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct TriangleRasterizerConfig {
    /// Number of instances. Default 1: one rasterizer at 8 pixels per cycle has twice the
    /// peak rate of the default four ROPs.
    pub count: u32,
    /// Cycles from accepting a triangle to its first quads being ready \[cycles\]. Default 4,
    /// as the lembo FragmentRasterizer.
    pub latency_cycles: u64,
    /// Pixels tested per cycle; a piece of q quads costs ceil(4 q / this) cycles, at least
    /// one, and a triangle that covers no pixel costs one cycle. Default 8: DESIGN.md §5, two
    /// quads per cycle.
    pub pixels_per_cycle: u64,
    /// Where the reciprocal of the interpolated 1/w is taken for perspective-correct
    /// attributes: `"quad"` (default; one reciprocal per covered quad, refined per covered
    /// pixel by a Newton step) or `"pixel"` (one per covered pixel). A pricing choice only
    /// (`cost::built`, DESIGN.md §12): the model divides exactly, whatever this says.
    pub reciprocal: Reciprocal,
}

/// Where the triangle rasterizer takes the reciprocal for perspective-correct attributes
/// ([`TriangleRasterizerConfig::reciprocal`]).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Reciprocal {
    /// One reciprocal per covered quad, at its upper-left pixel centre; each covered pixel
    /// refines it by one Newton step, w (2 - w (1/w)_pixel): 2 multiplies and an add.
    #[default]
    Quad,
    /// One reciprocal per covered pixel.
    Pixel,
}

/// ROP: depth test and per-fragment Phong shading for the pixels of its screen tiles.
/// Replicated; screen-interleaved. Item: one fragment span.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct RopConfig {
    /// Number of instances. Default 4: the ROP count of a mid-range part of the papers'
    /// era, and enough that the (tx + ty) interleave spreads a lembo over several ROPs.
    pub count: u32,
    /// Cycles from accepting a span to its write burst being ready \[cycles\]. Default 4: the
    /// depth compare and the shading arithmetic of one fragment, pipelined.
    pub latency_cycles: u64,
    /// Fragments tested and shaded per cycle, a multiple of 1/64 ([`Ratio`]: 0.5 is a
    /// fragment every two cycles); a span of n fragments costs ceil(n / this) cycles.
    /// Default 1: one depth test and one Phong evaluation per cycle per ROP.
    pub fragments_per_cycle: Ratio,
    /// Side of a screen interleave tile \[pixels\]: tile (tx, ty) of tile_px x tile_px pixels
    /// goes to ROP (tx + ty) % count. Default 8: 64 pixels, the size of a frame-buffer
    /// memory burst tile; small enough that one lembo covers several tiles and thus several
    /// ROPs, large enough that a span is not cut at every few pixels.
    pub tile_px: u32,
}

/// The discoid blend units (Piranda et al. 2006, DESIGN.md §4): one per ROP, instantiated only for
/// scenes with discoids. A fragment kept by the accumulation pass costs the ROP
/// `cycles_per_fragment_<mode>` more than its depth test and moves
/// `BlendMode::bytes_per_fragment` through the frame-buffer port (8, 16 or 32 bytes).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct BlendConfig {
    /// Blend cycles per fragment in rgba8 (Table 1: two 8-bit averages and two nibble
    /// adds) \[cycles\]. Default 1: 8-bit blenders run at full rate.
    pub cycles_per_fragment_rgba8: u64,
    /// Blend cycles per fragment in f16 \[cycles\]. Default 1: the GeForce 6 series blends
    /// FP16 targets at full rate.
    pub cycles_per_fragment_f16: u64,
    /// Blend cycles per fragment in f32 \[cycles\]. Default 2: FP32 blending at half rate,
    /// as GPUs that support it run it.
    pub cycles_per_fragment_f32: u64,
}

impl Default for BlendConfig {
    fn default() -> BlendConfig {
        BlendConfig {
            cycles_per_fragment_rgba8: 1,
            cycles_per_fragment_f16: 1,
            cycles_per_fragment_f32: 2,
        }
    }
}

/// The frame-buffer port: one memory port shared by every ROP. One instance. Item: one
/// write burst.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
#[serde(default, deny_unknown_fields)]
pub struct FrameBufferConfig {
    /// Bytes the port transfers per cycle \[bytes/cycle\]; with the default
    /// `access_cycles` of 1 a burst of b bytes costs ceil(b / this) cycles, at least one. Default 64: the GeForce 6800 GT the discoid paper measured on
    /// moves about 32 GB/s, 64 bytes per cycle at the default 500 MHz. Four ROPs at full
    /// rate ask for up to 48 bytes per cycle, so the port limits only wider units.
    pub bytes_per_cycle: u64,
    /// Bytes moved per fragment tested \[bytes\]. Default 4: one 32-bit depth read (24-bit
    /// depth and 8-bit stencil, the usual packed format).
    pub bytes_per_fragment_tested: u64,
    /// Bytes moved per fragment that passes the depth test \[bytes\]. Default 8: a 32-bit
    /// RGBA8 colour write and a 32-bit depth write.
    pub bytes_per_fragment_written: u64,
    /// The port's per-access cost: the length of its transfer slot \[cycles\], a multiple
    /// of 1/64 ([`Ratio`]). The port moves data in slots of this many cycles, each carrying
    /// `bytes_per_cycle` * this bytes; an access of b bytes occupies whole slots,
    /// this * ceil(b / (bytes_per_cycle * this)) cycles, at least one slot (DESIGN.md §3,
    /// "One memory port"). Fractions of a cycle are kept exactly and whole cycles charged
    /// as the port's time crosses them. Default 1: every access occupies at least a cycle,
    /// and a longer one ceil(b / bytes_per_cycle) cycles. It moves no bytes, so it
    /// changes no energy.
    pub access_cycles: Ratio,
}

impl FrameBufferConfig {
    /// The slots an access of `bytes` occupies: ceil(bytes / (bytes_per_cycle *
    /// access_cycles)), 0 for no bytes.
    pub fn slots(&self, bytes: u64) -> u64 {
        let slot_bytes_den = self.bytes_per_cycle as u128 * self.access_cycles.steps() as u128;
        (bytes as u128 * Ratio::DEN as u128).div_ceil(slot_bytes_den.max(1)) as u64
    }

    /// The time `slots` slots take, in 1/[`Ratio::DEN`] cycles.
    pub fn slot_time(&self, slots: u64) -> u128 {
        slots as u128 * self.access_cycles.steps() as u128
    }

    /// Whole cycles of one transfer of `bytes` on an idle port (a resolve pass), 0 for no
    /// bytes: ceil(bytes / bytes_per_cycle) with the default `access_cycles`.
    pub fn transfer_cycles(&self, bytes: u64) -> u64 {
        self.slot_time(self.slots(bytes))
            .div_ceil(Ratio::DEN as u128) as u64
    }
}

impl Default for ArchConfig {
    fn default() -> ArchConfig {
        ArchConfig {
            name: "baseline".to_string(),
            clock_mhz: 500.0,
            setup: SetupConfig::default(),
            minmax: MinMaxConfig::default(),
            interval_manager: IntervalManagerConfig::default(),
            segmenter: SegmenterConfig::default(),
            subsegmenter: SubsegmenterConfig::default(),
            rasterizer: RasterizerConfig::default(),
            tessellation: TessellationConfig::default(),
            fetch: FetchConfig::default(),
            tessellator: TessellatorConfig::default(),
            domain_eval: DomainEvalConfig::default(),
            triangle_setup: TriangleSetupConfig::default(),
            triangle_rasterizer: TriangleRasterizerConfig::default(),
            rop: RopConfig::default(),
            blend: BlendConfig::default(),
            framebuffer: FrameBufferConfig::default(),
            links: LinksConfig::default(),
        }
    }
}

impl Default for SetupConfig {
    fn default() -> SetupConfig {
        SetupConfig {
            count: 1,
            batch: 32,
            latency_cycles: 20,
            cycles_per_lembo: 6,
        }
    }
}

impl Default for MinMaxConfig {
    fn default() -> MinMaxConfig {
        MinMaxConfig {
            count: 1,
            latency_cycles: 8,
            cycles_per_lembo: 2,
            cull_backfaces: CullBackfaces::Auto,
            cull_cycles_per_lembo: 2,
        }
    }
}

impl Default for IntervalManagerConfig {
    fn default() -> IntervalManagerConfig {
        IntervalManagerConfig {
            count: 1,
            latency_cycles: 12,
            cycles_per_scanline: 3,
            cycles_per_interval: 1,
        }
    }
}

impl Default for SegmenterConfig {
    fn default() -> SegmenterConfig {
        SegmenterConfig {
            count: 2,
            latency_cycles: 16,
            cycles_per_segment: 2,
        }
    }
}

impl Default for SubsegmenterConfig {
    fn default() -> SubsegmenterConfig {
        SubsegmenterConfig {
            count: 2,
            latency_cycles: 8,
            cycles_per_subsegment: 1,
        }
    }
}

impl Default for RasterizerConfig {
    fn default() -> RasterizerConfig {
        RasterizerConfig {
            count: 4,
            latency_cycles: 4,
            cycles_per_subsegment: 1,
            fragments_per_cycle: 1,
        }
    }
}

impl Default for TriangleSetupConfig {
    fn default() -> TriangleSetupConfig {
        TriangleSetupConfig {
            count: 1,
            batch: 32,
            latency_cycles: 20,
            cycles_per_triangle: 1,
            culled_per_cycle: 1,
            cycles_per_clipped_piece: 1,
            cull_backfaces: CullBackfaces::Auto,
        }
    }
}

impl Default for TessellationConfig {
    fn default() -> TessellationConfig {
        TessellationConfig {
            source: TessSource::Memory,
            vertex_cache_entries: 32,
        }
    }
}

impl Default for TessellatorConfig {
    fn default() -> TessellatorConfig {
        TessellatorConfig {
            count: 1,
            batch: 4,
            latency_cycles: 8,
            cycles_per_triangle: Ratio::whole(1),
        }
    }
}

impl Default for DomainEvalConfig {
    fn default() -> DomainEvalConfig {
        DomainEvalConfig {
            count: 1,
            latency_cycles: 16,
            cycles_per_vertex: Ratio::whole(1),
        }
    }
}

impl Default for TriangleRasterizerConfig {
    fn default() -> TriangleRasterizerConfig {
        TriangleRasterizerConfig {
            count: 1,
            latency_cycles: 4,
            pixels_per_cycle: 8,
            reciprocal: Reciprocal::Quad,
        }
    }
}

impl Default for RopConfig {
    fn default() -> RopConfig {
        RopConfig {
            count: 4,
            latency_cycles: 4,
            fragments_per_cycle: Ratio::whole(1),
            tile_px: 8,
        }
    }
}

impl Default for FrameBufferConfig {
    fn default() -> FrameBufferConfig {
        FrameBufferConfig {
            bytes_per_cycle: 64,
            bytes_per_fragment_tested: 4,
            bytes_per_fragment_written: 8,
            access_cycles: Ratio::whole(1),
        }
    }
}

impl ArchConfig {
    /// Reads, parses and validates an architecture file. A file without a `"name"` is named
    /// by its file name (`my_arch` for `my_arch.json`), not the default `baseline`: it is a
    /// different architecture, and every output labels it.
    pub fn load(path: &Path) -> Result<ArchConfig> {
        let text = read_text_file(path)?;
        let mut config = ArchConfig::from_json(&text, &path.display().to_string())?;
        let named =
            serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| v.get("name").is_some());
        if !named {
            if let Some(stem) = path.file_stem() {
                config.name = stem.to_string_lossy().into_owned();
            }
        }
        Ok(config)
    }

    /// Parses and validates an architecture from JSON text; `file` is the name used in
    /// error messages. Fields the text leaves out keep their defaults.
    pub fn from_json(text: &str, file: &str) -> Result<ArchConfig> {
        let config: ArchConfig = parse_strict(text, file)?;
        config.validate(file)?;
        Ok(config)
    }

    /// This architecture with the fields `sets` (dotted path, value) set, validated as an
    /// architecture file is; an error names `flag` and the field (`--set`).
    pub fn with_fields(
        &self,
        sets: &[(String, serde_json::Value)],
        flag: &str,
    ) -> Result<ArchConfig> {
        if sets.is_empty() {
            return Ok(self.clone());
        }
        let mut value = serde_json::to_value(self).expect("the architecture serialises");
        for (path, v) in sets {
            crate::json::set_field(&mut value, path, v.clone(), "architecture").map_err(
                |message| Error::Parse {
                    file: crate::error::COMMAND_LINE.into(),
                    field: format!("{flag} {path}"),
                    message,
                },
            )?;
        }
        let config: ArchConfig =
            serde_path_to_error::deserialize(value).map_err(|e| Error::Parse {
                file: crate::error::COMMAND_LINE.into(),
                field: format!("{flag} {}", e.path()),
                message: e.into_inner().to_string(),
            })?;
        config.validate(&format!("{} ({flag})", crate::error::COMMAND_LINE))?;
        Ok(config)
    }

    /// The embedded `sim/arch/baseline.json`, equal to [`ArchConfig::default`].
    pub fn baseline() -> ArchConfig {
        // The text is part of the binary and checked by a unit test, so failing here is a
        // build defect, not bad input.
        ArchConfig::from_json(BASELINE_JSON, "sim/arch/baseline.json (embedded)")
            .expect("the embedded baseline architecture is valid")
    }

    /// How many instances of `kind` this architecture has, and the latency of each
    /// \[cycles\]: the one place a unit kind's configuration section is found. A blend unit
    /// sits in each ROP, so it has the ROPs' count and latency.
    pub fn unit(&self, kind: UnitKind) -> (u32, u64) {
        match kind {
            // The geometry fetch's time is the memory port's rate and the DRAM latency of
            // its links (`fetch_to_setup`).
            UnitKind::GeometryFetch => (1, 1),
            UnitKind::Setup => (self.setup.count, self.setup.latency_cycles),
            UnitKind::MinMax => (self.minmax.count, self.minmax.latency_cycles),
            UnitKind::IntervalManager => (
                self.interval_manager.count,
                self.interval_manager.latency_cycles,
            ),
            UnitKind::Segmenter => (self.segmenter.count, self.segmenter.latency_cycles),
            UnitKind::Subsegmenter => (self.subsegmenter.count, self.subsegmenter.latency_cycles),
            UnitKind::FragmentRasterizer => (self.rasterizer.count, self.rasterizer.latency_cycles),
            UnitKind::Tessellator => (self.tessellator.count, self.tessellator.latency_cycles),
            UnitKind::DomainEval => (self.domain_eval.count, self.domain_eval.latency_cycles),
            UnitKind::TriangleSetup => (
                self.triangle_setup.count,
                self.triangle_setup.latency_cycles,
            ),
            UnitKind::TriangleRasterizer => (
                self.triangle_rasterizer.count,
                self.triangle_rasterizer.latency_cycles,
            ),
            UnitKind::Rop | UnitKind::BlendUnit => (self.rop.count, self.rop.latency_cycles),
            UnitKind::FrameBuffer => (1, 1),
        }
    }

    /// The architecture field that sets `kind`'s instance count (`"rasterizer.count"`);
    /// None for a kind that has one instance by construction (the geometry fetch and the
    /// frame-buffer port). A blend unit sits in each ROP, so the ROPs' count is its.
    pub fn count_field(kind: UnitKind) -> Option<&'static str> {
        Some(match kind {
            UnitKind::GeometryFetch | UnitKind::FrameBuffer => return None,
            UnitKind::Setup => "setup.count",
            UnitKind::MinMax => "minmax.count",
            UnitKind::IntervalManager => "interval_manager.count",
            UnitKind::Segmenter => "segmenter.count",
            UnitKind::Subsegmenter => "subsegmenter.count",
            UnitKind::FragmentRasterizer => "rasterizer.count",
            UnitKind::Tessellator => "tessellator.count",
            UnitKind::DomainEval => "domain_eval.count",
            UnitKind::TriangleSetup => "triangle_setup.count",
            UnitKind::TriangleRasterizer => "triangle_rasterizer.count",
            UnitKind::Rop | UnitKind::BlendUnit => "rop.count",
        })
    }

    /// The units `path` instantiates on this architecture, in dataflow order, with their
    /// latencies \[cycles\].
    pub fn instances(&self, path: PrimitivePath) -> Vec<(UnitInstance, u64)> {
        self.instances_with(path, false)
    }

    /// [`ArchConfig::instances`], with the units a scene with discoids adds when `discoids`
    /// ([`graph::DISCOID_KINDS`]).
    pub fn instances_with(&self, path: PrimitivePath, discoids: bool) -> Vec<(UnitInstance, u64)> {
        graph::instances(
            &graph::kinds(path, self.tessellation.source, discoids),
            |k| self.unit(k).0,
        )
        .into_iter()
        .map(|u| {
            let latency = self.unit(u.kind).1;
            (u, latency)
        })
        .collect()
    }

    /// Unit instances of the lembo path (saturating, so that an unvalidated configuration
    /// cannot overflow).
    pub fn units(&self) -> u32 {
        graph::instance_count(PrimitivePath::Lembo, self.tessellation.source, |k| {
            self.unit(k).0
        })
    }

    /// The FIFO entries of every link `units` instantiate: each boundary's crossbar has one
    /// link per (producer, consumer) pair, each `fifo_depth` entries deep; a boundary
    /// between kinds absent from `units` has no links. Item sizes are not modelled, so this
    /// counts entries, not bytes \[entries\].
    pub fn fifo_entries(&self, units: &[UnitInstance]) -> u64 {
        let count = |kind: UnitKind| units.iter().filter(|u| u.kind == kind).count() as u64;
        let kinds: Vec<UnitKind> = units.iter().map(|u| u.kind).collect();
        self.links
            .boundaries()
            .filter(|(b, _)| b.wired_in(&kinds, self.tessellation.source))
            .map(|(b, link)| count(b.from) * count(b.to) * link.fifo_depth as u64)
            .sum()
    }

    /// Checks every value against what the simulator accepts; the first refused value is
    /// returned as [`Error::Invalid`] naming its dotted field path.
    pub fn validate(&self, file: &str) -> Result<()> {
        let check = Check { file };
        let chars = self.name.chars().count();
        if chars == 0 || chars > MAX_NAME_CHARS {
            return Err(Error::invalid(
                file,
                "name",
                format!("{:?}", self.name),
                format!("must be 1 to {MAX_NAME_CHARS} characters long"),
            ));
        }
        if !(self.clock_mhz.is_finite() && self.clock_mhz > 0.0 && self.clock_mhz <= MAX_CLOCK_MHZ)
        {
            return Err(Error::invalid(
                file,
                "clock_mhz",
                self.clock_mhz,
                format!("must be a finite clock above 0 and at most {MAX_CLOCK_MHZ} MHz"),
            ));
        }

        let setup = &self.setup;
        check.count("setup.count", setup.count)?;
        check.batch("setup.batch", setup.batch)?;
        check.cycles("setup.latency_cycles", setup.latency_cycles)?;
        check.cycles("setup.cycles_per_lembo", setup.cycles_per_lembo)?;

        let minmax = &self.minmax;
        check.count("minmax.count", minmax.count)?;
        check.cycles("minmax.latency_cycles", minmax.latency_cycles)?;
        check.cycles("minmax.cycles_per_lembo", minmax.cycles_per_lembo)?;
        check.at_most_cycles("minmax.cull_cycles_per_lembo", minmax.cull_cycles_per_lembo)?;

        let im = &self.interval_manager;
        check.count("interval_manager.count", im.count)?;
        check.cycles("interval_manager.latency_cycles", im.latency_cycles)?;
        check.cycles(
            "interval_manager.cycles_per_scanline",
            im.cycles_per_scanline,
        )?;
        check.cycles(
            "interval_manager.cycles_per_interval",
            im.cycles_per_interval,
        )?;

        let seg = &self.segmenter;
        check.count("segmenter.count", seg.count)?;
        check.cycles("segmenter.latency_cycles", seg.latency_cycles)?;
        check.cycles("segmenter.cycles_per_segment", seg.cycles_per_segment)?;

        let sub = &self.subsegmenter;
        check.count("subsegmenter.count", sub.count)?;
        check.cycles("subsegmenter.latency_cycles", sub.latency_cycles)?;
        check.cycles(
            "subsegmenter.cycles_per_subsegment",
            sub.cycles_per_subsegment,
        )?;

        let ras = &self.rasterizer;
        check.count("rasterizer.count", ras.count)?;
        check.cycles("rasterizer.latency_cycles", ras.latency_cycles)?;
        check.cycles(
            "rasterizer.cycles_per_subsegment",
            ras.cycles_per_subsegment,
        )?;
        check.fragments_per_cycle("rasterizer.fragments_per_cycle", ras.fragments_per_cycle)?;

        self.validate_geometry(&check)?;

        let ts = &self.triangle_setup;
        check.count("triangle_setup.count", ts.count)?;
        check.batch("triangle_setup.batch", ts.batch)?;
        check.cycles("triangle_setup.latency_cycles", ts.latency_cycles)?;
        check.cycles("triangle_setup.cycles_per_triangle", ts.cycles_per_triangle)?;
        check.range(
            "triangle_setup.culled_per_cycle",
            ts.culled_per_cycle,
            MAX_FRAGMENTS_PER_CYCLE,
            "culled triangles per cycle",
        )?;
        check.cycles(
            "triangle_setup.cycles_per_clipped_piece",
            ts.cycles_per_clipped_piece,
        )?;

        let tr = &self.triangle_rasterizer;
        check.count("triangle_rasterizer.count", tr.count)?;
        check.cycles("triangle_rasterizer.latency_cycles", tr.latency_cycles)?;
        check.range(
            "triangle_rasterizer.pixels_per_cycle",
            tr.pixels_per_cycle,
            MAX_FRAGMENTS_PER_CYCLE,
            "pixels per cycle",
        )?;

        let rop = &self.rop;
        check.count("rop.count", rop.count)?;
        check.cycles("rop.latency_cycles", rop.latency_cycles)?;
        check.ratio(
            "rop.fragments_per_cycle",
            rop.fragments_per_cycle,
            MAX_FRAGMENTS_PER_CYCLE,
        )?;
        check.range(
            "rop.tile_px",
            rop.tile_px.into(),
            MAX_TILE_PX.into(),
            "pixels (the side of a ROP interleave tile)",
        )?;

        let b = &self.blend;
        check.cycles(
            "blend.cycles_per_fragment_rgba8",
            b.cycles_per_fragment_rgba8,
        )?;
        check.cycles("blend.cycles_per_fragment_f16", b.cycles_per_fragment_f16)?;
        check.cycles("blend.cycles_per_fragment_f32", b.cycles_per_fragment_f32)?;

        self.validate_memory(&check)?;

        for (name, link) in self.links.all() {
            check.range(
                &format!("links.{name}.fifo_depth"),
                link.fifo_depth.into(),
                MAX_FIFO_DEPTH.into(),
                "items (a FIFO must hold at least one item)",
            )?;
            check.cycles(&format!("links.{name}.latency_cycles"), link.latency_cycles)?;
        }
        Ok(())
    }

    /// [`ArchConfig::validate`]'s checks of where the triangles come from: the vertex
    /// cache, the on-chip units and the bytes the geometry fetch reads.
    fn validate_geometry(&self, check: &Check) -> Result<()> {
        check.range(
            "tessellation.vertex_cache_entries",
            self.tessellation.vertex_cache_entries.into(),
            MAX_VERTEX_CACHE.into(),
            "entries (a post-transform cache holds at least one vertex)",
        )?;
        let tess = &self.tessellator;
        check.count("tessellator.count", tess.count)?;
        check.batch("tessellator.batch", tess.batch)?;
        check.cycles("tessellator.latency_cycles", tess.latency_cycles)?;
        check.ratio(
            "tessellator.cycles_per_triangle",
            tess.cycles_per_triangle,
            MAX_CYCLES,
        )?;
        let de = &self.domain_eval;
        check.count("domain_eval.count", de.count)?;
        check.cycles("domain_eval.latency_cycles", de.latency_cycles)?;
        check.ratio(
            "domain_eval.cycles_per_vertex",
            de.cycles_per_vertex,
            MAX_CYCLES,
        )?;
        let fetch = &self.fetch;
        check.bytes("fetch.bytes_per_lembo", fetch.bytes_per_lembo)?;
        check.bytes("fetch.bytes_per_vertex", fetch.bytes_per_vertex)?;
        check.bytes(
            "fetch.index_bytes_per_triangle",
            fetch.index_bytes_per_triangle,
        )?;
        Ok(())
    }

    /// [`ArchConfig::validate`]'s checks of the frame-buffer memory port.
    fn validate_memory(&self, check: &Check) -> Result<()> {
        let fb = &self.framebuffer;
        check.bytes("framebuffer.bytes_per_cycle", fb.bytes_per_cycle)?;
        check.bytes(
            "framebuffer.bytes_per_fragment_tested",
            fb.bytes_per_fragment_tested,
        )?;
        check.bytes(
            "framebuffer.bytes_per_fragment_written",
            fb.bytes_per_fragment_written,
        )?;
        check.ratio(
            "framebuffer.access_cycles",
            fb.access_cycles,
            MAX_ACCESS_CYCLES,
        )?;
        Ok(())
    }
}

/// Range checks that all share the file name and the lower bound of 1.
struct Check<'a> {
    file: &'a str,
}

impl Check<'_> {
    /// `value` must be in 1..=max; `unit` completes the reason ("must be 1 to 64 `unit`").
    fn range(&self, field: &str, value: u64, max: u64, unit: &str) -> Result<()> {
        if (1..=max).contains(&value) {
            Ok(())
        } else {
            Err(Error::invalid(
                self.file,
                field,
                value,
                format!("must be 1 to {max} {unit}"),
            ))
        }
    }

    fn count(&self, field: &str, value: u32) -> Result<()> {
        self.range(
            field,
            value.into(),
            MAX_UNIT_COUNT.into(),
            "instances (every stage needs at least one unit)",
        )
    }

    fn batch(&self, field: &str, value: u32) -> Result<()> {
        self.range(
            field,
            value.into(),
            MAX_BATCH.into(),
            "primitives per batch",
        )
    }

    fn cycles(&self, field: &str, value: u64) -> Result<()> {
        self.range(field, value, MAX_CYCLES, "cycles")
    }

    /// `value` must be in 0..=[`MAX_CYCLES`] (0: no cycles of its own).
    fn at_most_cycles(&self, field: &str, value: u64) -> Result<()> {
        if value <= MAX_CYCLES {
            return Ok(());
        }
        let reason = format!("must be 0 to {MAX_CYCLES} cycles");
        Err(Error::invalid(self.file, field, value, reason))
    }

    fn fragments_per_cycle(&self, field: &str, value: u64) -> Result<()> {
        self.range(field, value, MAX_FRAGMENTS_PER_CYCLE, "fragments per cycle")
    }

    fn bytes(&self, field: &str, value: u64) -> Result<()> {
        self.range(field, value, MAX_BYTES, "bytes")
    }

    /// `value` must be a multiple of 1/[`Ratio::DEN`] from 1/DEN to `max`.
    fn ratio(&self, field: &str, value: Ratio, max: u64) -> Result<()> {
        value
            .check(max)
            .map_err(|why| Error::invalid(self.file, field, value, why))
    }
}

#[cfg(test)]
mod tests;
