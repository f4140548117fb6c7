//! Setup: projects a lembo's six points, rebuilds screen-space coefficients, and prepares
//! what the later stages need once per lembo (Martinelli 2006 sections 4 and 5).
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
//! intervals ([`Partition`](super::screen::Partition)).
//!
//! This file holds Setup's entry points ([`setup`], [`setup_pieces`]) and the guard-band
//! split; what a set-up lembo is and how it is built from six screen points are in
//! `screen.rs`, on which the perspective split (`refine.rs`) builds too.

use super::screen::{
    build_piece, build_whole, on_domain_edge, outside, parabola, reference_uv, within_guard_band,
    zero_area, ScreenPoints, EDGE_POINTS, MAX_PIECES, MAX_SPLIT_DEPTH,
};
pub use super::screen::{Cull, ScreenLembo, Split};
use crate::camera::View;
use crate::datapath::Real;
use crate::lembo::{Lembo, Quadratic};

/// Projects the six points and applies the culls every lembo gets: behind the eye, outside,
/// zero area.
fn project(lembo: &Lembo, view: &View) -> Result<ScreenPoints, Cull> {
    let screen = lembo.points.map(|p| view.project(p));
    if screen
        .iter()
        .any(|s| s.w <= 0.0 || !s.x.is_finite() || !s.y.is_finite())
    {
        return Err(Cull::BehindEye);
    }
    let points = ScreenPoints {
        x: screen.map(|s| s.x),
        y: screen.map(|s| s.y),
        z: screen.map(|s| s.depth),
    };
    // The screen-space quadratic through the six projected points lies in the convex hull of
    // its own Bézier net.
    if outside(view, points.hull()) {
        return Err(Cull::Outside);
    }
    if zero_area(points.x, points.y) {
        return Err(Cull::Degenerate);
    }
    Ok(points)
}

/// Projects and prepares one lembo, whole (whatever its size; see [`setup_pieces`]).
pub fn setup<R: Real>(
    id: u32,
    lembo: &Lembo,
    color: [f64; 3],
    view: &View,
) -> Result<ScreenLembo<R>, Cull> {
    let points = project(lembo, view)?;
    Ok(build_whole(id, &points, lembo, color))
}

/// Projects and prepares one lembo into `out`: whole when its Bézier hull stays within
/// [`SPLIT_GUARD_VIEWPORTS`](super::screen::SPLIT_GUARD_VIEWPORTS) of the viewport (bit for bit what [`setup`] gives), otherwise
/// split.
///
/// Splitting halves the domain recursively into four sub-triangles, drops those whose hull
/// misses the viewport and keeps those within the guard band. A piece is the same screen
/// quadratics restricted to a sub-triangle (they are evaluated at its six reference points
/// and rebuilt with the paper's transform), so the pieces draw the lembo's own surface;
/// points on the lembo's domain edges are evaluated from the edge's three points in
/// canonical order, as the whole edge is, so a neighbour sharing the edge sees the same
/// curve. Pieces keep the lembo's id (the depth-test tie breaker) and carry their corners
/// in the lembo's domain ([`ScreenLembo::domain`]).
///
/// With a perspective tolerance (`Some(tol)` \[pixels\]) Setup also splits until every piece
/// is within `tol` of the true projection and handles the near plane ([`super::refine`]);
/// `None` is the paper's Setup, as described here.
pub fn setup_pieces<R: Real>(
    id: u32,
    lembo: &Lembo,
    color: [f64; 3],
    view: &View,
    perspective_tol: Option<f64>,
    out: &mut Vec<ScreenLembo<R>>,
) -> Result<Split, Cull> {
    // An orthographic projection is affine: the rebuilt quadratics are the true image.
    if let (Some(tol), false) = (perspective_tol, view.orthographic) {
        return super::refine::setup_refined(id, lembo, color, view, tol, out);
    }
    let points = project(lembo, view)?;
    let within = |hull| within_guard_band(view, hull);
    if within(points.hull()) {
        out.push(build_whole(id, &points, lembo, color));
        return Ok(Split::default());
    }
    let surface = Restrict::new(&points);
    let mut split = Split::default();
    let mut pending = vec![([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 0u32)];
    let first = out.len();
    while let Some((tri, depth)) = pending.pop() {
        let full = out.len() - first + pending.len() >= MAX_PIECES;
        if depth > 0 {
            split.examined += 1;
        }
        let uv = reference_uv(tri);
        let piece = surface.points(&uv);
        let hull = piece.hull();
        if depth > 0 && outside(view, hull) {
            split.culled += 1;
            continue;
        }
        if depth > 0 && (within(hull) || depth >= MAX_SPLIT_DEPTH || full) {
            out.push(build_piece(id, &piece, lembo, color, tri));
            continue;
        }
        let [a, b, c] = tri;
        let [_, _, _, ab, ca, bc] = uv;
        // Pushed in reverse, so pieces come out in the order A, B, C, middle.
        for child in [[bc, ca, ab], [ca, bc, c], [ab, b, bc], [a, ab, ca]] {
            pending.push((child, depth + 1));
        }
    }
    Ok(split)
}

/// A lembo's screen quadratics restricted to sub-triangles of its domain.
struct Restrict {
    x: Quadratic<f64>,
    y: Quadratic<f64>,
    z: Quadratic<f64>,
    /// Per domain edge in lembo order: (x, y, z) at canonical t = 0, 1/2, 1, and whether
    /// canonical t runs against the lembo's edge direction.
    edges: [([[f64; 3]; 3], bool); 3],
}

impl Restrict {
    fn new(p: &ScreenPoints) -> Self {
        let edges = EDGE_POINTS.map(|[s, m, e]| {
            let reversed = (p.y[e], p.x[e]) < (p.y[s], p.x[s]);
            let (s, e) = if reversed { (e, s) } else { (s, e) };
            ([s, m, e].map(|k| [p.x[k], p.y[k], p.z[k]]), reversed)
        });
        Restrict {
            x: Quadratic::from_reference_values(p.x),
            y: Quadratic::from_reference_values(p.y),
            z: Quadratic::from_reference_values(p.z),
            edges,
        }
    }

    /// (x, y, z) at domain point (u, v). On a domain edge the value comes from the edge's
    /// own parabola in canonical order (exact at the edge's three points), so every lembo
    /// that shares the edge computes the same bits there.
    fn at(&self, uv: [f64; 2]) -> [f64; 3] {
        match on_domain_edge(uv) {
            Some((e, t)) => {
                let (p, reversed) = &self.edges[e];
                parabola(p, if *reversed { 1.0 - t } else { t })
            }
            None => {
                let [u, v] = uv;
                [self.x.eval(u, v), self.y.eval(u, v), self.z.eval(u, v)]
            }
        }
    }

    fn points(&self, uv: &[[f64; 2]; 6]) -> ScreenPoints {
        let p = uv.map(|q| self.at(q));
        ScreenPoints {
            x: p.map(|p| p[0]),
            y: p.map(|p| p[1]),
            z: p.map(|p| p[2]),
        }
    }
}

/// Fixtures shared by the unit tests of the raster stages: lembos whose screen projection is
/// chosen exactly, so each test can put a scanline where the case it checks happens.
#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::lembo::REFERENCE_UV;
    use crate::raster::counts::Counts;
    use crate::raster::screen::{Partition, SPLIT_GUARD_VIEWPORTS};
    use crate::testkit::SplitMix64;
    use glam::DVec3;

    pub(crate) fn quad(a: f64, b: f64, c: f64, d: f64, e: f64, f: f64) -> Quadratic<f64> {
        Quadratic { a, b, c, d, e, f }
    }

    /// A lembo of the test view with random screen quadratics: linear parts of up to 90
    /// pixels and curved parts of up to `bend` pixels; `None` when setup drops it.
    pub(crate) fn random_lembo<R: Real>(rng: &mut SplitMix64, bend: f64) -> Option<ScreenLembo<R>> {
        let mut q = |f: f64| {
            let curve = [0; 3].map(|_| rng.range(-bend, bend));
            let linear = [0; 2].map(|_| rng.range(-90.0, 90.0));
            quad(curve[0], curve[1], curve[2], linear[0], linear[1], f)
        };
        let (x, y) = (q(64.0), q(64.0));
        setup::<R>(0, &lembo_on_screen(x, y), [0.8; 3], &view()).ok()
    }

    /// Side of the test viewport \[pixels\].
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

    /// A lembo whose screen x and y \[pixels\] are the quadratics `x` and `y` in the test view,
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
    /// `k` \[pixels\], with the stages' counts.
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
                    fragment::rasterize(
                        l,
                        j,
                        sub,
                        fragment::Columns::plain(SIDE),
                        &mut sink,
                        &mut counts,
                    );
                }
            }
        }
        (sink.0, counts)
    }

    /// |y(u, v) - (j + 0.5)| in f64 \[pixels\].
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
    fn lembos_sharing_an_edge_restrict_to_the_same_bits_on_it() {
        // Six screen points with inexact coordinates, and the same patch with A and B
        // swapped (points B, A, C, AB, BC, CA): its quadratics differ from the first's in
        // rounding, and it runs each edge the other way. Split points on an edge must come
        // out bit for bit alike from both, or the pieces either side of it would leave
        // gaps or overlaps.
        let p = [
            [10.3, 20.7, 0.31],
            [90.1, 30.9, 0.52],
            [40.7, 100.3, 0.77],
            [50.9, 21.3, 0.43],
            [22.1, 61.7, 0.55],
            [70.3, 70.1, 0.61],
        ];
        let a = Restrict::new(&ScreenPoints::of(&p));
        let b = Restrict::new(&ScreenPoints::of(&[p[1], p[0], p[2], p[3], p[5], p[4]]));
        for k in 0..=64 {
            let t = k as f64 / 64.0;
            // a's point (u, v) is b's (1 - u - v, v).
            for (ua, ub) in [
                ([t, 0.0], [1.0 - t, 0.0]),
                ([1.0 - t, t], [0.0, t]),
                ([0.0, 1.0 - t], [t, 1.0 - t]),
            ] {
                assert_eq!(
                    a.at(ua).map(f64::to_bits),
                    b.at(ub).map(f64::to_bits),
                    "{ua:?}"
                );
                // And they are the patch's points: exactly at the six reference points,
                // within rounding between them.
                let [u, v] = ua;
                let patch = [a.x.eval(u, v), a.y.eval(u, v), a.z.eval(u, v)];
                for (c, (got, want)) in a.at(ua).into_iter().zip(patch).enumerate() {
                    assert!((got - want).abs() <= 1e-12 * want.abs(), "{ua:?} {c}");
                }
            }
        }
        for (k, (u, v)) in REFERENCE_UV.into_iter().enumerate() {
            assert_eq!(a.at([u, v]), p[k], "reference point {k}");
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

    /// A curved lembo about 10⁶ px across whose corner region covers the test view.
    fn huge_lembo() -> Lembo {
        let x = quad(3e5, 0.0, 2e5, 1e6, 1e5, -3e5);
        let y = quad(0.0, -2e5, 1e5, 3e5, 1e6, -4e5);
        lembo_on_screen(x, y)
    }

    #[test]
    fn setup_pieces_keeps_a_lembo_within_the_guard_band_whole_and_bit_identical() {
        let l = lembo_on_screen(x_linear(), y_bowl());
        let mut out = Vec::new();
        let split = setup_pieces::<f32>(0, &l, [0.8; 3], &view(), None, &mut out).unwrap();
        assert_eq!(split, Split::default());
        assert_eq!(out.len(), 1);
        let whole = setup::<f32>(0, &l, [0.8; 3], &view()).unwrap();
        assert_eq!(format!("{:?}", out[0]), format!("{whole:?}"));
        assert!(out[0].domain.is_none());
    }

    #[test]
    fn pieces_are_the_lembo_restricted_to_their_sub_triangles() {
        let l = huge_lembo();
        let whole = setup::<f64>(0, &l, [0.8; 3], &view()).unwrap();
        let mut pieces = Vec::new();
        let split = setup_pieces::<f64>(0, &l, [0.8; 3], &view(), None, &mut pieces).unwrap();
        assert!(
            pieces.len() > 1 && split.culled > 0,
            "{} {split:?}",
            pieces.len()
        );
        let g = SPLIT_GUARD_VIEWPORTS * SIDE as f64;
        for p in &pieces {
            let dom = p.domain.expect("a piece knows its sub-triangle");
            for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.2, 0.3), (0.6, 0.1)] {
                let (lu, lv) = p.lembo_uv(u, v);
                assert!(lu >= -1e-15 && lv >= -1e-15 && lu + lv <= 1.0 + 1e-15);
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + b.abs());
                assert!(close(p.x.eval(u, v), whole.x.eval(lu, lv)), "{dom:?}");
                assert!(close(p.y.eval(u, v), whole.y.eval(lu, lv)), "{dom:?}");
                assert!(close(p.z.eval(u, v), whole.z.eval(lu, lv)), "{dom:?}");
                for c in 0..3 {
                    assert!(close(p.normal[c].eval(u, v), whole.normal[c].eval(lu, lv)));
                    assert!(close(
                        p.position[c].eval(u, v),
                        whole.position[c].eval(lu, lv)
                    ));
                }
                // Within the guard band (a piece's points lie in its hull).
                let (x, y) = (p.x.eval(u, v), p.y.eval(u, v));
                assert!(x >= -g && x <= SIDE as f64 + g && y >= -g && y <= SIDE as f64 + g);
            }
        }
        // Pieces that share a domain edge share its three screen points bit for bit, in the
        // same canonical order, so the edge roots agree and no pixel is dropped or doubled.
        let corners = |p: &ScreenLembo<f64>| {
            let [a, b, c] = p.domain.unwrap();
            [(a, b), (b, c), (c, a)]
        };
        let mut shared = 0;
        for (n, p) in pieces.iter().enumerate() {
            for q in &pieces[n + 1..] {
                for (ep, (a, b)) in corners(p).into_iter().enumerate() {
                    for (eq, (c, d)) in corners(q).into_iter().enumerate() {
                        if (a, b) == (d, c) || (a, b) == (c, d) {
                            shared += 1;
                            let (e, f) = (&p.edges[ep], &q.edges[eq]);
                            assert_eq!(e.x.map(f64::to_bits), f.x.map(f64::to_bits));
                            assert_eq!(e.y.map(f64::to_bits), f.y.map(f64::to_bits));
                        }
                    }
                }
            }
        }
        assert!(shared > 0);
    }

    #[test]
    fn splitting_is_bounded_whatever_the_size() {
        // 10¹⁵ px across: the depth limit and the piece budget bound the work.
        let x = quad(3e14, 0.0, 2e14, 1e15, 1e14, -3e14);
        let y = quad(0.0, -2e14, 1e14, 3e14, 1e15, -4e14);
        let mut pieces = Vec::new();
        let split = setup_pieces::<f32>(
            0,
            &lembo_on_screen(x, y),
            [0.8; 3],
            &view(),
            None,
            &mut pieces,
        )
        .unwrap();
        assert!(!pieces.is_empty());
        assert!(pieces.len() <= MAX_PIECES + 3, "{}", pieces.len());
        assert!(split.examined as usize <= 4 * (MAX_SPLIT_DEPTH as usize) * (MAX_PIECES + 3));
    }
}
