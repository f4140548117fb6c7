//! Setup: projects a lembo's six points, rebuilds screen-space coefficients, and prepares
//! what the later stages need once per lembo (paper 001 sections 4 and 5).
//!
//! Input: a world-space [`Lembo`], its colour and the [`View`]. Output: a [`ScreenLembo`]
//! in the datapath precision, or `None` when the lembo is culled (a control point behind
//! the eye, or its Bézier hull entirely outside the viewport or the depth range): one cull
//! test per primitive.
//!
//! The paper assumes the projection is already applied (section 4); we project the six
//! reference points and rebuild the quadratics with the paper's transform. Under perspective
//! this approximates the projected surface; the reference renders the true one, so the
//! approximation shows up in the accuracy report rather than being hidden.
//!
//! Setup also prepares the *walk partition* of the domain used to pair edge roots into
//! intervals (see `interval.rs`): a direction `a` such that `a·∇Y > 0` on each of at most two
//! convex parts of the domain, split by the line `a·∇Y = 0`. Inside such a part every level
//! curve `Y = y_j` is a graph over `rot_cw(a)`, so the position along that direction orders
//! the curve's points in walking order.

use super::v2::{dot, norm, V2};
use crate::camera::View;
use crate::datapath::Real;
use crate::lembo::{bezier_controls, Lembo, Quadratic, Quadratic3, REFERENCE_UV};
use glam::DVec3;

/// One domain edge in canonical order: the screen values of its start, middle and end
/// points, ordered so that two lembos sharing the edge compute bit-identical roots.
#[derive(Clone, Copy, Debug)]
pub struct EdgeCurve<R> {
    /// Screen y at canonical t = 0, 1/2, 1 [pixels].
    pub y: [R; 3],
    /// Screen x at canonical t = 0, 1/2, 1 [pixels].
    pub x: [R; 3],
    /// Whether canonical t runs against the lembo's edge direction.
    pub reversed: bool,
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
    Monotone { a: V2<R> },
    /// `∇Y` vanishes at an isolated point of the domain (an interior extremum if `det > 0`,
    /// a saddle if `det < 0`): the domain is split by the line `a·∇Y = 0`, with `a` chosen per
    /// scanline for saddles (the transverse axis of the hyperbola).
    Central {
        /// The critical point (u, v).
        centre: V2<R>,
        /// Screen y at the critical point [pixels].
        y_centre: R,
        /// Determinant of the Hessian of y.
        det: R,
        /// Unit eigenvectors of the Hessian and their eigenvalues, larger |λ| first.
        eig: [(V2<R>, R); 2],
    },
    /// The Hessian is (nearly) singular and `∇Y` vanishes along a line through the domain
    /// (a valley): level curves are near-parallel lines on either side of it.
    Valley { a: V2<R> },
}

/// A lembo ready for the scan-line stages, in datapath precision.
#[derive(Clone, Debug)]
pub struct ScreenLembo<R> {
    /// Global id (scene order), also the depth-test tie breaker.
    pub id: u32,
    /// Screen x [pixels], y [pixels] and depth [0, 1] as quadratics in (u, v).
    pub x: Quadratic<R>,
    pub y: Quadratic<R>,
    pub z: Quadratic<R>,
    /// World-space normal function (normalise per fragment).
    pub normal: Quadratic3<R>,
    /// World-space position function (for the per-fragment direction to the eye).
    pub position: Quadratic3<R>,
    /// Material colour, linear RGB.
    pub color: [R; 3],
    /// The three domain edges in canonical order.
    pub edges: [EdgeCurve<R>; 3],
    /// Screen y of the three vertices A, B, C [pixels] (shared bit-identically with
    /// neighbours).
    pub vertex_y: [R; 3],
    /// Hessian of y: (y_uu, y_uv, y_vv).
    pub hessian: (R, R, R),
    pub partition: Partition<R>,
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
fn zero_area(sx: [f64; 6], sy: [f64; 6]) -> bool {
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

/// Projects and prepares one lembo.
pub fn setup<R: Real>(
    id: u32,
    lembo: &Lembo,
    color: [f64; 3],
    view: &View,
) -> Result<ScreenLembo<R>, Cull> {
    let screen = lembo.points.map(|p| view.project(p));
    if screen
        .iter()
        .any(|s| s.w <= 0.0 || !s.x.is_finite() || !s.y.is_finite())
    {
        return Err(Cull::BehindEye);
    }
    // The screen-space quadratic through the six projected points lies in the convex hull of
    // its own Bézier net.
    let net = bezier_controls(&screen.map(|s| DVec3::new(s.x, s.y, s.depth)));
    let (lo, hi) = net.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    if hi.x < 0.0 || hi.y < 0.0 || lo.x > w || lo.y > h || hi.z < 0.0 || lo.z > 1.0 {
        return Err(Cull::Outside);
    }
    if zero_area(screen.map(|s| s.x), screen.map(|s| s.y)) {
        return Err(Cull::Degenerate);
    }

    let sx = screen.map(|s| R::of(s.x));
    let sy = screen.map(|s| R::of(s.y));
    let x = Quadratic::from_reference_values(sx);
    let y = Quadratic::from_reference_values(sy);
    let z = Quadratic::from_reference_values(screen.map(|s| R::of(s.depth)));
    let edges = EDGE_POINTS.map(|[s, m, e]| {
        // Canonical order: the end with the smaller (y, x) first.
        let reversed = (sy[e], sx[e]) < (sy[s], sx[s]);
        let (s, e) = if reversed { (e, s) } else { (s, e) };
        EdgeCurve {
            y: [sy[s], sy[m], sy[e]],
            x: [sx[s], sx[m], sx[e]],
            reversed,
        }
    });
    let hessian = y.hessian();
    Ok(ScreenLembo {
        id,
        x,
        partition: partition(&y),
        y,
        z,
        normal: lembo.normal.map(|q| q.cast()),
        position: lembo.position.map(|q| q.cast()),
        color: color.map(R::of),
        edges,
        vertex_y: [sy[0], sy[1], sy[2]],
        hessian,
    })
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
            return Partition::Monotone {
                a: [c[0] / d, c[1] / d],
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
    let dd = ((p - r) * half).hypot(q);
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

/// Fixtures shared by the unit tests of the raster stages: lembos whose screen projection is
/// chosen exactly, so each test can put a scanline where the case it checks happens.
#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::lembo::REFERENCE_UV;
    use crate::raster::Counts;

    pub(crate) fn quad(a: f64, b: f64, c: f64, d: f64, e: f64, f: f64) -> Quadratic<f64> {
        Quadratic { a, b, c, d, e, f }
    }

    /// Side of the test viewport [pixels].
    pub(crate) const SIDE: u32 = 128;

    /// A 128 x 128 orthographic view down -z, 128 world units high: world (X, Y, Z) lands on
    /// screen (X + 64, 64 - Y), exactly for values with few binary digits.
    pub(crate) fn view() -> View {
        let camera = Camera {
            eye: [0.0, 0.0, 10.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Orthographic {
                height: SIDE as f64,
                near: 0.1,
                far: 100.0,
            },
        };
        View::new(
            &camera,
            Viewport {
                width: SIDE,
                height: SIDE,
            },
        )
    }

    /// A lembo whose screen x and y [pixels] are the quadratics `x` and `y` in the test view,
    /// with depth growing along u + v and normals towards the eye.
    pub(crate) fn lembo_on_screen(x: Quadratic<f64>, y: Quadratic<f64>) -> Lembo {
        let points = REFERENCE_UV
            .map(|(u, v)| DVec3::new(x.eval(u, v) - 64.0, 64.0 - y.eval(u, v), -(u + v)));
        Lembo::new(points, [DVec3::Z; 6])
    }

    /// The [`ScreenLembo`] of [`lembo_on_screen`].
    pub(crate) fn screen_lembo<R: Real>(x: Quadratic<f64>, y: Quadratic<f64>) -> ScreenLembo<R> {
        setup::<R>(0, &lembo_on_screen(x, y), [0.8; 3], &view())
            .expect("the fixture is inside the view")
    }

    /// Screen x of the fixtures: linear, so x never folds by itself.
    pub(crate) fn x_linear() -> Quadratic<f64> {
        quad(0.0, 0.0, 0.0, 80.0, 30.0, 20.0)
    }

    /// y = 40.3 + 100 ((u - .3)² + (v - .3)²): a bowl with its minimum 40.3 at (.3, .3), so
    /// scanline 40 (y = 40.5) is a small closed loop touching no domain edge.
    pub(crate) fn y_bowl() -> Quadratic<f64> {
        quad(100.0, 100.0, 0.0, -60.0, -60.0, 58.3)
    }

    /// y = 50.3 + 100 ((u - .3)² - (v - .3)²): a saddle at (.3, .3) with value 50.3, so
    /// scanline 50 (y = 50.5) is within k/2 of it for k = 0.5.
    pub(crate) fn y_saddle() -> Quadratic<f64> {
        quad(100.0, -100.0, 0.0, -60.0, 60.0, 50.3)
    }

    /// y = 10 + 60u + 30v: a plane (straight level lines, no curvature).
    pub(crate) fn y_plane() -> Quadratic<f64> {
        quad(0.0, 0.0, 0.0, 60.0, 30.0, 10.0)
    }

    /// A fragment sink that keeps (pixel i, u, v) of every fragment.
    #[derive(Default)]
    pub(crate) struct Collect<R>(pub(crate) Vec<(u32, R, R)>);

    impl<R: Real> crate::raster::fragment::FragmentSink<R> for Collect<R> {
        fn fragment(
            &mut self,
            _: &ScreenLembo<R>,
            _: &crate::raster::subsegmenter::Subsegment<R>,
            i: u32,
            _: u32,
            u: R,
            v: R,
            _: R,
        ) {
            self.0.push((i, u, v));
        }
    }

    /// Every fragment (i, u, v) of scanline `j` of `l`, through all the stages at tolerance
    /// `k` [pixels], with the stages' counts.
    pub(crate) fn scanline_fragments<R: Real>(
        l: &ScreenLembo<R>,
        j: u32,
        k: f64,
    ) -> (Vec<(u32, R, R)>, Counts) {
        use crate::raster::{fragment, interval, segmenter, subsegmenter, DEFAULT_SEGMENT_CAP};
        let (k, mut counts, mut sink) = (R::of(k), Counts::default(), Collect::default());
        let (mut ivs, mut segs, mut subs) = (Vec::new(), Vec::new(), Vec::new());
        interval::intervals(
            l,
            j,
            k,
            &mut interval::IntervalScratch::default(),
            &mut ivs,
            &mut counts,
        );
        for iv in &ivs {
            segs.clear();
            segmenter::segments(l, j, k, iv, DEFAULT_SEGMENT_CAP, &mut segs, &mut counts)
                .expect("under the cap");
            for seg in &segs {
                subs.clear();
                subsegmenter::subsegments(l, seg, k, &mut subs, &mut counts);
                for sub in &subs {
                    fragment::rasterize(l, j, sub, SIDE, &mut sink, &mut counts);
                }
            }
        }
        (sink.0, counts)
    }

    /// |y(u, v) - (j + 0.5)| in f64 [pixels].
    pub(crate) fn y_error<R: Real>(l: &ScreenLembo<R>, j: u32, uv: [R; 2]) -> f64 {
        (l.y.cast::<f64>().eval(uv[0].f64(), uv[1].f64()) - (j as f64 + 0.5)).abs()
    }

    #[test]
    fn fixtures_project_exactly() {
        let l = screen_lembo::<f64>(x_linear(), y_bowl());
        for (got, want) in [(l.y, y_bowl()), (l.x, x_linear())] {
            for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.3), (0.2, 0.7)] {
                assert!((got.eval(u, v) - want.eval(u, v)).abs() < 1e-12, "{u} {v}");
            }
        }
        match l.partition {
            Partition::Central {
                centre,
                y_centre,
                det,
                ..
            } => {
                assert!((centre[0] - 0.3).abs() < 1e-12 && (centre[1] - 0.3).abs() < 1e-12);
                assert!((y_centre - 40.3).abs() < 1e-12 && det > 0.0);
            }
            p => panic!("{p:?}"),
        }
    }

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
    fn partition_is_monotone_when_the_gradient_keeps_a_side() {
        // y = 10u + 3v + 2u²: gradient (10 + 4u, 3), never zero.
        match partition(&quad(2.0, 0.0, 0.0, 10.0, 3.0, 0.0)) {
            Partition::Monotone { a } => {
                for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.3)] {
                    let (gu, gv) = quad(2.0, 0.0, 0.0, 10.0, 3.0, 0.0).grad(u, v);
                    assert!(a[0] * gu + a[1] * gv > 0.0);
                }
            }
            p => panic!("{p:?}"),
        }
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

    #[test]
    fn setup_culls_lembos_of_zero_area_and_keeps_thin_ones() {
        // A curved parametrisation of a parabola: x = 20 + 80 t, y = 30 + 40 t² with
        // t = u + v. Its Jacobian is zero everywhere, so it covers no pixel centre.
        let t = quad(1.0, 1.0, 2.0, 0.0, 0.0, 0.0); // (u + v)²
        let x = quad(0.0, 0.0, 0.0, 80.0, 80.0, 20.0);
        let y = quad(40.0 * t.a, 40.0 * t.b, 40.0 * t.c, 0.0, 0.0, 30.0);
        let l = lembo_on_screen(x, y);
        assert_eq!(
            setup::<f64>(0, &l, [0.8; 3], &view()).err(),
            Some(Cull::Degenerate)
        );
        assert_eq!(
            setup::<f32>(0, &l, [0.8; 3], &view()).err(),
            Some(Cull::Degenerate)
        );
        // A sliver a hundredth of a pixel wide over 80 pixels is not degenerate.
        let thin = quad(0.0, 0.0, 0.0, 0.0, 0.01, 30.0);
        let l = lembo_on_screen(quad(0.0, 0.0, 0.0, 80.0, 0.0, 20.0), thin);
        assert!(setup::<f64>(0, &l, [0.8; 3], &view()).is_ok());
    }
}
