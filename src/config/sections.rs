//! The architecture file, declared once: each section's [`section!`], then the whole
//! [`ArchConfig`] ([`architecture!`]): every field's doc, type, default and rule in one
//! place, in the order a file is echoed in. Adding a unit adds its section here and its
//! line in `ArchConfig`.

use super::declare::{architecture, section};
use super::links::LinksConfig;
use super::memory::{DramPreset, MemoryConfig, MemoryModel};
use super::ratio::Ratio;
use super::rules::{
    Chars, Checked, OneOf, Positive, Steps, Whole, BATCH, BYTES, COUNT, CYCLES, CYCLES_OR_NONE,
    MAX_ACCESS_CYCLES, MAX_CLOCK_MHZ, MAX_CYCLES, MAX_FRAGMENTS_PER_CYCLE, MAX_NAME_CHARS,
    MAX_TILE_PX, MAX_VERTEX_CACHE,
};
use crate::graph::TessSource;
use crate::memory::tiles::PixelOrder;
use serde::{Deserialize, Serialize};

/// The names of [`CullBackfaces`] (a unit test holds them equal to serde's).
pub(super) const CULL_BACKFACES: OneOf = OneOf(&["off", "on", "auto"]);
/// The names of [`Reciprocal`] (a unit test holds them equal to serde's).
pub(super) const RECIPROCALS: OneOf = OneOf(&["quad", "pixel"]);
/// The names of [`TessSource`] (a unit test holds them equal to serde's).
pub(super) const TESS_SOURCES: OneOf = OneOf(&["memory", "onchip"]);

section! {
    /// Setup: projects a lembo's six control points and six normals to screen space.
    /// Replicable: the scene's lembos are dealt to the instances in batches of `batch`, in
    /// submission order (batch b to instance b mod count), as a GPU's front end deals batches
    /// of primitives to its geometry engines. Item: one lembo.
    pub struct SetupConfig: replicated(Setup) {
        /// Number of instances. Default 1, Martinelli's Figure 5.
        pub count: u32 = 1 => COUNT,
        /// Lembos per batch dealt to one instance \[primitives\]. Default 32: each engine then
        /// reads runs of consecutive lembos (neighbours in a mesh share edges), and a batch's
        /// 192 busy cycles dwarf the dealing; only matters when `count` > 1.
        pub batch: u32 = 32 => BATCH,
        /// Cycles from accepting a lembo to its projected form being ready \[cycles\]. Default
        /// 20: a pipelined 4x4 matrix-vector multiply (about 6 stages of multiply-add), a
        /// reciprocal for the perspective divide (about 10 stages) and the viewport transform
        /// and format conversion (about 4).
        pub latency_cycles: u64 = 20 => CYCLES,
        /// Initiation interval per lembo \[cycles\]. Default 6: twelve vectors (six points and
        /// six normals) through a transform unit that takes two vectors per cycle.
        pub cycles_per_lembo: u64 = 6 => CYCLES,
    }
}

section! {
    /// MinMax: the lembo's screen-space y range, the cull test and the clip of the scanline
    /// range to the viewport. Replicable; Setup deals whole lembos (pieces) among instances
    /// round-robin. Item: one lembo.
    pub struct MinMaxConfig: replicated(MinMax) {
        /// Number of instances. Default 1, Martinelli's Figure 5: at 2 cycles a lembo against
        /// the interval manager's 3 a scanline, one MinMax keeps up.
        pub count: u32 = 1 => COUNT,
        /// Cycles from accepting a lembo to its scanline range being ready \[cycles\]. Default 8:
        /// the stationary point of each quadratic domain edge needs a divide (about 5 stages),
        /// then a compare tree over the candidates and the clip (about 3).
        pub latency_cycles: u64 = 8 => CYCLES,
        /// Initiation interval per lembo \[cycles\]. Default 2: three edge extremum candidates
        /// through a divider that starts two per cycle; the six control points' comparisons
        /// overlap with them.
        pub cycles_per_lembo: u64 = 2 => CYCLES,
        /// Whether MinMax culls lembos (and pieces) whose whole surface faces away from the eye
        /// (DESIGN.md §5, "Back-face culling"). `"off"`, `"on"`, or `"auto"` (default), which
        /// culls when every object of the scene is a closed, consistently oriented mesh, as a
        /// GPU culls what the application marks cullable. A scene of discoids refuses `"on"`.
        pub cull_backfaces: CullBackfaces = CullBackfaces::Auto => CULL_BACKFACES,
        /// Further busy cycles per lembo (or piece) for the back-face test when the run culls
        /// \[cycles\], culled or not; 0 folds the test into `cycles_per_lembo`. Default 2: the
        /// test's 15 facing coefficients take 36 three-term dot products and 9 cross products
        /// (about 170 multiplies and 130 adds, `raster::facing`), which MinMax's datapath, sized
        /// for its divides and compares, issues over two more cycles.
        pub cull_cycles_per_lembo: u64 = 2 => CYCLES_OR_NONE,
    }
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

section! {
    /// IntervalManager: for each scanline y_j of a lembo, the roots of the three domain edges
    /// with Y = y_j, paired into intervals of the parameter domain. Replicable; MinMax deals
    /// whole lembos (pieces, with all their scanlines) among instances round-robin, so an
    /// instance walks a lembo's scanlines in order. Items: one scanline, and one interval
    /// emitted.
    pub struct IntervalManagerConfig: replicated(IntervalManager) {
        /// Number of instances. Default 1, Figure 5's single interval manager (on scenes of
        /// small lembos it is the bottleneck whatever k is: raise it to see what a replicated
        /// front end buys).
        pub count: u32 = 1 => COUNT,
        /// Cycles from issuing a scanline to its intervals being ready \[cycles\]. Default 12: a
        /// pipelined quadratic solver, a square root (about 8 stages) and a divide overlapped
        /// with it, then the sort and pairing of the roots (about 4).
        pub latency_cycles: u64 = 12 => CYCLES,
        /// Initiation interval per scanline \[cycles\]. Default 3: a pipelined quadratic solver
        /// delivers one root pair per cycle after a fixed latency; three domain edges => 3
        /// cycles per scanline.
        pub cycles_per_scanline: u64 = 3 => CYCLES,
        /// Extra cycles per interval emitted \[cycles\]. Default 1: an interval is one output word
        /// and the output port writes one word per cycle.
        pub cycles_per_interval: u64 = 1 => CYCLES,
    }
}

section! {
    /// Segmenter: walks the curve Y(u,v) = y_j across an interval in steps whose midpoint
    /// error is exactly k. Replicated; intervals are dispatched among instances. Item: one
    /// segment emitted.
    pub struct SegmenterConfig: replicated(Segmenter) {
        /// Number of instances. Default 2: the segmenter iterates (one step per segment) where
        /// the interval manager does fixed work per scanline, so it is the first stage that
        /// needs replication to keep up.
        pub count: u32 = 2 => COUNT,
        /// Cycles from accepting an interval to its first segment being ready \[cycles\]. Default
        /// 16: the step solves a quadratic for the next endpoint (square root and divide, about
        /// 12 stages) and evaluates the midpoint error (about 4).
        pub latency_cycles: u64 = 16 => CYCLES,
        /// Initiation interval per segment \[cycles\]. Default 2: each step issues an endpoint
        /// solve and a midpoint error evaluation on one shared pipelined evaluator, two issue
        /// slots per segment.
        pub cycles_per_segment: u64 = 2 => CYCLES,
    }
}

section! {
    /// Subsegmenter: splits a segment so that x(t) is linear within k on each piece.
    /// Replicated. Item: one subsegment emitted.
    pub struct SubsegmenterConfig: replicated(Subsegmenter) {
        /// Number of instances. Default 2: one per segmenter, so that each segmenter's output
        /// has a subsegmenter to go to without waiting.
        pub count: u32 = 2 => COUNT,
        /// Cycles from accepting a segment to its first subsegment being ready \[cycles\].
        /// Default 8: a quadratic evaluation of x(t) (about 5 stages of multiply-add) and the
        /// comparison of its deviation with k (about 3).
        pub latency_cycles: u64 = 8 => CYCLES,
        /// Initiation interval per subsegment \[cycles\]. Default 1: the split points come from a
        /// fully pipelined evaluator, one per cycle.
        pub cycles_per_subsegment: u64 = 1 => CYCLES,
    }
}

section! {
    /// FragmentRasterizer: walks a subsegment's pixel centres, computing u, v, z and the normal
    /// by increments. Replicated. Items: one subsegment, and one fragment span (the fragments
    /// of one subsegment inside one ROP tile).
    pub struct RasterizerConfig: replicated(FragmentRasterizer) {
        /// Number of instances. Default 4: one per ROP, so that fragment generation and
        /// fragment testing have the same peak rate.
        pub count: u32 = 4 => COUNT,
        /// Cycles from accepting a subsegment to its first span being ready \[cycles\]. Default
        /// 4: the first fragment's values from the increment setup, through an adder pipeline.
        pub latency_cycles: u64 = 4 => CYCLES,
        /// Initiation interval per subsegment for the increment setup \[cycles\]. Default 1: the
        /// start values and forward differences of u, v, z and the normal come from one
        /// pipelined evaluation per subsegment.
        pub cycles_per_subsegment: u64 = 1 => CYCLES,
        /// Fragments produced per cycle; a span of n fragments costs ceil(n / this) cycles.
        /// Default 1: each fragment is one add per interpolated quantity, one fragment per
        /// cycle as in a classic scan converter.
        pub fragments_per_cycle: u64 = 1 => Whole {
            min: 1,
            max: MAX_FRAGMENTS_PER_CYCLE,
            unit: "fragments per cycle",
        },
    }
}

section! {
    /// Where the triangle path's triangles come from (DESIGN.md §5, "Tessellation paid for").
    pub struct TessellationConfig {
        /// Where the triangle path's triangles come from. `memory`: a mesh tessellated before
        /// the frame, read by the geometry fetch as indices and, on a vertex cache miss,
        /// vertices; `onchip`: the lembos are read and tessellated by Tessellator and
        /// DomainEval units. Default `memory`.
        pub source: TessSource = TessSource::Memory => TESS_SOURCES,
        /// Entries of each triangle setup engine's post-transform vertex cache, with the
        /// `memory` source \[vertices\]. FIFO replacement, one per engine, so a batch dealt to
        /// another engine starts cold. Default 32: post-transform caches of GPUs of the
        /// papers' era held tens of entries, and 32 hold the two lattice rows a tessellated
        /// lembo's triangles straddle up to n = 15.
        pub vertex_cache_entries: u32 = 32 => Whole {
                min: 1,
                max: MAX_VERTEX_CACHE as u64,
                unit: "entries (a post-transform cache holds at least one vertex)",
            },
    }
}

section! {
    /// GeometryFetch (DESIGN.md §3, "Geometry fetch"): the bytes of a primitive as it is
    /// stored in memory, read through the memory port (`framebuffer`) at the start of a frame
    /// and priced as DRAM (`cost.geometry_bytes`). Discoids keep their own fixed records.
    pub struct FetchConfig: single(GeometryFetch) {
        /// Bytes of one lembo as stored and read for Setup or the Tessellators \[bytes\].
        /// Default 144 (`lembo::LEMBO_BYTES`): six points and six normals in f32.
        pub bytes_per_lembo: u64 = 144 => BYTES,
        /// Bytes of one vertex of a mesh tessellated in memory, read on each post-transform
        /// vertex cache miss \[bytes\]. Default 24 (`lembo::tessellate::VERTEX_BYTES`):
        /// a position and a normal in f32.
        pub bytes_per_vertex: u64 = 24 => BYTES,
        /// Bytes of one triangle's indices in a mesh tessellated in memory \[bytes\]. Default 12
        /// (`lembo::tessellate::INDEX_BYTES_PER_TRIANGLE`): three 32-bit indices.
        pub index_bytes_per_triangle: u64 = 12 => BYTES,
    }
}

impl FetchConfig {
    /// Bytes of an indexed mesh of `triangles` triangles and `vertices` vertices
    /// \[bytes\].
    pub fn mesh_bytes(&self, triangles: u64, vertices: u64) -> u64 {
        triangles * self.index_bytes_per_triangle + vertices * self.bytes_per_vertex
    }
}

section! {
    /// Tessellator (the `onchip` source): makes a lembo's n² domain triangles (their
    /// connectivity and their (n + 1)(n + 2)/2 domain points), as the fixed-function
    /// tessellator of a DX11 GPU does. Replicable: the geometry fetch deals batches of
    /// lembos to the instances in submission order. Item: one lembo.
    pub struct TessellatorConfig: replicated(Tessellator) {
        /// Number of instances. Default 1.
        pub count: u32 = 1 => COUNT,
        /// Lembos per batch dealt to one instance \[primitives\]. Default 4: a batch of four
        /// 144-byte lembos is nine cycles of the memory port.
        pub batch: u32 = 4 => BATCH,
        /// Cycles from accepting a lembo to its first domain points being ready \[cycles\].
        /// Default 8: the lattice step (a reciprocal of n) and the first row's indices.
        pub latency_cycles: u64 = 8 => CYCLES,
        /// Initiation interval per triangle generated \[cycles\]. A multiple of 1/64
        /// ([`Ratio`]: 0.5 is two triangles a cycle); a lembo of t triangles costs
        /// ceil(t * this) cycles, at least one. Default 1: a DX11 tessellator emits about one
        /// triangle (with its new domain point) per clock.
        pub cycles_per_triangle: Ratio = Ratio::whole(1) => Steps { max: MAX_CYCLES },
    }
}

section! {
    /// DomainEval (the `onchip` source): evaluates each domain point of a lembo's tessellation,
    /// position and unit normal, from the lembo's quadratic functions (the DX11 domain
    /// shader's work), and passes the lembo's triangles in batches of `triangle_setup.batch`
    /// to the triangle setup engines in turn. Replicable: the tessellators deal lembos to the
    /// instances round-robin. Item: one vertex evaluated.
    pub struct DomainEvalConfig: replicated(DomainEval) {
        /// Number of instances. Default 1.
        pub count: u32 = 1 => COUNT,
        /// Cycles from accepting a lembo to its first vertices being ready \[cycles\]. Default
        /// 16: the six quadratic basis functions (about 4 stages), two weighted sums of six
        /// vectors (about 6) and the normal's normalisation (a reciprocal square root, about 6).
        pub latency_cycles: u64 = 16 => CYCLES,
        /// Initiation interval per vertex evaluated \[cycles\]. A multiple of 1/64 ([`Ratio`]:
        /// 0.5 is two vertices a cycle). Default 1: one fully pipelined evaluator. Each lembo's
        /// (n + 1)(n + 2)/2 points are evaluated: patches are independent, so a point on an edge
        /// two lembos share is evaluated by both, as a domain shader does.
        pub cycles_per_vertex: Ratio = Ratio::whole(1) => Steps { max: MAX_CYCLES },
    }
}

section! {
    /// TriangleSetup (the triangle path, DESIGN.md §5): projects a triangle's three vertices,
    /// snaps them to 16.8 fixed point and sets up the integer edge functions and the
    /// perspective-correct attribute planes. Replicable: triangles are dealt to the instances
    /// in batches of `batch`, in submission order (batch b to instance b mod count), as GPUs
    /// since 2010 deal batches of primitives to several geometry and setup engines, each about
    /// one primitive per clock. Item: one triangle.
    pub struct TriangleSetupConfig: replicated(TriangleSetup) {
        /// Number of instances. Default 1.
        pub count: u32 = 1 => COUNT,
        /// Triangles per batch dealt to one instance \[primitives\]. Default 32 (a batch of
        /// vertex work of a GPU's front end); only matters when `count` > 1.
        pub batch: u32 = 32 => BATCH,
        /// Cycles from accepting a triangle to its setup being ready \[cycles\]. Default 20, as
        /// the lembo Setup: a transform and perspective divide per vertex (about 16 stages) and
        /// the edge-function and plane setup (about 4).
        pub latency_cycles: u64 = 20 => CYCLES,
        /// Initiation interval per triangle \[cycles\]. Default 1: DESIGN.md §5's "setup 1 triangle
        /// per cycle", the rate of GPUs of the papers' era and since.
        pub cycles_per_triangle: u64 = 1 => CYCLES,
        /// Culled triangles disposed of per `cycles_per_triangle` \[triangles\]. A triangle
        /// culled whole (back-facing, outside the view, or covering no pixel centre), not
        /// clipped, leaves the engine after its cull test without edge-function or plane setup,
        /// so an engine can cull faster than it sets up. Default 1 (culled triangles cost
        /// what drawn ones do, the papers' era). Later GPUs cull faster than they draw: AMD's
        /// RDNA whitepaper (2019) gives its primitive units two culled primitives a clock
        /// against one drawn (as recalled, not checked here), and Mesa's piglit culling test
        /// (M. Olšák, 2019) measured a Radeon drawing 2.8 G triangles/s and culling 4.8 G/s of
        /// triangles outside the view.
        pub culled_per_cycle: u64 = 1 => Whole {
                min: 1,
                max: MAX_FRAGMENTS_PER_CYCLE,
                unit: "culled triangles per cycle",
            },
        /// Further busy cycles per piece of a clipped triangle \[cycles\]. A triangle crossing
        /// the near or far plane, or with a vertex beyond the 16.8 range (±32767 pixels), is
        /// clipped against the two depth planes and the four guard-band planes (those it
        /// crosses) and its polygon fanned into 1 to 7 triangles, each set up (and culled or
        /// emitted) as a triangle of its own, so it costs `cycles_per_triangle` plus this per
        /// fan triangle. Default 1: each piece takes the snap and edge-function stage
        /// for one cycle, as a triangle does; meanwhile the polygon's new vertices (at most
        /// fan + 2; a plane distance, a divide and a blend each, then the projection) fit in
        /// the three vertex slots per cycle of the transform stage, which the pieces leave idle.
        pub cycles_per_clipped_piece: u64 = 1 => CYCLES,
        /// Whether setup culls triangles facing away from the eye, by their snapped signed area
        /// at `culled_per_cycle` (DESIGN.md §5, "Back-face culling"). `"off"`, `"on"`, or
        /// `"auto"` (default), as [`MinMaxConfig::cull_backfaces`].
        pub cull_backfaces: CullBackfaces = CullBackfaces::Auto => CULL_BACKFACES,
    }
}

section! {
    /// TriangleRasterizer (the triangle path, DESIGN.md §5): tests 2x2 pixel quads against the
    /// integer edge functions with the top-left fill rule. Replicated; triangles are dispatched
    /// round-robin. Items: one triangle, and one quad-row piece (a triangle's quads in one
    /// pair of pixel rows inside one ROP tile).
    pub struct TriangleRasterizerConfig: replicated(TriangleRasterizer) {
        /// Number of instances. Default 1: one rasterizer at 8 pixels per cycle has twice the
        /// peak rate of the default four ROPs.
        pub count: u32 = 1 => COUNT,
        /// Cycles from accepting a triangle to its first quads being ready \[cycles\]. Default 4,
        /// as the lembo FragmentRasterizer.
        pub latency_cycles: u64 = 4 => CYCLES,
        /// Pixels tested per cycle; a piece of q quads costs ceil(4 q / this) cycles, at least
        /// one, and a triangle that covers no pixel costs one cycle. Default 8: DESIGN.md §5, two
        /// quads per cycle.
        pub pixels_per_cycle: u64 = 8 => Whole {
                min: 1,
                max: MAX_FRAGMENTS_PER_CYCLE,
                unit: "pixels per cycle",
            },
        /// Where the reciprocal of the interpolated 1/w is taken for perspective-correct
        /// attributes. `"quad"` (default; one reciprocal per covered quad, refined per covered
        /// pixel by a Newton step) or `"pixel"` (one per covered pixel). A pricing choice only
        /// (`cost::built`, DESIGN.md §12): the model divides exactly, whatever this says.
        pub reciprocal: Reciprocal = Reciprocal::Quad => RECIPROCALS,
    }
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

section! {
    /// ROP: depth test and per-fragment Phong shading for the pixels of its screen tiles.
    /// Replicated; screen-interleaved. Item: one fragment span.
    pub struct RopConfig: replicated(Rop) {
        /// Number of instances. Default 4: the ROP count of a mid-range part of the papers'
        /// era, and enough that the (tx + ty) interleave spreads a lembo over several ROPs.
        pub count: u32 = 4 => COUNT,
        /// Cycles from accepting a span to its write burst being ready \[cycles\]. Default 4: the
        /// depth compare and the shading arithmetic of one fragment, pipelined.
        pub latency_cycles: u64 = 4 => CYCLES,
        /// Fragments tested and shaded per cycle; a span of n fragments costs ceil(n / this)
        /// cycles. A multiple of 1/64 ([`Ratio`]: 0.5 is a fragment every two cycles).
        /// Default 1: one depth test and one Phong evaluation per cycle per ROP.
        pub fragments_per_cycle: Ratio = Ratio::whole(1) => Steps { max: MAX_FRAGMENTS_PER_CYCLE },
        /// Side of a screen interleave tile \[pixels\]: tile (tx, ty) of tile_px x tile_px pixels
        /// goes to ROP (tx + ty) % count. Default 8: 64 pixels, the size of a frame-buffer
        /// memory burst tile; small enough that one lembo covers several tiles and thus several
        /// ROPs, large enough that a span is not cut at every few pixels.
        pub tile_px: u32 = 8 => Whole {
                min: 1,
                max: MAX_TILE_PX as u64,
                unit: "pixels (the side of a ROP interleave tile)",
            },
    }
}

section! {
    /// The discoid blend units (Piranda et al. 2006, DESIGN.md §4): one per ROP, instantiated only for
    /// scenes with discoids. A fragment kept by the accumulation pass costs the ROP
    /// `cycles_per_fragment_<mode>` more than its depth test and moves
    /// `BlendMode::bytes_per_fragment` through the frame-buffer port (8, 16 or 32 bytes).
    pub struct BlendConfig {
        /// Blend cycles per fragment in rgba8 (Table 1: two 8-bit averages and two nibble
        /// adds) \[cycles\]. Default 1: 8-bit blenders run at full rate.
        pub cycles_per_fragment_rgba8: u64 = 1 => CYCLES,
        /// Blend cycles per fragment in f16 \[cycles\]. Default 1: the GeForce 6 series blends
        /// FP16 targets at full rate.
        pub cycles_per_fragment_f16: u64 = 1 => CYCLES,
        /// Blend cycles per fragment in f32 \[cycles\]. Default 2: FP32 blending at half rate,
        /// as GPUs that support it run it.
        pub cycles_per_fragment_f32: u64 = 2 => CYCLES,
    }
}

section! {
    /// The frame-buffer port: one memory port shared by every ROP. One instance. Item: one
    /// write burst.
    pub struct FrameBufferConfig: single(FrameBuffer) {
        /// Bytes the port transfers per cycle \[bytes/cycle\]; with the default
        /// `access_cycles` of 1 a burst of b bytes costs ceil(b / this) cycles, at least one.
        /// Default 64: the GeForce 6800 GT the discoid paper measured on moves about 32 GB/s,
        /// 64 bytes per cycle at the default 500 MHz. Four ROPs at full rate ask for up to 48
        /// bytes per cycle, so the port limits only wider units.
        pub bytes_per_cycle: u64 = 64 => BYTES,
        /// Bytes moved per fragment tested \[bytes\]. Default 4: one 32-bit depth read (24-bit
        /// depth and 8-bit stencil, the usual packed format).
        pub bytes_per_fragment_tested: u64 = 4 => BYTES,
        /// Bytes moved per fragment that passes the depth test \[bytes\]. Default 8: a 32-bit
        /// RGBA8 colour write and a 32-bit depth write.
        pub bytes_per_fragment_written: u64 = 8 => BYTES,
        /// The port's per-access cost: the length of its transfer slot \[cycles\]. A multiple
        /// of 1/64 ([`Ratio`]). The port moves data in slots of this many cycles, each carrying
        /// `bytes_per_cycle` * this bytes; an access of b bytes occupies whole slots,
        /// this * ceil(b / (bytes_per_cycle * this)) cycles, at least one slot (DESIGN.md §3,
        /// "One memory port"). Fractions of a cycle are kept exactly and whole cycles charged
        /// as the port's time crosses them. Default 1: every access occupies at least a cycle,
        /// and a longer one ceil(b / bytes_per_cycle) cycles. It moves no bytes, so it
        /// changes no energy.
        pub access_cycles: Ratio = Ratio::whole(1) => Steps { max: MAX_ACCESS_CYCLES },
    }
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

/// Enums and switches whose names serde checks as the file is parsed.
macro_rules! choices {
    ($($ty:ty),*) => {$(
        impl Checked for $ty {
            type Rule = OneOf;
            fn refusal(&self, _: &OneOf) -> Option<(String, String)> {
                None
            }
        }
    )*};
}
choices!(
    CullBackfaces,
    Reciprocal,
    TessSource,
    bool,
    MemoryModel,
    DramPreset,
    PixelOrder
);

architecture! {
    /// The whole architecture: units in dataflow order, then the links between them.
    pub struct ArchConfig {
        /// Name of the configuration, shown in reports. Default `"baseline"`; a file that
        /// leaves it out is named by its file name ([`ArchConfig::load`]).
        pub name: String = "baseline".to_string() => Chars {
            min: 1,
            max: MAX_NAME_CHARS,
        },
        /// Clock of every unit \[MHz\], used only to turn cycles into frames per second. Default
        /// 500: the class of a mid-2000s GPU core (the GeForce 6800 GT of the papers' figures
        /// runs at about 400 MHz), rounded so that one cycle is 2 ns.
        pub clock_mhz: f64 = 500.0 => Positive {
            max: MAX_CLOCK_MHZ,
            what: "clock",
            unit: "MHz",
        },
        sections:
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
        /// The memory system behind the ROPs (its model, caches, tile table and DRAM);
        /// defaults in [`MemoryConfig`].
        pub memory: MemoryConfig,
        /// The FIFOs between stages, one setting per boundary; defaults in [`LinksConfig`].
        pub links: LinksConfig,
    }
}
