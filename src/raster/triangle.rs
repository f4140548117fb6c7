//! The triangle path's setup and rasterizer (DESIGN §5): the fair baseline, rasterized as
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
//! - **Quads**: the rasterizer walks the bounding box in 2x2 pixel quads aligned to even
//!   coordinates, as GPUs shade; a quad with at least one covered pixel is emitted with its
//!   4-bit mask.
//! - **Fragments**: barycentrics are the three edge functions at the pixel centre over twice
//!   the area. Window depth is interpolated linearly in screen space, which is exact for a
//!   plane under perspective (z_ndc is affine in screen x and y); the normal and the world
//!   position are interpolated perspective-correctly (the weights divided by w, then
//!   normalised). A fragment is a function of the triangle and the pixel only, so any order
//!   of evaluation (functional model, or the timed ROPs tile by tile) gives the same bits.
//!
//! Not modelled: near-plane clipping (a triangle with a vertex at or behind the eye is
//! dropped and counted, as a lembo is), guard-band clipping (a vertex beyond the 16.8 range,
//! ±32768 pixels, drops the triangle and is counted), back-face culling (the lembo path has
//! none either; both paths shade two-sided).

use super::Counts;
use crate::camera::{View, Viewport};
use crate::datapath::Real;
use crate::lembo::tessellate::{Tessellation, Triangle};
use glam::DVec3;

/// Fractional bits of the snapped vertex coordinates (16.8 fixed point).
pub const SUBPIXEL_BITS: u32 = 8;
/// Sub-pixel steps per pixel.
pub const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// The largest |x| or |y| a snapped vertex may have [pixels]: 16 integer bits, signed.
pub const GUARD_BAND_PX: f64 = 32767.0;

/// One edge function `E(X, Y) = a X + b Y + c` in sub-pixel units, positive inside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeFunction {
    pub a: i64,
    pub b: i64,
    pub c: i64,
    /// The smallest value that counts as inside: 0 on a top or left edge, 1 otherwise.
    pub min: i64,
}

impl EdgeFunction {
    /// The edge from `(x0, y0)` to `(x1, y1)` of a triangle oriented so that the third
    /// vertex gives a positive value.
    fn new(x0: i64, y0: i64, x1: i64, y1: i64) -> Self {
        let (dx, dy) = (x1 - x0, y1 - y0);
        // E = dx (Y - y0) - dy (X - x0). With E > 0 inside and y pointing down, an edge
        // with dy < 0 has the triangle to its right (a left edge); dy = 0 and dx > 0 has
        // it below (a top edge).
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        EdgeFunction {
            a: -dy,
            b: dx,
            c: dy * x0 - dx * y0,
            min: if top_left { 0 } else { 1 },
        }
    }

    /// The value at sub-pixel position (x, y).
    #[inline(always)]
    pub fn at(&self, x: i64, y: i64) -> i64 {
        self.a * x + self.b * y + self.c
    }
}

/// The sub-pixel position of pixel (i, j)'s centre.
#[inline(always)]
pub fn pixel_centre(i: u32, j: u32) -> (i64, i64) {
    (
        i as i64 * SUBPIXEL + SUBPIXEL / 2,
        j as i64 * SUBPIXEL + SUBPIXEL / 2,
    )
}

/// Snaps a screen coordinate [pixels] to 16.8 fixed point, rounding to nearest.
#[inline]
pub fn snap<R: Real>(x: R) -> i64 {
    (x * R::of(SUBPIXEL as f64)).round().to_i64().unwrap_or(0)
}

/// A triangle ready for the rasterizer, in the datapath precision.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenTriangle<R> {
    /// Global id (tessellation order), also the depth-test tie breaker.
    pub id: u32,
    /// Snapped vertex positions [1/256 pixel], counter-clockwise on screen as seen with y
    /// down (edge functions positive inside).
    pub x: [i64; 3],
    pub y: [i64; 3],
    /// Edge function `k` is the edge opposite vertex `k`.
    pub edges: [EdgeFunction; 3],
    /// Twice the area [1/256 pixel, squared], > 0.
    pub area2: i64,
    /// Pixels the triangle may cover, clipped to the viewport: columns i0..i1, rows j0..j1
    /// (half-open, non-empty).
    pub bbox: [u32; 4],
    /// Window depth per vertex.
    pub z: [R; 3],
    /// 1/w per vertex (1 for orthographic views).
    pub inv_w: [R; 3],
    /// World-space unit normal / w per vertex.
    pub normal_w: [[R; 3]; 3],
    /// World-space position / w per vertex.
    pub position_w: [[R; 3]; 3],
    /// Material colour, linear RGB.
    pub color: [R; 3],
}

/// Why a triangle produced no [`ScreenTriangle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriangleCull {
    /// A vertex is at or behind the eye plane (near clipping is not modelled).
    BehindEye,
    /// A vertex is beyond the 16.8 guard band (guard-band clipping is not modelled).
    GuardBand,
    /// The bounding box misses the viewport, or the triangle lies outside the depth range.
    Outside,
    /// Zero area after snapping, or no pixel centre inside the bounding box.
    Degenerate,
}

/// One fragment of a triangle: what the ROP needs to test and shade it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleFragment<R> {
    /// Window depth [0, 1].
    pub z: R,
    /// World-space normal, perspective-correct, not normalised.
    pub normal: [R; 3],
    /// World-space position, perspective-correct.
    pub position: [R; 3],
}

/// Sets up triangle `id` (world-space `positions`, unit `normals`, `color`) for `view`.
pub fn setup<R: Real>(
    id: u32,
    positions: &[DVec3; 3],
    normals: &[DVec3; 3],
    color: [f64; 3],
    view: &View,
) -> Result<ScreenTriangle<R>, TriangleCull> {
    let s = positions.map(|p| view.project(p));
    if s.iter()
        .any(|s| s.w <= 0.0 || !s.x.is_finite() || !s.y.is_finite())
    {
        return Err(TriangleCull::BehindEye);
    }
    if s.iter()
        .any(|s| !(s.x.abs() <= GUARD_BAND_PX && s.y.abs() <= GUARD_BAND_PX))
    {
        return Err(TriangleCull::GuardBand);
    }
    if s.iter().all(|s| s.depth < 0.0) || s.iter().all(|s| s.depth > 1.0) {
        return Err(TriangleCull::Outside);
    }
    let x = s.map(|s| snap(R::of(s.x)));
    let y = s.map(|s| snap(R::of(s.y)));
    let inv_w = s.map(|s| if view.orthographic { 1.0 } else { 1.0 / s.w });
    let r3 = |v: DVec3, f: f64| [R::of(v.x * f), R::of(v.y * f), R::of(v.z * f)];
    let vertices = [0, 1, 2].map(|k| Vertex {
        z: R::of(s[k].depth),
        inv_w: R::of(inv_w[k]),
        normal_w: r3(normals[k], inv_w[k]),
        position_w: r3(positions[k], inv_w[k]),
    });
    ScreenTriangle::assemble(id, x, y, vertices, color.map(R::of), view.viewport)
}

/// What a vertex carries into the rasterizer besides its snapped position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex<R> {
    pub z: R,
    pub inv_w: R,
    pub normal_w: [R; 3],
    pub position_w: [R; 3],
}

impl<R: Real> ScreenTriangle<R> {
    /// Orients, bounds and sets up the edge functions of a triangle with snapped vertices
    /// (x, y) [1/256 pixel].
    pub fn assemble(
        id: u32,
        mut x: [i64; 3],
        mut y: [i64; 3],
        mut v: [Vertex<R>; 3],
        color: [R; 3],
        viewport: Viewport,
    ) -> Result<Self, TriangleCull> {
        let mut area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        if area2 == 0 {
            return Err(TriangleCull::Degenerate);
        }
        if area2 < 0 {
            // Clockwise as seen with y down: swap two vertices so the edge functions are
            // positive inside (no back-face culling).
            x.swap(1, 2);
            y.swap(1, 2);
            v.swap(1, 2);
            area2 = -area2;
        }
        let (vw, vh) = (viewport.width as i64, viewport.height as i64);
        // Pixel i's centre 256 i + 128 is inside [lo, hi] for first(lo) <= i <= last(hi).
        let first = |lo: i64| (lo - SUBPIXEL / 2 + SUBPIXEL - 1).div_euclid(SUBPIXEL);
        let last = |hi: i64| (hi - SUBPIXEL / 2).div_euclid(SUBPIXEL);
        let (xmin, xmax) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        let (ymin, ymax) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
        let (i0, i1) = (first(xmin).max(0), (last(xmax) + 1).min(vw));
        let (j0, j1) = (first(ymin).max(0), (last(ymax) + 1).min(vh));
        if i0 >= i1 || j0 >= j1 {
            let outside =
                last(xmax) < 0 || first(xmin) >= vw || last(ymax) < 0 || first(ymin) >= vh;
            return Err(if outside {
                TriangleCull::Outside
            } else {
                TriangleCull::Degenerate
            });
        }
        Ok(ScreenTriangle {
            id,
            x,
            y,
            edges: [
                EdgeFunction::new(x[1], y[1], x[2], y[2]),
                EdgeFunction::new(x[2], y[2], x[0], y[0]),
                EdgeFunction::new(x[0], y[0], x[1], y[1]),
            ],
            area2,
            bbox: [i0 as u32, i1 as u32, j0 as u32, j1 as u32],
            z: v.map(|v| v.z),
            inv_w: v.map(|v| v.inv_w),
            normal_w: v.map(|v| v.normal_w),
            position_w: v.map(|v| v.position_w),
            color,
        })
    }
}

impl<R: Real> ScreenTriangle<R> {
    /// The three edge functions at pixel (i, j)'s centre.
    #[inline(always)]
    fn edge_values(&self, i: u32, j: u32) -> [i64; 3] {
        let (px, py) = pixel_centre(i, j);
        self.edges.map(|e| e.at(px, py))
    }

    /// Whether pixel (i, j)'s centre is inside, by the top-left rule.
    #[inline(always)]
    pub fn covers(&self, i: u32, j: u32) -> bool {
        let e = self.edge_values(i, j);
        (0..3).all(|k| e[k] >= self.edges[k].min)
    }

    /// The fragment at pixel (i, j) (meaningful where [`Self::covers`]).
    #[inline]
    pub fn fragment(&self, i: u32, j: u32) -> TriangleFragment<R> {
        let e = self.edge_values(i, j);
        let area = R::of(self.area2 as f64);
        let l = e.map(|v| R::of(v as f64) / area);
        let z = l[0] * self.z[0] + l[1] * self.z[1] + l[2] * self.z[2];
        // Perspective-correct: sum(l_k a_k / w_k) / sum(l_k / w_k), with a_k / w_k kept
        // per vertex.
        let sum = l[0] * self.inv_w[0] + l[1] * self.inv_w[1] + l[2] * self.inv_w[2];
        let lerp = |v: &[[R; 3]; 3]| {
            [0, 1, 2].map(|c| (l[0] * v[0][c] + l[1] * v[1][c] + l[2] * v[2][c]) / sum)
        };
        TriangleFragment {
            z,
            normal: lerp(&self.normal_w),
            position: lerp(&self.position_w),
        }
    }

    /// The covered pixels of row `j` as a half-open column range (empty when start >= end,
    /// and for rows outside the bounding box). Coverage of a row is contiguous: each edge
    /// function is linear along it, so each admits a half-line of columns.
    #[inline]
    pub fn row_span(&self, j: u32) -> (u32, u32) {
        let [i0, i1, j0, j1] = self.bbox;
        if j < j0 || j >= j1 {
            return (i0, i0);
        }
        let mut a = i0;
        while a < i1 && !self.covers(a, j) {
            a += 1;
        }
        let mut b = a;
        while b < i1 && self.covers(b, j) {
            b += 1;
        }
        (a, b)
    }

    /// Calls `quad(qi, qj, rows, mask)` for every 2x2 quad (top-left pixel (qi, qj), both
    /// even) with at least one covered pixel, row by row, left to right. `rows` are the
    /// covered spans of rows qj and qj + 1 ([`Self::row_span`]); mask bit 0 is (qi, qj),
    /// bit 1 (qi + 1, qj), bit 2 (qi, qj + 1), bit 3 (qi + 1, qj + 1).
    pub fn quads(&self, mut quad: impl FnMut(u32, u32, &[(u32, u32); 2], u8)) {
        let [_, _, j0, j1] = self.bbox;
        let mut qj = j0 & !1;
        while qj < j1 {
            let rows = [self.row_span(qj), self.row_span(qj + 1)];
            let live = rows.iter().filter(|r| r.0 < r.1);
            let lo = live.clone().map(|r| r.0).min();
            let hi = live.map(|r| r.1).max();
            if let (Some(lo), Some(hi)) = (lo, hi) {
                let mut qi = lo & !1;
                while qi < hi {
                    let mut mask = 0u8;
                    for bit in 0..4u32 {
                        let (a, b) = rows[(bit >> 1) as usize];
                        let i = qi + (bit & 1);
                        if a <= i && i < b {
                            mask |= 1 << bit;
                        }
                    }
                    if mask != 0 {
                        quad(qi, qj, &rows, mask);
                    }
                    qi += 2;
                }
            }
            qj += 2;
        }
    }
}

/// Quads (2x2, aligned to even columns) touched by the union of two row spans.
pub fn quads_in(rows: &[(u32, u32); 2]) -> u64 {
    let q = |(a, b): (u32, u32)| (a < b).then(|| (a / 2, (b - 1) / 2));
    match (q(rows[0]), q(rows[1])) {
        (None, None) => 0,
        (Some((a, b)), None) | (None, Some((a, b))) => (b - a + 1) as u64,
        (Some((a0, b0)), Some((a1, b1))) => {
            if a1 > b0 + 1 || a0 > b1 + 1 {
                (b0 - a0 + 1) as u64 + (b1 - a1 + 1) as u64
            } else {
                (b0.max(b1) - a0.min(a1) + 1) as u64
            }
        }
    }
}

/// Receives triangle fragments: the ROP in a render, a probe in tests and accuracy runs.
pub trait TriangleSink<R: Real> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>);
}

/// Rasterizes one set-up triangle into `sink`, quad by quad.
pub fn rasterize<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    sink: &mut S,
    counts: &mut Counts,
) {
    t.quads(|qi, qj, _, mask| {
        counts.quads += 1;
        for bit in 0..4 {
            if mask & (1 << bit) != 0 {
                let (i, j) = (qi + (bit & 1), qj + (bit >> 1));
                sink.fragment(t, i, j, &t.fragment(i, j));
                counts.fragments += 1;
            }
        }
    });
}

/// Counts a culled triangle.
pub fn count_cull(cull: TriangleCull, counts: &mut Counts) {
    match cull {
        TriangleCull::BehindEye => counts.triangles_culled_behind_eye += 1,
        TriangleCull::GuardBand => counts.triangles_culled_guard_band += 1,
        TriangleCull::Outside => counts.triangles_culled_outside += 1,
        TriangleCull::Degenerate => counts.triangles_degenerate += 1,
    }
}

/// A triangle sink that counts double hits on shared edges, then forwards each fragment.
///
/// Two triangles on opposite sides of a shared edge can both contain a pixel centre only if
/// it lies exactly on that edge, where the fill rule must give it to one of them. So a
/// double hit is a pixel whose centre lies exactly on an edge (edge function 0) of two
/// triangles with the same snapped end points, on opposite sides of it. Fragments off every
/// edge need no bookkeeping, so the probe costs little.
pub struct TriangleProbe<'a, S> {
    inner: &'a mut S,
    width: u32,
    /// Per pixel with an on-edge fragment: (triangle id, canonical edge, side) of each.
    on_edge: std::collections::HashMap<u32, Vec<(u32, [i64; 4], bool)>>,
    doubles: std::collections::HashSet<u32>,
}

impl<'a, S> TriangleProbe<'a, S> {
    pub fn new(width: u32, inner: &'a mut S) -> Self {
        TriangleProbe {
            inner,
            width,
            on_edge: Default::default(),
            doubles: Default::default(),
        }
    }

    /// Pixels claimed from both sides of a shared edge.
    pub fn double_hit_pixels(&self) -> u64 {
        self.doubles.len() as u64
    }
}

impl<R: Real, S: TriangleSink<R>> TriangleSink<R> for TriangleProbe<'_, S> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        let e = t.edge_values(i, j);
        for (k, &ek) in e.iter().enumerate() {
            if ek != 0 {
                continue;
            }
            // Edge k joins vertices k + 1 and k + 2; order its ends canonically and note on
            // which side of it the third vertex lies.
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let (pa, pb) = ((t.x[a], t.y[a]), (t.x[b], t.y[b]));
            let (p, q) = if pa <= pb { (pa, pb) } else { (pb, pa) };
            let side = (q.0 - p.0) * (t.y[k] - p.1) - (q.1 - p.1) * (t.x[k] - p.0) > 0;
            let key = [p.0, p.1, q.0, q.1];
            let pixel = j * self.width + i;
            let seen = self.on_edge.entry(pixel).or_default();
            if seen
                .iter()
                .any(|&(id, other, s)| id != t.id && other == key && s != side)
            {
                self.doubles.insert(pixel);
            }
            seen.push((t.id, key, side));
        }
        self.inner.fragment(t, i, j, f);
    }
}

/// Where the triangle path's triangles come from, chunk by chunk (a lembo's n², a planar
/// discoid's two). Triangle k of chunk c has id `first_id + c * per_chunk + k`.
pub trait TriangleSource: Sync {
    /// Chunks, in drawing order.
    fn chunks(&self) -> usize;
    /// Triangles per chunk.
    fn per_chunk(&self) -> u64;
    /// The triangles of chunk `c`, in order, into `out` (cleared first).
    fn chunk(&self, c: usize, out: &mut Vec<Triangle>);
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
}

/// Runs the triangle path over every triangle of `source`, in order, into `sink`.
pub fn render_triangles<R: Real, S: TriangleSink<R>>(
    source: &dyn TriangleSource,
    view: &View,
    sink: &mut S,
    counts: &mut Counts,
) {
    let mut triangles = Vec::new();
    for c in 0..source.chunks() {
        source.chunk(c, &mut triangles);
        for (k, t) in triangles.iter().enumerate() {
            counts.triangles += 1;
            let id = source.id(c, k);
            match setup::<R>(id, &t.positions, &t.normals, t.color, view) {
                Ok(st) => rasterize(&st, sink, counts),
                Err(cull) => count_cull(cull, counts),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};

    const VP: Viewport = Viewport {
        width: 64,
        height: 48,
    };

    fn flat(z: f64) -> Vertex<f64> {
        Vertex {
            z,
            inv_w: 1.0,
            normal_w: [0.0, 0.0, 1.0],
            position_w: [0.0; 3],
        }
    }

    /// A triangle from sub-pixel vertex positions.
    fn tri(id: u32, p: [(i64, i64); 3]) -> Option<ScreenTriangle<f64>> {
        ScreenTriangle::assemble(
            id,
            p.map(|p| p.0),
            p.map(|p| p.1),
            [flat(0.5); 3],
            [1.0; 3],
            VP,
        )
        .ok()
    }

    /// Pixel centre (i, j) in sub-pixel units.
    fn c(i: i64, j: i64) -> (i64, i64) {
        (i * SUBPIXEL + SUBPIXEL / 2, j * SUBPIXEL + SUBPIXEL / 2)
    }

    /// How often each pixel is covered by the triangles, through the quad walk.
    fn hits(tris: &[ScreenTriangle<f64>]) -> Vec<u32> {
        struct Hits(Vec<u32>);
        impl TriangleSink<f64> for Hits {
            fn fragment(
                &mut self,
                _: &ScreenTriangle<f64>,
                i: u32,
                j: u32,
                _: &TriangleFragment<f64>,
            ) {
                self.0[(j * VP.width + i) as usize] += 1;
            }
        }
        let mut sink = Hits(vec![0; VP.pixels()]);
        let mut counts = Counts::default();
        for t in tris {
            rasterize(t, &mut sink, &mut counts);
        }
        assert_eq!(
            counts.fragments,
            sink.0.iter().map(|&n| n as u64).sum::<u64>()
        );
        sink.0
    }

    fn covered(h: &[u32], i: i64, j: i64) -> u32 {
        h[(j * VP.width as i64 + i) as usize]
    }

    #[test]
    fn top_left_rule_on_pixel_centres() {
        // A rectangle from centre (2, 2) to centre (10, 6), split along its diagonal: its
        // top and left sides pass exactly through pixel centres and are included, its
        // bottom and right sides too and are excluded.
        for winding in [false, true] {
            let (a, b, cc, d) = (c(2, 2), c(10, 2), c(10, 6), c(2, 6));
            let mut t = vec![tri(0, [a, b, cc]).unwrap(), tri(1, [a, cc, d]).unwrap()];
            if winding {
                t = vec![tri(0, [a, cc, b]).unwrap(), tri(1, [a, d, cc]).unwrap()];
            }
            let h = hits(&t);
            for j in 0..VP.height as i64 {
                for i in 0..VP.width as i64 {
                    let want = (2..10).contains(&i) && (2..6).contains(&j);
                    assert_eq!(covered(&h, i, j), want as u32, "pixel ({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn triangles_sharing_an_edge_cover_each_pixel_exactly_once() {
        // Shared edges of many slopes through many pixel centres, both windings: the union
        // of the two triangles (a convex quadrilateral) is covered exactly once.
        let mut seed = 12345u64;
        let mut rnd = |lo: i64, hi: i64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (seed % (hi - lo) as u64) as i64
        };
        for case in 0..400 {
            // The shared edge from p to q; on-centre end points half the time.
            let (p, q) = if case % 2 == 0 {
                // Even offsets: the edge's midpoint is a pixel centre too.
                let (i, j) = (rnd(8, 24), rnd(8, 40));
                (c(i, j), c(i + 2 * rnd(8, 16), j + 2 * rnd(-4, 4)))
            } else {
                (
                    (rnd(2000, 6000), rnd(2000, 10000)),
                    (rnd(10000, 14000), rnd(2000, 10000)),
                )
            };
            // Third vertices on either side of the edge, far enough to keep it convex.
            let (mx, my) = ((p.0 + q.0) / 2, (p.1 + q.1) / 2);
            let (nx, ny) = (-(q.1 - p.1), q.0 - p.0);
            let f = rnd(2, 9) as f64 / 10.0;
            let r = (mx + (nx as f64 * f) as i64, my + (ny as f64 * f) as i64);
            let g = rnd(2, 9) as f64 / 10.0;
            let s = (mx - (nx as f64 * g) as i64, my - (ny as f64 * g) as i64);
            let (Some(t0), Some(t1)) = (
                tri(0, if case % 3 == 0 { [p, q, r] } else { [q, p, r] }),
                tri(1, [p, q, s]),
            ) else {
                continue;
            };
            let h = hits(&[t0.clone(), t1.clone()]);
            let quad = |i: i64, j: i64| {
                let (x, y) = c(i, j);
                let side = |a: (i64, i64), b: (i64, i64)| {
                    (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0)
                };
                // Strictly inside the quadrilateral p r q s (either orientation).
                let e = [side(p, r), side(r, q), side(q, s), side(s, p)];
                e.iter().all(|&v| v > 0) || e.iter().all(|&v| v < 0)
            };
            let mut on_edge = 0;
            for j in 0..VP.height as i64 {
                for i in 0..VP.width as i64 {
                    let n = covered(&h, i, j);
                    assert!(n <= 1, "case {case}: pixel ({i}, {j}) covered {n} times");
                    if quad(i, j) {
                        assert_eq!(n, 1, "case {case}: pixel ({i}, {j}) missed");
                        let (x, y) = c(i, j);
                        if (q.0 - p.0) * (y - p.1) == (q.1 - p.1) * (x - p.0) {
                            on_edge += 1;
                        }
                    }
                }
            }
            if case % 2 == 0 {
                // The edge passes through pixel centres: exactly the case the fill rule
                // decides.
                assert!(on_edge >= 1, "case {case}: no centre on the shared edge");
            }
        }
    }

    #[test]
    fn a_fan_around_a_vertex_covers_each_pixel_exactly_once() {
        // Twelve triangles around a vertex on a pixel centre, outer vertices on a polygon
        // (some on centres, some not): every pixel strictly inside is covered once,
        // the centre pixel included.
        let o = c(30, 24);
        let ring: Vec<(i64, i64)> = (0..12)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 12.0;
                let r = if k % 2 == 0 {
                    20.0 * 256.0
                } else {
                    17.3 * 256.0
                };
                (
                    o.0 + (r * a.cos()).round() as i64,
                    o.1 + (r * a.sin()).round() as i64,
                )
            })
            .collect();
        let tris: Vec<_> = (0..12)
            .map(|k| tri(k as u32, [o, ring[k], ring[(k + 1) % 12]]).unwrap())
            .collect();
        let h = hits(&tris);
        assert_eq!(covered(&h, 30, 24), 1);
        for j in 0..VP.height as i64 {
            for i in 0..VP.width as i64 {
                let n = covered(&h, i, j);
                assert!(n <= 1, "pixel ({i}, {j}) covered {n} times");
                let (x, y) = c(i, j);
                let inside = (0..12).all(|k| {
                    let (a, b) = (ring[k], ring[(k + 1) % 12]);
                    (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0) > 0
                });
                if inside {
                    assert_eq!(n, 1, "pixel ({i}, {j}) missed");
                }
            }
        }
    }

    #[test]
    fn quads_are_aligned_and_their_masks_match_coverage() {
        let t = tri(
            0,
            [
                c(3, 1),
                (40 * 256 + 17, 9 * 256 + 3),
                (11 * 256 + 200, 30 * 256),
            ],
        )
        .unwrap();
        let mut seen = std::collections::BTreeSet::new();
        let mut quads = 0u64;
        t.quads(|qi, qj, rows, mask| {
            assert!(qi % 2 == 0 && qj % 2 == 0 && mask != 0);
            assert_eq!(*rows, [t.row_span(qj), t.row_span(qj + 1)]);
            for bit in 0..4 {
                let (i, j) = (qi + (bit & 1), qj + (bit >> 1));
                let inside = i < VP.width && j < VP.height && t.covers(i, j);
                assert_eq!(mask & (1 << bit) != 0, inside, "({i}, {j})");
                if inside {
                    seen.insert((i, j));
                }
            }
            quads += 1;
        });
        let all: std::collections::BTreeSet<_> = (0..VP.height)
            .flat_map(|j| (0..VP.width).map(move |i| (i, j)))
            .filter(|&(i, j)| t.covers(i, j))
            .collect();
        assert_eq!(seen, all);
        let per_row: u64 = (0..VP.height / 2)
            .map(|q| quads_in(&[t.row_span(2 * q), t.row_span(2 * q + 1)]))
            .sum();
        assert_eq!(quads, per_row);
    }

    #[test]
    fn snapping_rounds_to_the_nearest_256th_of_a_pixel() {
        assert_eq!(snap(10.0f64), 2560);
        assert_eq!(snap(10.3f64), 2637); // 2636.8
        assert_eq!(snap(-0.3f64), -77); // -76.8
        assert_eq!(snap(1.0f64 / 512.0 * 0.99), 0);
        assert_eq!(snap(3.0f32 + 1.0 / 256.0), 3 * 256 + 1);
        // A triangle nudged by less than half a sub-pixel step covers the same pixels.
        let view = ortho_view();
        // On the sub-pixel grid, then nudged by less than half a step.
        let p = [
            DVec3::new(3.25, 4.125, 0.0),
            DVec3::new(40.5 + 3.0 / 256.0, 9.0, 0.0),
            DVec3::new(12.25, 30.0 + 255.0 / 256.0, 0.0),
        ];
        let nudge = DVec3::new(0.4 / 256.0, -0.45 / 256.0, 0.0);
        let a = setup::<f64>(0, &p, &[DVec3::Z; 3], [1.0; 3], &view).unwrap();
        let b = setup::<f64>(0, &p.map(|q| q + nudge), &[DVec3::Z; 3], [1.0; 3], &view);
        let b = b.unwrap();
        assert_eq!((a.x, a.y), (b.x, b.y));
        assert_eq!((a.x[0], a.y[0]), (3 * 256 + 64, 4 * 256 + 32));
    }

    /// World x, y = screen x, y (pixels), y down, with an orthographic camera.
    fn ortho_view() -> View {
        let (w, h) = (VP.width as f64, VP.height as f64);
        View::new(
            &Camera {
                eye: [w / 2.0, h / 2.0, -10.0],
                target: [w / 2.0, h / 2.0, 0.0],
                up: [0.0, -1.0, 0.0],
                projection: Projection::Orthographic {
                    height: h,
                    near: 1.0,
                    far: 20.0,
                },
            },
            VP,
        )
    }

    #[test]
    fn perspective_correct_depth_normal_and_position_match_the_plane() {
        // A triangle strongly slanted in depth, seen in perspective, with three different
        // vertex normals. At every covered pixel centre the ray meets the triangle's plane
        // at P: the fragment's depth is P's depth, its position is P, and its normal is the
        // world-space barycentric blend at P. Affine (not perspective-correct) weights miss
        // by far more than the tolerance, so the test can fail.
        let view = View::new(
            &Camera {
                eye: [0.0, 0.0, 0.0],
                target: [0.0, 0.0, -1.0],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 60.0,
                    near: 0.1,
                    far: 100.0,
                },
            },
            VP,
        );
        let p = [
            DVec3::new(-1.0, -0.6, -1.5),
            DVec3::new(2.5, -0.4, -8.0),
            DVec3::new(-0.5, 1.2, -2.0),
        ];
        let n = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let t = setup::<f64>(7, &p, &n, [1.0; 3], &view).unwrap();
        let plane_n = (p[1] - p[0]).cross(p[2] - p[0]);
        let (mut checked, mut affine_miss) = (0, 0.0f64);
        for j in 0..VP.height {
            for i in 0..VP.width {
                if !t.covers(i, j) {
                    continue;
                }
                let (o, d) = view.ray(i as f64 + 0.5, j as f64 + 0.5);
                let hit = o + d * (plane_n.dot(p[0] - o) / plane_n.dot(d));
                // World barycentrics of the hit.
                let area = plane_n.length_squared();
                let b = [
                    (p[1] - hit).cross(p[2] - hit).dot(plane_n) / area,
                    (p[2] - hit).cross(p[0] - hit).dot(plane_n) / area,
                    (p[0] - hit).cross(p[1] - hit).dot(plane_n) / area,
                ];
                let want_n = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize();
                let f = t.fragment(i, j);
                let got_n = DVec3::from_array(f.normal).normalize();
                let got_p = DVec3::from_array(f.position);
                // Tolerances: snapping moves the vertices by up to 1/512 pixel, about 4e-4
                // world units at the far vertex, more along the grazing plane.
                assert!(
                    (f.z - view.depth_of(hit)).abs() < 1e-5,
                    "depth at ({i}, {j})"
                );
                assert!((got_p - hit).length() < 3e-3, "position at ({i}, {j})");
                assert!((got_n - want_n).length() < 1e-3, "normal at ({i}, {j})");
                // What affine screen-space weights would give.
                let e = t.edge_values(i, j).map(|v| v as f64 / t.area2 as f64);
                let affine: DVec3 = (0..3)
                    .map(|k| DVec3::from_array(t.position_w[k]) / t.inv_w[k] * e[k])
                    .sum();
                affine_miss = affine_miss.max((affine - hit).length());
                checked += 1;
            }
        }
        assert!(checked > 200, "{checked}");
        assert!(affine_miss > 0.1, "{affine_miss}");
    }

    #[test]
    fn culls_are_classified() {
        let view = ortho_view();
        let z = DVec3::Z;
        let cull = |p: [DVec3; 3]| setup::<f32>(0, &p, &[z; 3], [1.0; 3], &view).err();
        let (a, b, c) = (
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(9.0, 1.0, 0.0),
            DVec3::new(1.0, 9.0, 0.0),
        );
        assert_eq!(cull([a, b, c]), None);
        let off = DVec3::new(500.0, 0.0, 0.0);
        assert_eq!(
            cull([a + off, b + off, c + off]),
            Some(TriangleCull::Outside)
        );
        assert_eq!(cull([a, b, a]), Some(TriangleCull::Degenerate));
        let far = DVec3::new(1e6, 0.0, 0.0);
        assert_eq!(cull([a, b, far]), Some(TriangleCull::GuardBand));
        // Between two pixel centres: no sample inside.
        let tiny = [
            DVec3::new(1.6, 1.6, 0.0),
            DVec3::new(1.9, 1.6, 0.0),
            DVec3::new(1.6, 1.9, 0.0),
        ];
        assert_eq!(cull(tiny), Some(TriangleCull::Degenerate));
        // Beyond the far plane (the eye is at z = -10, far = 20).
        let behind = DVec3::new(0.0, 0.0, 30.0);
        assert_eq!(
            cull([a + behind, b + behind, c + behind]),
            Some(TriangleCull::Outside)
        );
    }
}
