//! The triangle path's rasterizer: coverage by integer edge functions with the top-left
//! rule, 2x2 quads, and each covered pixel's perspective-correct [`TriangleFragment`].

use super::setup::{ScreenTriangle, SUBPIXEL};
use crate::datapath::Real;
use crate::datapath::{Event, Op};
use crate::raster::counts::Counts;

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

impl<R: Real> ScreenTriangle<R> {
    /// The three edge functions at pixel (i, j)'s centre (on a sample grid, its sample).
    #[inline(always)]
    pub(super) fn edge_values(&self, i: u32, j: u32) -> [i64; 3] {
        self.edge_values_at(self.sample_at(i, j))
    }

    /// The three edge functions at sub-pixel position (px, py).
    #[inline(always)]
    fn edge_values_at(&self, (px, py): (i64, i64)) -> [i64; 3] {
        // Three edge functions a x + b y + c.
        R::count_beside(Op::IntMul, 6);
        R::count_beside(Op::IntAdd, 6);
        let [e0, e1, e2] = &self.edges;
        [e0.at(px, py), e1.at(px, py), e2.at(px, py)]
    }

    /// Whether pixel (i, j)'s centre is inside, by the top-left rule.
    #[inline(always)]
    pub fn covers(&self, i: u32, j: u32) -> bool {
        let e = self.edge_values(i, j);
        R::count_beside(Op::IntAdd, 3);
        (0..3).all(|k| e[k] >= self.edges[k].min)
    }

    /// The fragment at pixel (i, j) (meaningful where [`Self::covers`]).
    #[inline]
    pub fn fragment(&self, i: u32, j: u32) -> TriangleFragment<R> {
        let (l, z) = self.weights(i, j);
        self.fragment_at(l, z)
    }

    /// The barycentric weights of pixel (i, j)'s centre (on a sample grid, its sample) and
    /// the depth there.
    #[inline(always)]
    pub fn weights(&self, i: u32, j: u32) -> ([R; 3], R) {
        self.weights_of(self.edge_values(i, j))
    }

    /// The barycentric weights a multisampled triangle is shaded with at column i of sample
    /// row j: at the centre of the pixel ([`ScreenTriangle::shading_point`]), the same for
    /// every sample of the pixel. A centre outside the triangle has its negative weights
    /// clamped to 0 and the rest scaled to sum 1 (a point on the triangle's border, as
    /// centroid sampling aims for): extrapolated attributes could leave the surface, and
    /// 1/w could reach 0 beside a triangle that runs to the horizon.
    #[inline(always)]
    pub fn shading_weights(&self, i: u32, j: u32) -> [R; 3] {
        let l = self
            .weights_of(self.edge_values_at(self.shading_point(i, j)))
            .0;
        if l.iter().all(|&w| w >= R::zero()) {
            return l;
        }
        let l = l.map(|w| w.max(R::zero()));
        let sum = l[0] + l[1] + l[2];
        l.map(|w| w / sum)
    }

    /// The weights and depth of edge-function values `e`.
    #[inline(always)]
    fn weights_of(&self, e: [i64; 3]) -> ([R; 3], R) {
        let area = R::of(self.area2 as f64);
        let l = [
            R::of(e[0] as f64) / area,
            R::of(e[1] as f64) / area,
            R::of(e[2] as f64) / area,
        ];
        let z = l[0] * self.z[0] + l[1] * self.z[1] + l[2] * self.z[2];
        (l, z)
    }

    /// The fragment of weights `l` and depth `z` ([`Self::weights`]): its normal and
    /// position, perspective-correct, sum(l_k a_k / w_k) / sum(l_k / w_k) with a_k / w_k
    /// kept per vertex.
    #[inline(always)]
    pub fn fragment_at(&self, l: [R; 3], z: R) -> TriangleFragment<R> {
        let sum = inv_w_at(l, self.inv_w);
        TriangleFragment {
            z,
            normal: perspective_lerp(l, sum, &self.normal_w),
            position: perspective_lerp(l, sum, &self.position_w),
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
        if R::COUNTS_OPERATIONS {
            return self.row_span_by_pixels(j);
        }
        // Each edge's half-line of columns, in exact integer arithmetic: E(i) = A i + B
        // with A = 256 a, B = a x0 + b y + c (x0 = 128, column 0's centre, or its sample),
        // covered where E(i) >= min.
        let (x0, py) = self.sample_at(0, j);
        let (mut lo, mut hi) = (i0 as i64, i1 as i64);
        for e in &self.edges {
            let (a, b) = (e.a * SUBPIXEL, e.a * x0 + e.b * py + e.c);
            let need = e.min - b;
            match a.cmp(&0) {
                // i >= ceil(need / a)
                std::cmp::Ordering::Greater => lo = lo.max(-(-need).div_euclid(a)),
                // i <= floor(-need / -a)
                std::cmp::Ordering::Less => hi = hi.min((-need).div_euclid(-a) + 1),
                std::cmp::Ordering::Equal if need > 0 => return (i1, i1),
                std::cmp::Ordering::Equal => {}
            }
        }
        if lo >= hi {
            return (i1, i1);
        }
        (lo as u32, hi as u32)
    }

    /// [`Self::row_span`] found pixel by pixel, testing each from the bounding box's left
    /// until the first covered one and on to the first uncovered one: the edge-function
    /// work a counting datapath counts (the closed form above finds the same columns).
    pub fn row_span_by_pixels(&self, j: u32) -> (u32, u32) {
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

    /// Row `j`'s exact edge functions as `E_k(i) = a_k i + b_k` over its columns i, in
    /// `f64`, for [`Self::weights_lanes`].
    #[inline(always)]
    pub fn row_edges(&self, j: u32) -> RowEdges<R> {
        let (x0, py) = self.sample_at(0, j);
        RowEdges {
            a: self.edges.map(|e| (e.a * SUBPIXEL) as f64),
            b: self.edges.map(|e| (e.a * x0 + e.b * py + e.c) as f64),
            area: R::of(self.area2 as f64),
        }
    }

    /// [`Self::weights`] of the [`WEIGHT_LANES`] pixels from column `i` on of the row of
    /// `row` ([`Self::row_edges`]): the same values bit for bit, computed side by side.
    ///
    /// An edge function's value is an integer below 2^50 in magnitude (snapped vertices
    /// within the guard band, pixel centres within 16384 pixels), and so are `a_k i` and
    /// `b_k`: `f64` holds each exactly and adds them exactly, which gives the integer the
    /// scalar path converts.
    #[inline(always)]
    pub fn weights_lanes(
        &self,
        row: &RowEdges<R>,
        i: u32,
    ) -> ([[R; WEIGHT_LANES]; 3], [R; WEIGHT_LANES]) {
        let l: [[R; WEIGHT_LANES]; 3] = std::array::from_fn(|e| {
            std::array::from_fn(|k| {
                let x = (i as usize + k) as f64;
                R::of(row.a[e] * x + row.b[e]) / row.area
            })
        });
        let z = std::array::from_fn(|k| {
            l[0][k] * self.z[0] + l[1][k] * self.z[1] + l[2][k] * self.z[2]
        });
        (l, z)
    }
}

/// Side of the coarse tiles a hardware rasterizer tests a triangle's bounding box in, before
/// its quads \[pixels\]: the ROP interleave tile's default (`rop.tile_px`), so a tile that
/// survives is one ROP's. Even, so a tile holds whole 2x2 quads.
pub const COARSE_TILE_PX: u32 = 8;

/// What a hierarchical rasterizer meets walking one triangle ([`ScreenTriangle::walk`]):
/// the events its operations are priced by (`cost::built`). The model finds coverage in
/// closed form per row ([`ScreenTriangle::row_span`]); the walk finds the same pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Walk {
    /// Coarse tiles of the bounding box, each tested against the three edges.
    pub tiles: u64,
    /// Quads (2x2, aligned to even coordinates) of the tiles not rejected that meet the
    /// bounding box: each has its four pixel centres tested.
    pub quads_tested: u64,
    /// Tested quads with at least one covered pixel centre (the model's `Counts::quads`).
    pub quads_covered: u64,
    /// Covered pixel centres (the model's `Counts::fragments`).
    pub fragments: u64,
}

impl<R: Real> ScreenTriangle<R> {
    /// The hierarchical walk of the bounding box, in [`COARSE_TILE_PX`] tiles aligned to
    /// the screen: a tile is rejected when one edge is below its fill-rule minimum at the
    /// tile's pixel centre where that edge is largest (the corner its signs of a and b
    /// point to: the trivial-reject corner), so no centre of the tile can be inside; each
    /// quad of a surviving tile that meets the bounding box is tested pixel by pixel, in
    /// exact integers (the fill rule of [`Self::covers`]), uncounted.
    pub fn walk(&self) -> Walk {
        let [i0, i1, j0, j1] = self.bbox;
        let t = COARSE_TILE_PX;
        let inside = |i: u32, j: u32| {
            let (x, y) = self.sample_at(i, j);
            self.edges.iter().all(|e| e.at(x, y) >= e.min)
        };
        // A tile's samples lie between its corner pixels' centres moved by the pattern's
        // least and greatest offsets along a row (none with one sample).
        let (dmin, dmax) = self.samples.dx16_range();
        let corner = |i: u32, j: u32, d: i64| {
            let (x, y) = super::setup::pixel_centre(i, j);
            (x + SUBPIXEL / 16 * d, y)
        };
        let mut walk = Walk::default();
        for ty in j0 / t..=(j1 - 1) / t {
            for tx in i0 / t..=(i1 - 1) / t {
                walk.tiles += 1;
                let (lo_x, lo_y) = corner(tx * t, ty * t, dmin);
                let (hi_x, hi_y) = corner(tx * t + t - 1, ty * t + t - 1, dmax);
                let rejected = self.edges.iter().any(|e| {
                    let x = if e.a > 0 { hi_x } else { lo_x };
                    let y = if e.b > 0 { hi_y } else { lo_y };
                    e.at(x, y) < e.min
                });
                if rejected {
                    continue;
                }
                let rows = (ty * t).max(j0 & !1)..(ty * t + t).min(j1);
                for qj in rows.step_by(2) {
                    let cols = (tx * t).max(i0 & !1)..(tx * t + t).min(i1);
                    for qi in cols.step_by(2) {
                        walk.quads_tested += 1;
                        let covered = [(0, 0), (1, 0), (0, 1), (1, 1)]
                            .iter()
                            .map(|&(di, dj)| (qi + di, qj + dj))
                            .filter(|&(i, j)| (i0..i1).contains(&i) && (j0..j1).contains(&j))
                            .filter(|&(i, j)| inside(i, j))
                            .count() as u64;
                        walk.quads_covered += (covered > 0) as u64;
                        walk.fragments += covered;
                    }
                }
            }
        }
        walk
    }

    /// Tallies the triangle's [`Walk`] as hardware events (`Real::tally`; a counting
    /// datapath keeps them for `cost::built`, other words do nothing).
    #[inline]
    pub fn tally_walk(&self) {
        if !R::COUNTS_OPERATIONS {
            return;
        }
        let w = self.walk();
        R::tally(Event::Triangle, 1);
        R::tally(Event::Tile, w.tiles);
        R::tally(Event::QuadTested, w.quads_tested);
        R::tally(Event::QuadCovered, w.quads_covered);
        match self.samples.get() {
            1 => R::tally(Event::Fragment, w.fragments),
            _ => R::tally(Event::Sample, w.fragments),
        }
    }
}

/// Pixels [`ScreenTriangle::weights_lanes`] works out together.
pub const WEIGHT_LANES: usize = 8;

/// One row's edge functions along its columns ([`ScreenTriangle::row_edges`]).
#[derive(Clone, Copy, Debug)]
pub struct RowEdges<R> {
    /// Per edge, the step from one column to the next \[1/256 pixel, squared\].
    a: [f64; 3],
    /// Per edge, the value at column 0.
    b: [f64; 3],
    /// Twice the triangle's area, in the datapath.
    area: R,
}

/// 1/w at weights `l`: sum(l_k / w_k), from the vertices' 1/w.
#[inline(always)]
pub fn inv_w_at<R: Real>(l: [R; 3], inv_w: [R; 3]) -> R {
    l[0] * inv_w[0] + l[1] * inv_w[1] + l[2] * inv_w[2]
}

/// An attribute at weights `l`, perspective-correct: sum(l_k a_k / w_k) / `inv_w`, from the
/// vertices' a_k / w_k and 1/w there ([`inv_w_at`]).
#[inline(always)]
pub fn perspective_lerp<R: Real>(l: [R; 3], inv_w: R, a_w: &[[R; 3]; 3]) -> [R; 3] {
    let at = |c: usize| (l[0] * a_w[0][c] + l[1] * a_w[1][c] + l[2] * a_w[2][c]) / inv_w;
    [at(0), at(1), at(2)]
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
/// A triangle covers a pixel at most once, so the order its fragments arrive in does not
/// matter to a sink that keeps per-pixel state.
pub trait TriangleSink<R: Real> {
    /// Takes fragment `f` of triangle `t` at pixel (i, j).
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>);

    /// Takes the covered pixel (i, j) of triangle `t` with its weights and depth
    /// ([`ScreenTriangle::weights`]). The default works out the fragment's normal and
    /// position ([`ScreenTriangle::fragment_at`]) and hands it to [`Self::fragment`]; the
    /// ROP tests the depth first and works them out, in lanes, only for the fragments
    /// that pass.
    #[inline]
    fn covered(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, l: [R; 3], z: R) {
        let f = t.fragment_at(l, z);
        self.fragment(t, i, j, &f);
    }

    /// Takes the covered pixels `a..b` (not empty) of row `j` of triangle `t`. The default
    /// hands each, left to right, to [`Self::covered`] with its weights and depth; the ROP
    /// works out the weights of several pixels together ([`ScreenTriangle::weights_lanes`]).
    #[inline]
    fn row(&mut self, t: &ScreenTriangle<R>, j: u32, a: u32, b: u32) {
        row_by_pixels(self, t, j, a, b);
    }
}

/// [`TriangleSink::row`] pixel by pixel: each covered pixel `a..b` of row `j`, left to
/// right, to [`TriangleSink::covered`] with its weights and depth.
#[inline]
pub fn row_by_pixels<R: Real, S: TriangleSink<R> + ?Sized>(
    sink: &mut S,
    t: &ScreenTriangle<R>,
    j: u32,
    a: u32,
    b: u32,
) {
    for i in a..b {
        let (l, z) = t.weights(i, j);
        sink.covered(t, i, j, l, z);
    }
}

/// Rasterizes one set-up triangle into `sink`, a pair of rows at a time.
pub fn rasterize<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    sink: &mut S,
    counts: &mut Counts,
) {
    rasterize_rows(t, 0, u32::MAX, sink, counts)
}

/// [`rasterize`] for the quads whose top row is in `lo..hi` (`lo` even): a band of rows
/// of the frame. Each pair of rows counts the 2x2 quads its covered spans touch
/// ([`quads_in`]); the covered pixels go to the sink a row at a time, top to bottom. On an
/// x86-64 CPU with AVX2 this is compiled for it, the sink's rows included (the lanes of
/// [`ScreenTriangle::weights_lanes`] eight wide): the same IEEE operations in the same
/// order, so the same bits.
pub fn rasterize_rows<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    lo: u32,
    hi: u32,
    sink: &mut S,
    counts: &mut Counts,
) {
    #[cfg(target_arch = "x86_64")]
    if crate::isa::kernels() == crate::isa::Isa::Avx2 {
        // SAFETY: `kernels` says AVX2 only where the CPU has it.
        return unsafe { rasterize_rows_avx2(t, lo, hi, sink, counts) };
    }
    rasterize_rows_as_compiled(t, lo, hi, sink, counts)
}

/// [`rasterize_rows`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn rasterize_rows_avx2<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    lo: u32,
    hi: u32,
    sink: &mut S,
    counts: &mut Counts,
) {
    rasterize_rows_as_compiled(t, lo, hi, sink, counts)
}

/// [`rasterize_rows`] for the instruction set its caller is compiled for.
#[inline(always)]
pub(crate) fn rasterize_rows_as_compiled<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    lo: u32,
    hi: u32,
    sink: &mut S,
    counts: &mut Counts,
) {
    debug_assert!(
        lo.is_multiple_of(2),
        "bands start on even rows, as quads do"
    );
    let [_, _, j0, j1] = t.bbox;
    let mut qj = (j0 & !1).max(lo);
    while qj < j1.min(hi) {
        let rows = [t.row_span(qj), t.row_span(qj + 1)];
        counts.quads += quads_in(&rows);
        for (j, (a, b)) in (qj..).zip(rows) {
            if a < b {
                sink.row(t, j, a, b);
                counts.fragments += (b - a) as u64;
            }
        }
        qj += 2;
    }
}
