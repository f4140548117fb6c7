//! The set-up lembo the scan-line stages take ([`ScreenLembo`]: screen quadratics, canonical
//! edges, walk partition) and how Setup builds one from six screen points, with the tests on
//! screen points (hull, viewport, guard band, zero area) that Setup (`setup.rs`) and its
//! perspective split (`refine.rs`) share. Setup's entry points and its guard-band split are
//! in `setup.rs`, which builds on this file as the perspective split does; this file knows
//! neither.
//!
//! The *walk partition* of the domain pairs edge roots into intervals (see `interval.rs`): a
//! direction `a` such that `a·∇Y > 0` on each of at most two convex parts of the domain,
//! split by the line `a·∇Y = 0`. Inside such a part every level curve `Y = y_j` is a graph
//! over `rot_cw(a)`, so the position along that direction orders the curve's points in
//! walking order.

use super::v2::{dot, norm, V2};
use crate::camera::View;
use crate::datapath::Real;
use crate::lembo::{bezier_controls, Lembo, Quadratic, Quadratic3, REFERENCE_UV};
use glam::DVec3;

/// One domain edge in canonical order: the screen values of its start, middle and end
/// points, ordered so that two lembos sharing the edge compute bit-identical roots.
#[derive(Clone, Copy, Debug)]
pub struct EdgeCurve<R> {
    /// Screen y at canonical t = 0, 1/2, 1 \[pixels\].
    pub y: [R; 3],
    /// Screen x at canonical t = 0, 1/2, 1 \[pixels\].
    pub x: [R; 3],
    /// Whether canonical t runs against the lembo's edge direction.
    pub reversed: bool,
    /// On a plain datapath, [`Self::y_power`], [`Self::x_power`], [`Self::y_vertex`] and
    /// [`Self::y_dip`] worked out once at Setup (the interval manager needs them on every
    /// scanline; the same bits); on a counting datapath unused, so that the interval
    /// manager counts them where the hardware computes them. Made by [`Self::new`] from
    /// `y` and `x`, which nothing changes after.
    hoisted: Hoisted<R>,
}

/// An edge's values that depend on its screen values only ([`EdgeCurve::hoisted`]).
#[derive(Clone, Copy, Debug)]
struct Hoisted<R> {
    y: (R, R),
    x: (R, R),
    vertex: R,
    dip: R,
}

impl<R: Real> EdgeCurve<R> {
    /// The edge from its canonical screen values.
    pub fn new(y: [R; 3], x: [R; 3], reversed: bool) -> Self {
        let hoisted = if R::COUNTS_OPERATIONS {
            let zero = R::zero();
            Hoisted {
                y: (zero, zero),
                x: (zero, zero),
                vertex: zero,
                dip: zero,
            }
        } else {
            let (a, b) = power(&y);
            Hoisted {
                y: (a, b),
                x: power(&x),
                vertex: vertex(a, b),
                dip: dip(a, b),
            }
        };
        EdgeCurve {
            y,
            x,
            reversed,
            hoisted,
        }
    }

    /// Canonical t of the vertex of y's parabola, -B / 2A (not finite for a straight y),
    /// from y's (A, B) = [`Self::y_power`] (a counting datapath works it out from them).
    #[inline(always)]
    pub fn y_vertex(&self, (a, b): (R, R)) -> R {
        if R::COUNTS_OPERATIONS {
            return vertex(a, b);
        }
        self.hoisted.vertex
    }

    /// y(0) less y at the vertex: B² / 4A, from y's (A, B) as [`Self::y_vertex`].
    #[inline(always)]
    pub fn y_dip(&self, (a, b): (R, R)) -> R {
        if R::COUNTS_OPERATIONS {
            return dip(a, b);
        }
        self.hoisted.dip
    }

    /// y(t) - y(0) = A t² + B t through the canonical start, middle and end: (A, B).
    #[inline(always)]
    pub fn y_power(&self) -> (R, R) {
        if R::COUNTS_OPERATIONS {
            return power(&self.y);
        }
        self.hoisted.y
    }

    /// x(t) - x(0) = A t² + B t, as [`Self::y_power`].
    #[inline(always)]
    pub fn x_power(&self) -> (R, R) {
        if R::COUNTS_OPERATIONS {
            return power(&self.x);
        }
        self.hoisted.x
    }
}

/// -B / 2A.
#[inline(always)]
fn vertex<R: Real>(a: R, b: R) -> R {
    -b / (R::of(2.0) * a)
}

/// B² / 4A.
#[inline(always)]
fn dip<R: Real>(a: R, b: R) -> R {
    b * b / (R::of(4.0) * a)
}

/// (A, B) of the parabola through values `p` at t = 0, 1/2, 1, less its value at 0.
#[inline(always)]
fn power<R: Real>(p: &[R; 3]) -> (R, R) {
    let (two, three, four) = (R::of(2.0), R::of(3.0), R::of(4.0));
    let b = four * p[1] - three * p[0] - p[2];
    let a = two * p[0] + two * p[2] - four * p[1];
    (a, b)
}

/// The domain edges in the lembo's counter-clockwise order: A→B (v = 0), B→C (u + v = 1),
/// C→A (u = 0), each given by the indices of its start, middle and end reference points.
pub const EDGE_POINTS: [[usize; 3]; 3] = [[0, 3, 1], [1, 5, 2], [2, 4, 0]];

/// (u, v) of the point at lembo-order parameter `t` on domain edge `e`.
#[inline]
pub fn edge_uv<R: Real>(e: usize, t: R) -> V2<R> {
    let one = R::one();
    match e {
        0 => [t, R::zero()],
        1 => [one - t, t],
        _ => [R::zero(), one - t],
    }
}

/// How the domain is split for walking level curves (computed once per lembo).
#[derive(Clone, Copy, Debug)]
pub enum Partition<R> {
    /// `a·∇Y > 0` on the whole domain: one part, no split.
    Monotone {
        /// The walk axis.
        a: V2<R>,
        /// The least `a·∇Y` and the largest `|∇Y|` at the domain's corners (worked out in
        /// `f64`): as ∇Y is affine, they bound it over the whole domain (the segmenter's
        /// `least_reach`, which allows for their rounding).
        grad_bounds: [R; 2],
    },
    /// `∇Y` vanishes at an isolated point of the domain (an interior extremum if `det > 0`,
    /// a saddle if `det < 0`): the domain is split by the line `a·∇Y = 0`, with `a` chosen per
    /// scanline for saddles (the transverse axis of the hyperbola).
    Central {
        /// The critical point (u, v).
        centre: V2<R>,
        /// Screen y at the critical point \[pixels\].
        y_centre: R,
        /// Determinant of the Hessian of y.
        det: R,
        /// Unit eigenvectors of the Hessian and their eigenvalues, larger |λ| first.
        eig: [(V2<R>, R); 2],
    },
    /// The Hessian is (nearly) singular and `∇Y` vanishes along a line through the domain
    /// (a valley): level curves are near-parallel lines on either side of it.
    Valley {
        /// The walk axis, across the valley.
        a: V2<R>,
    },
}

/// A lembo ready for the scan-line stages, in datapath precision.
#[derive(Clone, Debug)]
pub struct ScreenLembo<R> {
    /// Global id (scene order), also the depth-test tie breaker.
    pub id: u32,
    /// Screen x \[pixels\], y \[pixels\] and depth [0, 1] as quadratics in (u, v).
    pub x: Quadratic<R>,
    /// Screen y \[pixels\].
    pub y: Quadratic<R>,
    /// Window depth.
    pub z: Quadratic<R>,
    /// World-space normal function (normalise per fragment).
    pub normal: Quadratic3<R>,
    /// World-space position function (for the per-fragment direction to the eye).
    pub position: Quadratic3<R>,
    /// Material colour, linear RGB.
    pub color: [R; 3],
    /// The three domain edges in canonical order.
    pub edges: [EdgeCurve<R>; 3],
    /// Screen y of the three vertices A, B, C \[pixels\] (shared bit-identically with
    /// neighbours).
    pub vertex_y: [R; 3],
    /// Hessian of y: (y_uu, y_uv, y_vv).
    pub hessian: (R, R, R),
    /// How the domain is split for walking its level curves.
    pub partition: Partition<R>,
    /// For a piece of a lembo Setup split ([`super::setup::setup_pieces`]): its corners A, B, C in the
    /// lembo's domain, so that (u, v) on the piece is `A + u (B - A) + v (C - A)` on the
    /// lembo. `None` for a whole lembo.
    pub domain: Option<[[f64; 2]; 3]>,
}

impl<R: Real> ScreenLembo<R> {
    /// The lembo's own domain point of (u, v) on this lembo or piece.
    #[inline]
    pub fn lembo_uv(&self, u: R, v: R) -> (R, R) {
        match &self.domain {
            None => (u, v),
            Some([a, b, c]) => {
                let at = |k: usize| R::of(a[k]) + u * R::of(b[k] - a[k]) + v * R::of(c[k] - a[k]);
                (at(0), at(1))
            }
        }
    }
}

/// Why a lembo produced no [`ScreenLembo`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cull {
    /// A point of the Bézier hull is at or behind the eye plane (near clipping is not
    /// modelled: such a lembo is dropped and counted).
    BehindEye,
    /// The Bézier hull lies outside the viewport or outside the depth range.
    Outside,
    /// The screen map has zero area everywhere: its Jacobian x_u y_v - x_v y_u vanishes
    /// identically (six coincident points, a patch on a line or a curve, seen edge-on).
    /// Such a lembo covers no pixel centre; walking its scanlines would draw a trail.
    Degenerate,
}

/// Relative size below which a screen Jacobian counts as zero (f64 rounding of the
/// projection is about 1e-16 of its terms).
pub const DEGENERATE_JACOBIAN: f64 = 1e-9;

/// Whether the screen map through the six projected points has zero area everywhere. The
/// Jacobian is a quadratic in (u, v), so it vanishes identically exactly when it vanishes at
/// the six reference points (they determine a quadratic).
pub(super) fn zero_area(sx: [f64; 6], sy: [f64; 6]) -> bool {
    let (x, y) = (
        Quadratic::from_reference_values(sx),
        Quadratic::from_reference_values(sy),
    );
    let (mut j_max, mut scale) = (0.0f64, 0.0f64);
    for (u, v) in REFERENCE_UV {
        let ((xu, xv), (yu, yv)) = (x.grad(u, v), y.grad(u, v));
        j_max = j_max.max((xu * yv - xv * yu).abs());
        scale = scale.max((xu * yv).abs() + (xv * yu).abs());
    }
    j_max <= DEGENERATE_JACOBIAN * scale
}

/// How far a lembo's Bézier hull may reach beyond the viewport on each side before Setup
/// splits it [viewport sizes, the larger side]. A lembo within this guard band is set up
/// whole; a larger one would make the segmenter and subsegmenter walk its level curves far
/// off screen (a lembo 10⁷ px across needs more than 65536 segments per scanline at
/// k = 1e-4), so it is split into pieces no larger than about the guard band.
pub const SPLIT_GUARD_VIEWPORTS: f64 = 4.0;

/// At most this many halvings of the domain: a piece 2^-40 of a lembo 10¹² px across is
/// still about a pixel. Pieces at this depth are kept whatever their size.
pub const MAX_SPLIT_DEPTH: u32 = 40;

/// At most this many pieces per lembo (kept or pending); past it, pending pieces are kept
/// unsplit, so the work per lembo stays bounded whatever the input.
pub const MAX_PIECES: usize = 1024;

/// What splitting one lembo took (all zero for a lembo set up whole).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Split {
    /// Sub-patches examined: each has its six points evaluated and its hull tested.
    pub examined: u32,
    /// Sub-patches dropped because their Bézier hull misses the viewport or the depth range.
    pub culled: u32,
    /// Sub-patches dropped because they lie wholly nearer than the near plane, or still
    /// straddle the plane `w = w_min` at a cap (`refine.rs`).
    pub culled_near: u32,
    /// Sub-patches kept (or, unprojectable, dropped) at the depth or piece cap while they
    /// still wanted splitting.
    pub capped: u32,
    /// Whether the perspective tolerance split the lembo (`refine.rs`).
    pub perspective: bool,
    /// Whether the lembo was split because part of it could not be projected (it crosses
    /// the plane `w = w_min` near the eye; `refine.rs`).
    pub near: bool,
}

/// A lembo's six reference points on screen: x, y \[pixels\] and depth, in f64.
#[derive(Clone, Copy, Debug)]
pub(super) struct ScreenPoints {
    /// Screen x \[pixels\].
    pub(super) x: [f64; 6],
    /// Screen y \[pixels\].
    pub(super) y: [f64; 6],
    /// Window depth.
    pub(super) z: [f64; 6],
}

impl ScreenPoints {
    /// From six (x, y, depth) points.
    pub(super) fn of(p: &[[f64; 3]; 6]) -> Self {
        ScreenPoints {
            x: p.map(|p| p[0]),
            y: p.map(|p| p[1]),
            z: p.map(|p| p[2]),
        }
    }

    /// Screen x of the six points \[pixels\].
    pub(super) fn xs(&self) -> [f64; 6] {
        self.x
    }

    /// Screen y of the six points \[pixels\].
    pub(super) fn ys(&self) -> [f64; 6] {
        self.y
    }

    /// The bounding box (lo, hi) of the Bézier net of (x, y, z): the patch lies in it.
    pub(super) fn hull(&self) -> (DVec3, DVec3) {
        let p: [DVec3; 6] = std::array::from_fn(|k| DVec3::new(self.x[k], self.y[k], self.z[k]));
        bezier_controls(&p).iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }
}

/// Whether a hull (lo, hi) misses the viewport or the depth range.
pub(super) fn outside(view: &View, (lo, hi): (DVec3, DVec3)) -> bool {
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    hi.x < 0.0 || hi.y < 0.0 || lo.x > w || lo.y > h || hi.z < 0.0 || lo.z > 1.0
}

/// The six reference points (u, v) of the domain triangle `tri`, in the paper's order:
/// its corners A, B, C, then the middles of AB, CA and BC.
pub(super) fn reference_uv(tri: [[f64; 2]; 3]) -> [[f64; 2]; 6] {
    let mid = |p: [f64; 2], q: [f64; 2]| [(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5];
    let [a, b, c] = tri;
    [a, b, c, mid(a, b), mid(c, a), mid(b, c)]
}

/// The domain edge (A→B, B→C, C→A) a point (u, v) lies on and its lembo-order parameter
/// there; `None` inside. Split points are dyadic, so these tests are exact.
pub(super) fn on_domain_edge([u, v]: [f64; 2]) -> Option<(usize, f64)> {
    if v == 0.0 {
        Some((0, u))
    } else if u + v == 1.0 {
        Some((1, v))
    } else if u == 0.0 {
        Some((2, 1.0 - v))
    } else {
        None
    }
}

/// The parabola through `p` (at t = 0, 1/2, 1, exact there) at `t`.
#[inline]
pub(super) fn parabola<const N: usize>(p: &[[f64; N]; 3], t: f64) -> [f64; N] {
    let w = [
        (1.0 - t) * (1.0 - 2.0 * t),
        4.0 * t * (1.0 - t),
        t * (2.0 * t - 1.0),
    ];
    std::array::from_fn(|c| w[0] * p[0][c] + w[1] * p[1][c] + w[2] * p[2][c])
}

/// Whether a hull (lo, hi) stays within [`SPLIT_GUARD_VIEWPORTS`] of the viewport.
pub(super) fn within_guard_band(view: &View, (lo, hi): (DVec3, DVec3)) -> bool {
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    let g = SPLIT_GUARD_VIEWPORTS * w.max(h);
    lo.x >= -g && lo.y >= -g && hi.x <= w + g && hi.y <= h + g
}

/// Builds a whole lembo from its six screen points.
pub(super) fn build_whole<R: Real>(
    id: u32,
    points: &ScreenPoints,
    lembo: &Lembo,
    color: [f64; 3],
) -> ScreenLembo<R> {
    build(id, points, lembo.normal, lembo.position, color, None)
}

/// Builds a piece of `lembo` over the sub-triangle `tri` of its domain from the piece's six
/// screen points: the lembo's normal and position functions restricted to the sub-triangle.
pub(super) fn build_piece<R: Real>(
    id: u32,
    points: &ScreenPoints,
    lembo: &Lembo,
    color: [f64; 3],
    tri: [[f64; 2]; 3],
) -> ScreenLembo<R> {
    let uv = reference_uv(tri);
    let restrict = |q: &Quadratic3<f64>| {
        [0, 1, 2].map(|c| Quadratic::from_reference_values(uv.map(|[u, v]| q[c].eval(u, v))))
    };
    build(
        id,
        points,
        restrict(&lembo.normal),
        restrict(&lembo.position),
        color,
        Some(tri),
    )
}

/// Builds the datapath form of a lembo (or piece) from its six screen points.
pub(super) fn build<R: Real>(
    id: u32,
    p: &ScreenPoints,
    normal: Quadratic3<f64>,
    position: Quadratic3<f64>,
    color: [f64; 3],
    domain: Option<[[f64; 2]; 3]>,
) -> ScreenLembo<R> {
    let sx = p.x.map(R::of);
    let sy = p.y.map(R::of);
    let x = Quadratic::from_reference_values(sx);
    let y = Quadratic::from_reference_values(sy);
    let z = Quadratic::from_reference_values(p.z.map(R::of));
    let edges = EDGE_POINTS.map(|[s, m, e]| {
        // Canonical order: the end with the smaller (y, x) first.
        let reversed = (sy[e], sx[e]) < (sy[s], sx[s]);
        let (s, e) = if reversed { (e, s) } else { (s, e) };
        EdgeCurve::new([sy[s], sy[m], sy[e]], [sx[s], sx[m], sx[e]], reversed)
    });
    let hessian = y.hessian();
    ScreenLembo {
        id,
        x,
        partition: partition(&y),
        y,
        z,
        normal: normal.map(|q| q.cast()),
        position: position.map(|q| q.cast()),
        color: color.map(R::of),
        edges,
        vertex_y: [sy[0], sy[1], sy[2]],
        hessian,
        domain,
    }
}

/// Chooses the walk partition of the domain for the level curves of `y`.
pub fn partition<R: Real>(y: &Quadratic<R>) -> Partition<R> {
    let corners = [
        [R::zero(), R::zero()],
        [R::one(), R::zero()],
        [R::zero(), R::one()],
    ];
    let g = corners.map(|[u, v]| {
        let (gu, gv) = y.grad(u, v);
        [gu, gv]
    });
    let scale = g.iter().map(|g| norm(*g)).fold(R::zero(), R::max);
    let eps = R::epsilon() * R::of(64.0);
    if let Some(c) = closest_to_origin(g) {
        let d = norm(c);
        if d > eps * scale {
            let a = [c[0] / d, c[1] / d];
            let (a0, a1) = (a[0].f64(), a[1].f64());
            let along = g.map(|[gu, gv]| a0 * gu.f64() + a1 * gv.f64());
            let length = g.map(|[gu, gv]| gu.f64().hypot(gv.f64()));
            let finite = along.iter().chain(&length).all(|x| x.is_finite());
            return Partition::Monotone {
                a,
                grad_bounds: if finite {
                    [
                        R::of(along[0].min(along[1]).min(along[2])),
                        R::of(length[0].max(length[1]).max(length[2])),
                    ]
                } else {
                    [R::nan(); 2]
                },
            };
        }
    }
    let (huu, huv, hvv) = y.hessian();
    let det = huu * hvv - huv * huv;
    let h_scale = huu.abs().max(huv.abs()).max(hvv.abs());
    let eig = eigen_sym(huu, huv, hvv);
    if h_scale > R::zero() && det.abs() > R::of(1e3) * R::epsilon() * h_scale * h_scale {
        // Cramer's rule for ∇y = 0.
        let uc = (huv * y.e - hvv * y.d) / det;
        let vc = (huv * y.d - huu * y.e) / det;
        return Partition::Central {
            centre: [uc, vc],
            y_centre: y.eval(uc, vc),
            det,
            eig,
        };
    }
    Partition::Valley { a: eig[0].0 }
}

/// The point of the triangle `t` nearest the origin, or `None` if the origin is inside.
fn closest_to_origin<R: Real>(t: [V2<R>; 3]) -> Option<V2<R>> {
    let cross = |a: V2<R>, b: V2<R>| a[0] * b[1] - a[1] * b[0];
    let sub = |a: V2<R>, b: V2<R>| [a[0] - b[0], a[1] - b[1]];
    let o = [R::zero(), R::zero()];
    let s = [
        cross(sub(t[1], t[0]), sub(o, t[0])),
        cross(sub(t[2], t[1]), sub(o, t[1])),
        cross(sub(t[0], t[2]), sub(o, t[2])),
    ];
    let zero = R::zero();
    let inside = (s[0] >= zero && s[1] >= zero && s[2] >= zero)
        || (s[0] <= zero && s[1] <= zero && s[2] <= zero);
    let area = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    if inside && area != zero {
        return None;
    }
    let seg = |a: V2<R>, b: V2<R>| {
        let ab = sub(b, a);
        let l = dot(ab, ab);
        let t = if l > zero {
            (-dot(a, ab) / l).max(zero).min(R::one())
        } else {
            zero
        };
        [a[0] + t * ab[0], a[1] + t * ab[1]]
    };
    let c = [seg(t[0], t[1]), seg(t[1], t[2]), seg(t[2], t[0])];
    let best = c
        .into_iter()
        .fold(c[0], |b, p| if dot(p, p) < dot(b, b) { p } else { b });
    // A degenerate gradient triangle through the origin has no separating direction.
    if dot(best, best) == zero {
        None
    } else {
        Some(best)
    }
}

/// Unit eigenvectors and eigenvalues of [[p, q], [q, r]], larger |λ| first.
pub fn eigen_sym<R: Real>(p: R, q: R, r: R) -> [(V2<R>, R); 2] {
    let half = R::of(0.5);
    let m = (p + r) * half;
    let dd = ((p - r) * half).length(q);
    let (l1, l2) = (m + dd, m - dd);
    let vec = |l: R| {
        let a = [q, l - p];
        let b = [l - r, q];
        let v = if dot(a, a) >= dot(b, b) { a } else { b };
        let n = norm(v);
        if n > R::zero() {
            [v[0] / n, v[1] / n]
        } else if (l - p).abs() <= (l - r).abs() {
            [R::one(), R::zero()]
        } else {
            [R::zero(), R::one()]
        }
    };
    let (v1, v2) = (vec(l1), vec(l2));
    // Keep the pair orthogonal even when the eigenvalues coincide.
    let v2 = if dot(v1, v2).abs() > R::of(0.5) {
        [-v1[1], v1[0]]
    } else {
        v2
    };
    if l1.abs() >= l2.abs() {
        [(v1, l1), (v2, l2)]
    } else {
        [(v2, l2), (v1, l1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::setup::tests::{quad, screen_lembo, x_linear, y_plane};

    #[test]
    fn canonical_edges_start_at_the_smaller_end() {
        // y = 10 + 60u + 30v: A = 10, B = 70, C = 40; x = 20 + 80u + 30v.
        let l = screen_lembo::<f32>(x_linear(), y_plane());
        assert_eq!(l.vertex_y, [10.0, 70.0, 40.0]);
        assert_eq!(l.edges.map(|c| c.reversed), [false, true, true]);
        assert_eq!(
            l.edges.map(|c| c.y),
            [[10.0, 40.0, 70.0], [40.0, 55.0, 70.0], [10.0, 25.0, 40.0]]
        );
        assert_eq!(
            l.edges.map(|c| c.x),
            [[20.0, 60.0, 100.0], [50.0, 75.0, 100.0], [20.0, 35.0, 50.0]]
        );
    }

    #[test]
    fn zero_area_does_not_depend_on_the_scale_of_either_axis() {
        // A curved parametrisation of a parabola, x = 0.7 t, y = 0.3 + 0.9 t² with
        // t = 0.37 u + 0.61 v (zero Jacobian everywhere, up to the rounding of its
        // inexact coefficients), and the same with y tilted by 10⁻⁶ of its size along u:
        // a sliver, thin but with area.
        let point = |(u, v): (f64, f64), tilt: f64| {
            let t = 0.37 * u + 0.61 * v;
            (0.7 * t, 0.3 + 0.9 * t * t + tilt * u)
        };
        for (tilt, degenerate) in [(0.0, true), (1e-6, false)] {
            for sx in [1e-4, 1.0, 1e4] {
                for sy in [1e-4, 1.0, 1e4] {
                    let p = REFERENCE_UV.map(|uv| point(uv, tilt));
                    let (x, y) = (p.map(|p| p.0 * sx), p.map(|p| p.1 * sy));
                    assert_eq!(zero_area(x, y), degenerate, "tilt {tilt}, scales {sx} {sy}");
                }
            }
        }
    }

    #[test]
    fn a_hull_touching_the_viewport_or_the_depth_range_is_not_outside() {
        let view = crate::raster::setup::tests::view();
        let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
        let hull = |lo: [f64; 3], hi: [f64; 3]| (DVec3::from(lo), DVec3::from(hi));
        assert!(!outside(&view, hull([1.0, 1.0, 0.25], [3.0, 2.0, 0.75])));
        // Per side of the viewport and of the depth range [0, 1]: a hull whose face lies
        // on the side from outside (the side's pixels or depths are still in reach), and
        // the same hull moved 10⁻⁹ further out.
        let d = 1e-9;
        for (side, [touching, beyond]) in [
            (
                "left",
                [0.0, -d].map(|x| hull([x - 2.0, 1.0, 0.25], [x, 2.0, 0.75])),
            ),
            (
                "top",
                [0.0, -d].map(|y| hull([1.0, y - 2.0, 0.25], [3.0, y, 0.75])),
            ),
            (
                "right",
                [w, w + d].map(|x| hull([x, 1.0, 0.25], [x + 2.0, 2.0, 0.75])),
            ),
            (
                "bottom",
                [h, h + d].map(|y| hull([1.0, y, 0.25], [3.0, y + 2.0, 0.75])),
            ),
            (
                "near",
                [0.0, -d].map(|z| hull([1.0, 1.0, z - 0.5], [3.0, 2.0, z])),
            ),
            (
                "far",
                [1.0, 1.0 + d].map(|z| hull([1.0, 1.0, z], [3.0, 2.0, z + 0.5])),
            ),
        ] {
            assert!(!outside(&view, touching), "touching the {side}");
            assert!(outside(&view, beyond), "beyond the {side}");
        }
    }

    #[test]
    fn a_hull_reaching_the_guard_band_is_within_it() {
        let view = crate::raster::setup::tests::view();
        let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
        let g = SPLIT_GUARD_VIEWPORTS * w.max(h);
        let hull = |lo: [f64; 2], hi: [f64; 2]| {
            (DVec3::new(lo[0], lo[1], 0.5), DVec3::new(hi[0], hi[1], 0.5))
        };
        // The whole band, and per side a hull reaching exactly the band's edge (within),
        // then 10⁻⁶ past it (not within).
        assert!(within_guard_band(&view, hull([-g, -g], [w + g, h + g])));
        let d = 1e-6;
        for (side, [reaching, past]) in [
            ("left", [-g, -g - d].map(|x| hull([x, 1.0], [3.0, 2.0]))),
            ("top", [-g, -g - d].map(|y| hull([1.0, y], [3.0, 2.0]))),
            (
                "right",
                [w + g, w + g + d].map(|x| hull([1.0, 1.0], [x, 2.0])),
            ),
            (
                "bottom",
                [h + g, h + g + d].map(|y| hull([1.0, 1.0], [3.0, y])),
            ),
        ] {
            assert!(within_guard_band(&view, reaching), "reaching the {side}");
            assert!(!within_guard_band(&view, past), "past the {side}");
        }
    }

    #[test]
    fn reference_uv_is_the_corners_then_the_edge_middles_in_the_papers_order() {
        let whole = reference_uv([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
        assert_eq!(whole, REFERENCE_UV.map(|(u, v)| [u, v]));
        // A piece: corners A, B, C, then the middles of AB, CA and BC.
        let piece = reference_uv([[0.25, 0.5], [0.5, 0.25], [0.25, 0.25]]);
        assert_eq!(
            piece,
            [
                [0.25, 0.5],
                [0.5, 0.25],
                [0.25, 0.25],
                [0.375, 0.375],
                [0.25, 0.375],
                [0.375, 0.25],
            ]
        );
    }

    /// The parabola through three points is each of them at t = 0, ½ and 1, bit for bit,
    /// and the quadratic through them in between (each coordinate on its own).
    #[test]
    fn the_parabola_passes_through_its_three_points_and_is_their_quadratic_between() {
        let p = [[10.3, -20.7], [90.1, 30.9], [40.7, 100.3]];
        for (t, want) in [(0.0, p[0]), (0.5, p[1]), (1.0, p[2])] {
            assert_eq!(parabola(&p, t), want, "t = {t}");
        }
        for t in [0.25, 0.75, 0.1, 1.5] {
            // Newton's form of the same quadratic.
            let want: [f64; 2] = std::array::from_fn(|c| {
                let d1 = 2.0 * (p[1][c] - p[0][c]);
                let d2 = 2.0 * (p[2][c] - 2.0 * p[1][c] + p[0][c]);
                p[0][c] + t * d1 + t * (t - 0.5) * d2
            });
            let got = parabola(&p, t);
            for c in 0..2 {
                assert!(
                    (got[c] - want[c]).abs() <= 1e-12 * want[c].abs(),
                    "t = {t}: {got:?} {want:?}"
                );
            }
        }
    }

    #[test]
    fn partition_is_monotone_when_the_gradient_keeps_a_side() {
        // y = 10u + 3v + 2u²: gradient (10 + 4u, 3), never zero.
        match partition(&quad(2.0, 0.0, 0.0, 10.0, 3.0, 0.0)) {
            Partition::Monotone { a, .. } => {
                for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.3)] {
                    let (gu, gv) = quad(2.0, 0.0, 0.0, 10.0, 3.0, 0.0).grad(u, v);
                    assert!(a[0] * gu + a[1] * gv > 0.0);
                }
            }
            p => panic!("{p:?}"),
        }
    }

    /// The gradient hull counts as clear of the origin only beyond 64 ulp of its scale: the
    /// bowl (u + δ)² + v², its minimum δ outside the edge u = 0, has corner gradients
    /// (2δ, 0), (2 + 2δ, 0) and (2δ, 2), a hull 2δ from the origin against a threshold of
    /// 64 ε (2 + 2δ) ≈ 2.8·10⁻¹⁴. At δ = 2⁻⁴⁷ (2δ ≈ 1.4·10⁻¹⁴, rounding) it is walked from
    /// its centre; at δ = 2⁻⁴⁰ (2δ ≈ 1.8·10⁻¹²) as monotone.
    #[test]
    fn a_gradient_hull_within_rounding_of_the_origin_is_not_monotone() {
        let bowl = |delta: f64| quad(1.0, 1.0, 0.0, 2.0 * delta, 0.0, delta * delta);
        match partition(&bowl(2f64.powi(-47))) {
            Partition::Central { centre, det, .. } => {
                assert_eq!((centre, det), ([-(2f64.powi(-47)), 0.0], 4.0));
            }
            p => panic!("{p:?}"),
        }
        match partition(&bowl(2f64.powi(-40))) {
            Partition::Monotone { a, .. } => assert_eq!(a, [1.0, 0.0]),
            p => panic!("{p:?}"),
        }
    }

    /// The partition of a bowl and of a saddle does not depend on their scale: the same
    /// centre from 10⁻⁸ to 10⁸ times the curvature (the threshold on the determinant scales
    /// with the Hessian's square, as the determinant does).
    #[test]
    fn partition_does_not_depend_on_the_scale_of_y() {
        for scale in [1e-8, 1e-3, 0.1, 1.0, 10.0, 1e3, 1e8] {
            for sign in [1.0, -1.0] {
                let y = quad(
                    scale,
                    sign * scale,
                    0.0,
                    -0.6 * scale,
                    -0.6 * sign * scale,
                    0.0,
                );
                match partition(&y) {
                    Partition::Central { centre, det, .. } => {
                        assert!((centre[0] - 0.3).abs() < 1e-12 && (centre[1] - 0.3).abs() < 1e-12);
                        assert_eq!(det.signum(), sign, "scale {scale}");
                    }
                    p => panic!("scale {scale}, sign {sign}: {p:?}"),
                }
            }
        }
    }

    /// An isotropic Hessian (a multiple of the identity, zero included) has every direction
    /// for an eigenvector: `eigen_sym` gives the axes, u first. One isotropic within
    /// rounding (p = r, q a few ulps of p) has every direction for an eigenvector within
    /// rounding, and may compute two nearly parallel vectors: the second is then the first
    /// turned a quarter, so the pair is never within 60° (|cos| <= ½), and exactly
    /// orthogonal where turned.
    #[test]
    fn an_isotropic_hessians_eigenvectors_are_the_axes() {
        for c in [0.0, 1.0, -2.0] {
            assert_eq!(
                eigen_sym(c, 0.0, c),
                [([1.0, 0.0], c), ([0.0, 1.0], c)],
                "{c} times the identity"
            );
        }
        let mut rng = crate::testkit::SplitMix64::new(7);
        let mut turned = 0;
        for _ in 0..10_000 {
            let p = rng.range(-2.0, 2.0);
            let q = p * rng.range(-4.0, 4.0) * f64::EPSILON;
            let [(v1, _), (v2, _)] = eigen_sym(p, q, p);
            for v in [v1, v2] {
                assert!((dot(v, v) - 1.0).abs() < 1e-12, "{p} {q}: {v:?}");
            }
            assert!(dot(v1, v2).abs() <= 0.5, "{p} {q}: {v1:?} {v2:?}");
            turned += (dot(v1, v2) == 0.0 && v1[0] * v1[1] != 0.0) as u32;
        }
        assert!(turned > 100, "{turned} of 10 000 pairs turned off the axes");
    }

    #[test]
    fn partition_finds_an_interior_extremum_and_a_saddle() {
        // Minimum of (u - .3)² + (v - .3)² at (.3, .3).
        let bowl = quad(1.0, 1.0, 0.0, -0.6, -0.6, 0.18);
        match partition(&bowl) {
            Partition::Central { centre, det, .. } => {
                assert!(
                    (centre[0] - 0.3).abs() < 1e-12 && (centre[1] - 0.3).abs() < 1e-12 && det > 0.0
                )
            }
            p => panic!("{p:?}"),
        }
        // Saddle (u - .3)² - (v - .3)².
        match partition(&quad(1.0, -1.0, 0.0, -0.6, 0.6, 0.0)) {
            Partition::Central { det, y_centre, .. } => {
                assert!(det < 0.0 && y_centre.abs() < 1e-12)
            }
            p => panic!("{p:?}"),
        }
    }

    #[test]
    fn partition_of_a_valley_is_along_the_curvature() {
        // y = 50 (u - v)²: zero gradient along u = v, singular Hessian.
        match partition(&quad(50.0, 50.0, -100.0, 0.0, 0.0, 0.0)) {
            Partition::Valley { a } => assert!((a[0] + a[1]).abs() < 1e-12),
            p => panic!("{p:?}"),
        }
    }

    #[test]
    fn eigen_decomposition_is_orthonormal() {
        for (p, q, r) in [
            (2.0, 0.5, -1.0),
            (1.0, 0.0, 1.0),
            (0.0, 3.0, 0.0),
            (5.0, 0.0, 0.0),
        ] {
            let e = eigen_sym::<f64>(p, q, r);
            for (v, l) in e {
                let hv = [p * v[0] + q * v[1], q * v[0] + r * v[1]];
                assert!((hv[0] - l * v[0]).abs() < 1e-12 && (hv[1] - l * v[1]).abs() < 1e-12);
            }
            assert!(dot(e[0].0, e[1].0).abs() < 1e-12);
            assert!(e[0].1.abs() >= e[1].1.abs());
        }
    }
}
