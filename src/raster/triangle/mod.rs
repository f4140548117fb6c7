//! The triangle path's setup and rasterizer (DESIGN.md §5): the fair baseline, rasterized as
//! a GPU does it.
//!
//! - **Setup** projects the three vertices, snaps x and y to 16.8 fixed point (16 integer
//!   bits, 8 fractional: 1/256 pixel), orients the triangle so that its edge functions are
//!   positive inside, and keeps per vertex the window depth, 1/w, and normal/w and
//!   position/w for perspective-correct interpolation.
//! - **Coverage** is decided in integers: pixel (i, j) samples its centre
//!   (256 i + 128, 256 j + 128) and is covered when every edge function is positive there,
//!   or zero on a *top* or *left* edge (the top-left fill rule of Direct3D and of OpenGL
//!   implementations: a top edge is horizontal with the triangle below it, a left edge has
//!   the triangle to its right). Two triangles sharing an edge therefore never both cover,
//!   nor both miss, a pixel centre on it.
//! - **Quads**: the rasterizer works in pairs of rows (even, odd), as GPUs shade 2x2 pixel
//!   quads aligned to even coordinates; it counts the quads with at least one covered pixel
//!   (the timed rasterizer's unit of work) and hands each row's covered span of columns,
//!   found in closed form from the edge functions, to the sink.
//! - **Fragments**: barycentrics are the three edge functions at the pixel centre over twice
//!   the area. Window depth is interpolated linearly in screen space, which is exact for a
//!   plane under perspective (z_ndc is affine in screen x and y); the normal and the world
//!   position are interpolated perspective-correctly (the weights divided by w, then
//!   normalised). A fragment is a function of the triangle and the pixel only, so any order
//!   of evaluation (functional model, or the timed ROPs tile by tile) gives the same bits.
//!
//! - **Near- and far-plane clipping**: a triangle crossing the near or the far plane is
//!   clipped, as GPUs do, in homogeneous clip space before the divide, to -w <= z <= w (GL).
//!   Clip coordinates are linear in the world point (c = M (p, 1)), so each clip-space plane
//!   e · c >= 0 is the world plane (Mᵀ e) · (p, 1) >= 0, and Sutherland–Hodgman on the world
//!   triangle is the clip-space clip, for any sign of w (vertices behind the eye included).
//!   A triangle wholly nearer than the near plane (or behind the eye) is culled as
//!   [`TriangleCull::BehindEye`], one wholly beyond the far plane or (clip-space outcodes)
//!   beside the viewport as [`TriangleCull::Outside`]. What the depth planes leave is then
//!   clipped to the guard band (below) and fanned the same way; its vertices' window depths
//!   are clamped to [0, 1] (removing only the rounding of a crossing on a depth plane), so
//!   its fragments' depths are in [0, 1] too (the far end up to one rounding, which the
//!   ROP's depth test discards).
//! - **Guard-band clipping**: a triangle with a vertex beyond the 16.8 range (±32767
//!   pixels) is clipped, as GPUs do, against the four planes x = ±[`CLIP_PX`] and
//!   y = ±[`CLIP_PX`]. Screen x is (c_x / c_w + 1) W / 2 for clip coordinates c, so each
//!   plane is linear in the world point, and Sutherland–Hodgman on the world triangle gives
//!   exact world-space vertices; position and normal are blended linearly along the edges
//!   (they are affine over the flat triangle), so the pieces' perspective-correct fragments
//!   are the unclipped triangle's. The polygon (at most 7 vertices, 9 after the depth
//!   planes too) is projected and snapped once and fanned into at most 5 (7) pieces that
//!   share their snapped vertices and the parent's id; the top-left rule then covers each
//!   pixel once. Edge crossings are computed from the edge's lexicographically smaller end,
//!   so two triangles sharing an edge cut it at the same points, bit for bit. A triangle
//!   inside the depth range and the guard band takes the unclipped path unchanged.
//!
//! Layout: [`setup`](mod@setup) (projection, clipping, snapping, fans, edge functions),
//! [`rasterize`](mod@rasterize) (coverage, quads, fragments), [`probe`] (measurements); this module
//! the sources of triangles, the path in the driver's terms ([`TrianglePath`]) and
//! [`render_triangles`].
//!
//! Back faces are culled by the sign of the snapped area when the view says so
//! ([`crate::camera::Culling`], DESIGN.md §5); drawn, both sides are shaded. The lembo path's counterpart of near-plane clipping is Setup's near-plane
//! split (`refine.rs`), which leaves the near plane itself to the depth test per fragment.

pub mod probe;
pub mod rasterize;
pub mod setup;

use super::counts::Counts;
use super::driver::{draw_in_order, Draw, Stages};
use crate::camera::View;
use crate::config::FetchConfig;
use crate::datapath::Real;
use crate::error::Error;
use crate::graph::UnitKind;
use crate::lembo::tessellate::{Tessellation, Triangle};
pub use probe::*;
pub use rasterize::*;
pub use setup::*;

/// Where the triangle path's triangles come from, chunk by chunk (a lembo's n², a planar
/// discoid's two). Triangle k of chunk c has id `first_id + c * per_chunk + k`.
pub trait TriangleSource: Sync {
    /// Chunks, in drawing order.
    fn chunks(&self) -> usize;
    /// Triangles per chunk.
    fn per_chunk(&self) -> u64;
    /// The triangles of chunk `c`, in order, into `out` (cleared first).
    fn chunk(&self, c: usize, out: &mut Vec<Triangle>);
    /// Bytes of the source as stored in memory and fetched: an indexed mesh's vertices and
    /// indices at `sizes`' bytes each; a source of fixed records (planar discoids) its own.
    fn bytes(&self, sizes: &FetchConfig) -> u64;
    /// The distinct vertices of one chunk's triangles, which an on-chip domain evaluator
    /// computes once each. By default three a triangle (no sharing).
    fn vertices_per_chunk(&self) -> u64 {
        3 * self.per_chunk()
    }
    /// Whether the source is an indexed mesh, whose vertex indices [`Self::vertex_ids`]
    /// gives.
    fn indexed(&self) -> bool {
        false
    }
    /// The indexed mesh's vertex indices of chunk `c`'s triangles, in order, into `out`
    /// (cleared first), for a vertex cache; `out` left empty for a source that is not
    /// [`Self::indexed`].
    fn vertex_ids(&self, c: usize, out: &mut Vec<[u64; 3]>) {
        let _ = c;
        out.clear();
    }
    /// The id of the first triangle (ids of other primitives drawn in the same frame come
    /// before it).
    fn first_id(&self) -> u32 {
        0
    }
    /// The id of triangle `k` of chunk `c`.
    fn id(&self, c: usize, k: usize) -> u32 {
        (self.first_id() as u64 + c as u64 * self.per_chunk() + k as u64) as u32
    }
}

impl TriangleSource for Tessellation<'_> {
    fn chunks(&self) -> usize {
        self.lembos()
    }

    fn per_chunk(&self) -> u64 {
        self.triangles_per_lembo()
    }

    fn chunk(&self, c: usize, out: &mut Vec<Triangle>) {
        self.lembo_triangles(c, out);
    }

    fn bytes(&self, sizes: &FetchConfig) -> u64 {
        sizes.mesh_bytes(self.len(), self.vertex_count())
    }

    fn vertices_per_chunk(&self) -> u64 {
        // The lattice points of a lembo: (n + 1)(n + 2)/2.
        let n = u64::from(self.level());
        (n + 1) * (n + 2) / 2
    }

    fn indexed(&self) -> bool {
        true
    }

    fn vertex_ids(&self, c: usize, out: &mut Vec<[u64; 3]>) {
        self.lembo_vertex_ids(c, out);
    }
}

/// The triangle path over a source's triangles, in the driver's terms
/// ([`super::driver`]): triangle setup (clipping, snapping, edge functions), the rows of a
/// set-up triangle's bounding box, and the rasterizer a pair of rows at a time into a
/// [`TriangleSink`].
pub struct TrianglePath<'a> {
    source: &'a dyn TriangleSource,
    view: &'a View,
}

impl<'a> TrianglePath<'a> {
    /// The triangles of `source` seen through `view`.
    pub fn new(source: &'a dyn TriangleSource, view: &'a View) -> Self {
        TrianglePath { source, view }
    }
}

/// The triangles of the chunk of a [`TriangleSource`] Setup fetched last.
#[derive(Default)]
pub struct Fetched {
    chunk: Option<usize>,
    triangles: Vec<Triangle>,
}

impl<R: Real> Stages<R> for TrianglePath<'_> {
    type Piece = ScreenTriangle<R>;
    type SetupScratch = Fetched;
    type Buffers = ();

    fn primitives(&self) -> usize {
        self.source.chunks() * self.source.per_chunk() as usize
    }

    fn fetched_together(&self) -> usize {
        self.source.per_chunk() as usize
    }

    /// Setup of triangle `n`, the source's chunk fetched when it is not already.
    fn set_up(
        &self,
        n: usize,
        fetched: &mut Fetched,
        pieces: &mut Vec<ScreenTriangle<R>>,
        counts: &mut Counts,
    ) {
        let per_chunk = self.source.per_chunk() as usize;
        let (c, k) = (n / per_chunk, n % per_chunk);
        if fetched.chunk != Some(c) {
            self.source.chunk(c, &mut fetched.triangles);
            fetched.chunk = Some(c);
        }
        let t = &fetched.triangles[k];
        let id = self.source.id(c, k);
        R::charge(UnitKind::TriangleSetup);
        setup_onto::<R>(id, &t.positions, &t.normals, t.color, self.view, pieces).count(counts);
    }

    /// The rows of the triangle's bounding box.
    fn rows(&self, t: &ScreenTriangle<R>, _: &mut Counts) -> Option<(u32, u32)> {
        let [_, _, j0, j1] = t.bbox;
        Some((j0, j1))
    }
}

impl<R: Real, S: TriangleSink<R>> Draw<R, S> for TrianglePath<'_> {
    #[inline]
    fn draw(
        &self,
        t: &ScreenTriangle<R>,
        lo: u32,
        hi: u32,
        sink: &mut S,
        counts: &mut Counts,
        _: &mut (),
    ) -> std::result::Result<(), (u32, Error)> {
        R::charge(UnitKind::TriangleRasterizer);
        // The hardware walk's events, once a triangle: in the band that holds its first row.
        if lo <= t.bbox[2] {
            t.tally_walk();
        }
        // The quads whose top row is in lo..hi: the first starts on the even row at or
        // above lo (a band starts on an even row, so it holds that quad's top row too).
        rasterize_rows(t, lo & !1, hi, sink, counts);
        Ok(())
    }
}

/// Runs the triangle path over every triangle of `source`, in order, into `sink`.
pub fn render_triangles<R: Real, S: TriangleSink<R>>(
    source: &dyn TriangleSource,
    view: &View,
    sink: &mut S,
    counts: &mut Counts,
) {
    draw_in_order(&TrianglePath::new(source, view), sink, counts)
        .expect("the triangle path records no error");
}

#[cfg(test)]
mod tests;
