//! Setup's perspective-adaptive split and near-plane handling (`--perspective-tol`).
//!
//! The paper (001, section 4) assumes the projection is already applied: Setup projects a
//! lembo's six reference points and rebuilds screen-space quadratics through them. Under
//! perspective the projection of a quadratic patch is rational, not quadratic, so the rebuilt
//! patch misses the true image by an error that does not depend on k (1.3 px on sphere24 at
//! any k). With a perspective tolerance `tol` \[pixels\], Setup measures that error and splits
//! the lembo into pieces until every piece is within `tol` of the true projection, with the
//! same piece mechanism the guard-band split uses ([`super::setup::setup_pieces`]).
//!
//! **The estimate.** A piece is a sub-triangle of the lembo's domain with six screen points.
//! Its error is measured against the true projection of the world surface at extra domain
//! points: the quarter points (t = 1/4, 3/4) of each of its edges that are still its own
//! (below), and inside, the middles of the three segments that join its edge middles and its
//! centroid. The largest screen distance \[pixels\] there is the piece's error. Each halving
//! divides the error of a smooth projection by about 8 (the rebuilt quadratic interpolates a
//! smooth map at six points: its error is third order in the piece's size). An error counts
//! only beyond the rounding noise of projecting its point (`NOISE_ULPS` rounding units of
//! the world coordinates' magnitude, carried to pixels by the projection's scale there):
//! far from the origin or under extreme zoom, rounding alone exceeds a small tolerance, and
//! splitting would chase it to the caps. An orthographic view projects affinely, so Setup
//! never calls this for one ([`super::setup::setup_pieces`]).
//!
//! **Watertight by construction.** A shared edge must be one curve for both pieces (or
//! lembos) on its sides. So an edge's fate is decided from the edge alone: it is *refined*
//! (both halves get their middles from the true projection) when its own quarter points are
//! farther than `tol` from the parabola through its three points, or when it is not wholly in
//! front of the plane `w = w_min` (below). A piece splits when any of its own edges is refined,
//! when its interior error exceeds `tol`, when it reaches beyond the guard band, or when it
//! cannot be projected. When a piece splits but one of its edges is not refined, the edge is
//! *frozen*: its halves, and every later piece along it, take their points from the parabola
//! through its three screen points, in a canonical order (by world position of its ends), so
//! the piece that stays whole on the other side draws the same curve. The lembo's own edges
//! are evaluated from their world-space parabola in canonical order (as construction computed
//! them), so neighbouring lembos make the same decisions from the same bits. Where one side
//! is split deeper than the other along a frozen edge, the two agree up to the rounding of
//! evaluating the same parabola (a T-junction), as the guard-band split's pieces do.
//!
//! **Near plane.** Points with clip `w <= 0` cannot be projected. The world position is
//! quadratic and clip coordinates are affine in it, so the clip coordinates of the lembo's
//! Bézier net bound the patch's. A piece whose net lies wholly beyond one plane of the view
//! frustum is dropped (in front of the near plane: counted apart); a piece whose net has every
//! `w >= w_min` (half the near distance; any positive `w` for orthographic views) is projected
//! and drawn, and its fragments nearer than the near plane fail the depth test's `[0, 1]`
//! range (clipped per fragment); any other piece straddles the plane `w = w_min` and is split.
//!
//! Splitting is bounded as the guard-band split is: at most [`MAX_SPLIT_DEPTH`] halvings and
//! [`MAX_PIECES`] pieces per lembo. A piece kept at a cap while still over the tolerance is
//! counted (`capped`); one that still cannot be projected there is dropped and counted.

use super::screen::{
    build_piece, build_whole, on_domain_edge, outside, parabola, reference_uv, within_guard_band,
    zero_area, Cull, ScreenLembo, ScreenPoints, Split, EDGE_POINTS, MAX_PIECES, MAX_SPLIT_DEPTH,
};
use crate::camera::View;
use crate::datapath::Real;
use crate::lembo::construct::canonical_order;
use crate::lembo::{bezier_controls, Lembo, Quadratic};
use glam::{DVec3, DVec4};
use std::cmp::Ordering;

/// A screen point: x, y \[pixels\] and window depth.
type S3 = [f64; 3];

/// A domain point (u, v) of the lembo.
type Uv = [f64; 2];

fn mid(p: Uv, q: Uv) -> Uv {
    [(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5]
}

/// Where the screen points of a piece's edge come from.
#[derive(Clone, Copy, Debug)]
enum EdgeSource {
    /// The edge's middle is the projection of its world point: the edge may still be refined.
    Own,
    /// A stretch of a frozen ancestor edge: the parabola `curve` through that edge's three
    /// screen points in canonical order, from canonical parameter `t[0]` (at this edge's
    /// start, in the piece's counter-clockwise order) to `t[1]` (at its end).
    Frozen { curve: [S3; 3], t: [f64; 2] },
}

/// A sub-triangle of the lembo's domain under examination.
#[derive(Clone, Debug)]
struct Node {
    /// Its corners A, B, C in the lembo's domain.
    tri: [Uv; 3],
    depth: u32,
    /// Its six reference points on the world surface and on screen, in the paper's order.
    world: [DVec3; 6],
    screen: [S3; 6],
    /// Its edges A→B, B→C, C→A ([`EDGE_POINTS`]).
    edges: [EdgeSource; 3],
}

/// A lembo's world surface, as Setup samples it for splitting.
struct Surface<'a> {
    lembo: &'a Lembo,
    view: &'a View,
    /// Per domain edge A→B, B→C, C→A: its three world points in canonical order and whether
    /// that order runs against the lembo's.
    edges: [([[f64; 3]; 3], bool); 3],
    /// Pieces whose Bézier net has every clip w at least this can be projected.
    w_min: f64,
    tol: f64,
    /// The largest absolute world coordinate of the lembo and the eye (at least 1): the
    /// scale of the rounding in evaluating and projecting a world point.
    magnitude: f64,
    /// Per screen axis: half the viewport side times the L1 norm of the view-projection
    /// row of that axis and of w (their linear parts).
    rows: [[f64; 2]; 2],
}

/// How many rounding units of a projected point's noise an error must exceed before it
/// counts (the six points' noise reaches the rebuilt quadratic through weights up to 5).
const NOISE_ULPS: f64 = 64.0;

impl<'a> Surface<'a> {
    fn new(lembo: &'a Lembo, view: &'a View, tol: f64) -> Self {
        let p = &lembo.points;
        let edges = EDGE_POINTS.map(|[s, m, e]| {
            let reversed = canonical_order(p[e], p[s]) == Ordering::Less;
            let (s, e) = if reversed { (e, s) } else { (s, e) };
            ([s, m, e].map(|k| p[k].to_array()), reversed)
        });
        let w_min = if view.orthographic {
            0.0
        } else {
            0.5 * view.near
        };
        let magnitude = p
            .iter()
            .chain([&view.eye])
            .map(|q| q.abs().max_element())
            .fold(1.0, f64::max);
        let m = view.view_proj;
        let row = |r: usize| m.row(r).truncate().abs().element_sum();
        let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
        let rows = [
            [0.5 * w * row(0), 0.5 * w * row(3)],
            [0.5 * h * row(1), 0.5 * h * row(3)],
        ];
        Surface {
            lembo,
            view,
            edges,
            w_min,
            tol,
            magnitude,
            rows,
        }
    }

    /// Whether the error vector (dx, dy) \[pixels, and rows of the view's grid\] at world
    /// point `p` is longer than the tolerance, and than the rounding noise of projecting `p` there (far from the origin,
    /// or under extreme zoom, rounding alone can exceed a small tolerance; splitting would
    /// then chase noise to the caps). A vector whose |dx| + |dy| is clearly within the
    /// tolerance is within it without `hypot` (slow in libm): |dx| + |dy| bounds the
    /// length, and the margin of 4 ulps covers the sum's rounding and `hypot`'s (within one
    /// ulp), so the answer is the one `hypot` gives.
    fn exceeds(&self, dx: f64, dy: f64, p: DVec3) -> bool {
        // On a multisampled frame's sample grid, rows are 1/samples of a pixel apart: the
        // error is measured in pixels, as the tolerance is.
        let dy = dy / self.view.samples.get() as f64;
        if dx.abs() + dy.abs() <= self.tol * (1.0 - 4.0 * f64::EPSILON) {
            return false;
        }
        let err = dx.hypot(dy);
        if err <= self.tol {
            return false;
        }
        let c = self.clip(p);
        let w = c.w.abs();
        let along = |axis: usize, ndc: f64| self.rows[axis][0] + ndc.abs() * self.rows[axis][1];
        let noise = NOISE_ULPS
            * f64::EPSILON
            * self.magnitude
            * (along(0, c.x / c.w) + along(1, c.y / c.w))
            / w;
        err > self.tol + noise
    }

    /// The world point at domain point `uv`; on a domain edge, from the edge's parabola in
    /// canonical order, so every lembo that shares the edge computes the same bits.
    fn world(&self, uv: Uv) -> DVec3 {
        match on_domain_edge(uv) {
            Some((e, t)) => {
                let (p, reversed) = &self.edges[e];
                DVec3::from_array(parabola(p, if *reversed { 1.0 - t } else { t }))
            }
            None => self.lembo.position_at(uv[0], uv[1]),
        }
    }

    fn clip(&self, p: DVec3) -> DVec4 {
        self.view.view_proj * p.extend(1.0)
    }

    fn screen(&self, p: DVec3) -> S3 {
        let s = self.view.project(p);
        [s.x, s.y, s.depth]
    }

    /// Clip coordinates of the Bézier net through six world points.
    fn net(&self, world: &[DVec3; 6]) -> [DVec4; 6] {
        bezier_controls(world).map(|p| self.clip(p))
    }

    /// Whether the patch through these clip-space control points can be projected.
    fn projectable(&self, net: &[DVec4]) -> bool {
        net.iter().all(|c| c.w >= self.w_min && c.w > 0.0)
    }

    /// Whether an edge, from its ends and middle (uv, world, screen), must be refined: it
    /// cannot be projected, or its quarter points are farther than the tolerance from the
    /// parabola through its three screen points. Computed in canonical order, so the pieces
    /// on both sides decide the same.
    fn refine(&self, ends: [(Uv, DVec3, S3); 3]) -> bool {
        let [s, m, e] = canonical(ends);
        let (ws, wm, we) = (s.1, m.1, e.1);
        let net = [ws, 2.0 * wm - 0.5 * (ws + we), we].map(|p| self.clip(p));
        if !self.projectable(&net) {
            return true;
        }
        let curve = [s.2, m.2, e.2];
        [(s.0, 0.25), (e.0, 0.75)].into_iter().any(|(end, t)| {
            let world = self.world(mid(end, m.0));
            let truth = self.screen(world);
            let got = parabola(&curve, t);
            self.exceeds(got[0] - truth[0], got[1] - truth[1], world)
        })
    }

    /// Whether the piece's rebuilt screen quadratics miss the true projection by more than
    /// the tolerance at one of its interior check points.
    fn interior_exceeds(&self, node: &Node) -> bool {
        let x = Quadratic::from_reference_values(node.screen.map(|s| s[0]));
        let y = Quadratic::from_reference_values(node.screen.map(|s| s[1]));
        let [a, b, c] = node.tri;
        let at = |u: f64, v: f64| {
            [
                a[0] + u * (b[0] - a[0]) + v * (c[0] - a[0]),
                a[1] + u * (b[1] - a[1]) + v * (c[1] - a[1]),
            ]
        };
        let third = 1.0 / 3.0;
        [(0.25, 0.25), (0.5, 0.25), (0.25, 0.5), (third, third)]
            .into_iter()
            .any(|(u, v)| {
                let world = self.world(at(u, v));
                let truth = self.screen(world);
                self.exceeds(x.eval(u, v) - truth[0], y.eval(u, v) - truth[1], world)
            })
    }
}

/// The three points of an edge ordered by the world position of its ends (the middle stays in
/// the middle).
fn canonical<T: Copy>(p: [(Uv, DVec3, T); 3]) -> [(Uv, DVec3, T); 3] {
    if canonical_order(p[2].1, p[0].1) == Ordering::Less {
        [p[2], p[1], p[0]]
    } else {
        p
    }
}

/// Why a frustum test failed for a net wholly beyond one of its planes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Beyond {
    Near,
    Other,
}

/// Whether every control point lies beyond one plane of the view frustum.
fn beyond(net: &[DVec4; 6]) -> Option<Beyond> {
    let all = |f: &dyn Fn(&DVec4) -> bool| net.iter().all(f);
    if all(&|c| c.z < -c.w) {
        Some(Beyond::Near)
    } else if all(&|c| c.x < -c.w)
        || all(&|c| c.x > c.w)
        || all(&|c| c.y < -c.w)
        || all(&|c| c.y > c.w)
        || all(&|c| c.z > c.w)
    {
        Some(Beyond::Other)
    } else {
        None
    }
}

/// Sets up one lembo with the perspective tolerance `tol` \[pixels\] into `out`: whole when
/// it can be projected, is within `tol` of its true projection and within the guard band;
/// otherwise split (see the module documentation).
pub fn setup_refined<R: Real>(
    id: u32,
    lembo: &Lembo,
    color: [f64; 3],
    view: &View,
    tol: f64,
    out: &mut Vec<ScreenLembo<R>>,
) -> Result<Split, Cull> {
    let s = Surface::new(lembo, view, tol);
    let world = lembo.points;
    let root = Node {
        tri: [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        depth: 0,
        world,
        screen: world.map(|p| s.screen(p)),
        edges: [EdgeSource::Own; 3],
    };
    let root_net = s.net(&world);
    cull_whole(&s, view, &root, &root_net)?;
    let mut split = Split::default();
    let mut pending = vec![root];
    let first = out.len();
    while let Some(node) = pending.pop() {
        let full = out.len() - first + pending.len() >= MAX_PIECES;
        if node.depth > 0 {
            split.examined += 1;
        }
        // The root's net was worked out above.
        let net = match node.depth {
            0 => root_net,
            _ => s.net(&node.world),
        };
        let projectable = s.projectable(&net);
        let points = ScreenPoints::of(&node.screen);
        if node.depth > 0 && culled_piece(view, &net, projectable, &points, &mut split) {
            continue;
        }
        // Why this piece would split (decided before the caps, to count what they cut).
        let own_refined: [bool; 3] = std::array::from_fn(|e| {
            matches!(node.edges[e], EdgeSource::Own) && s.refine(edge_points(&node, e))
        });
        let perspective =
            projectable && (own_refined.iter().any(|&r| r) || s.interior_exceeds(&node));
        let guard = projectable && !within_guard_band(view, points.hull());
        let wants = !projectable || perspective || guard;
        if !wants || node.depth >= MAX_SPLIT_DEPTH || full {
            if !projectable {
                // At a cap and still straddling w = w_min: nothing of it can be drawn.
                split.capped += 1;
                split.culled_near += 1;
                continue;
            }
            if wants {
                split.capped += 1;
            }
            if node.depth == 0 {
                out.push(build_whole(id, &points, lembo, color));
                return Ok(split);
            }
            out.push(build_piece(id, &points, lembo, color, node.tri));
            continue;
        }
        split.perspective |= perspective;
        split.near |= !projectable;
        let project = perspective || !projectable;
        // Pushed in reverse, so pieces come out in the order A, B, C, middle.
        for child in children(&s, &node, own_refined, project).into_iter().rev() {
            pending.push(child);
        }
    }
    Ok(split)
}

/// Why the whole lembo (the root node, with its Bézier net `net`) is not drawn, if it is
/// not: outside the view or of zero screen area when projectable, else wholly behind the
/// eye or beyond another clip plane.
fn cull_whole(s: &Surface, view: &View, root: &Node, net: &[DVec4; 6]) -> Result<(), Cull> {
    if s.projectable(net) {
        let points = ScreenPoints::of(&root.screen);
        if outside(view, points.hull()) {
            return Err(Cull::Outside);
        }
        if zero_area(points.xs(), points.ys()) {
            return Err(Cull::Degenerate);
        }
    } else {
        match beyond(net) {
            Some(Beyond::Near) => return Err(Cull::BehindEye),
            Some(Beyond::Other) => return Err(Cull::Outside),
            None => {}
        }
    }
    Ok(())
}

/// Whether a piece below the root is culled (outside the view when projectable, else
/// beyond a clip plane by its net), counted in `split` as culled near or culled.
fn culled_piece(
    view: &View,
    net: &[DVec4; 6],
    projectable: bool,
    points: &ScreenPoints,
    split: &mut Split,
) -> bool {
    let culled = if projectable {
        outside(view, points.hull()).then_some(Beyond::Other)
    } else {
        beyond(net)
    };
    match culled {
        Some(Beyond::Near) => {
            split.culled_near += 1;
            true
        }
        Some(Beyond::Other) => {
            split.culled += 1;
            true
        }
        None => false,
    }
}

/// Edge `e` of a node as (uv, world, screen) at its start, middle and end.
fn edge_points(node: &Node, e: usize) -> [(Uv, DVec3, S3); 3] {
    let uv = reference_uv(node.tri);
    EDGE_POINTS[e].map(|k| (uv[k], node.world[k], node.screen[k]))
}

/// The four children of a node, with the screen points of their new edge middles taken from
/// the true projection (refined edges, and inner edges when `project`), from the node's own
/// quadratics (inner edges otherwise) or from the frozen parabola of an edge.
fn children(s: &Surface, node: &Node, refined: [bool; 3], project: bool) -> [Node; 4] {
    let uv = reference_uv(node.tri);
    // Per parent edge: the middles of its two halves (world, screen) and the halves' sources.
    let halves: [_; 3] = std::array::from_fn(|e| {
        let [i0, im, i1] = EDGE_POINTS[e];
        let (q0, q1) = (mid(uv[i0], uv[im]), mid(uv[im], uv[i1]));
        let (w0, w1) = (s.world(q0), s.world(q1));
        let frozen = match node.edges[e] {
            EdgeSource::Own if refined[e] => None,
            EdgeSource::Own => {
                let p = edge_points(node, e);
                let forward = canonical(p)[0].0 == p[0].0;
                let c = canonical(p).map(|q| q.2);
                Some((c, if forward { [0.0, 1.0] } else { [1.0, 0.0] }))
            }
            EdgeSource::Frozen { curve, t } => Some((curve, t)),
        };
        match frozen {
            None => (
                [(w0, s.screen(w0)), (w1, s.screen(w1))],
                [EdgeSource::Own; 2],
            ),
            Some((curve, [t0, t1])) => {
                let tm = 0.5 * (t0 + t1);
                let (ta, tb) = (0.5 * (t0 + tm), 0.5 * (tm + t1));
                (
                    [(w0, parabola(&curve, ta)), (w1, parabola(&curve, tb))],
                    [
                        EdgeSource::Frozen { curve, t: [t0, tm] },
                        EdgeSource::Frozen { curve, t: [tm, t1] },
                    ],
                )
            }
        }
    });
    let [a, b, c] = node.tri;
    let [_, _, _, ab, ca, bc] = uv;
    let p = |k: usize| (node.world[k], node.screen[k]);
    // The parent's own screen quadratics, for children of a split that is not for
    // perspective or the near plane (the guard band alone): they restrict the parent as the
    // paper's Setup's pieces restrict the lembo, rather than bring in projected points
    // whose error (rounding noise, at such sizes) the parent was not split for.
    let q: [Quadratic<f64>; 3] =
        std::array::from_fn(|c| Quadratic::from_reference_values(node.screen.map(|p| p[c])));
    // The middle of the inner edge from x to y, at (u, v) in the node's own domain.
    let inner = |x: Uv, y: Uv, (u, v): (f64, f64)| {
        let w = s.world(mid(x, y));
        if project {
            (w, s.screen(w))
        } else {
            (w, q.map(|q| q.eval(u, v)))
        }
    };
    let (m_ab_ca, m_ab_bc, m_bc_ca) = (
        inner(ab, ca, (0.25, 0.25)),
        inner(ab, bc, (0.5, 0.25)),
        inner(bc, ca, (0.25, 0.5)),
    );
    let own = EdgeSource::Own;
    let make = |tri: [Uv; 3], pts: [(DVec3, S3); 6], edges: [EdgeSource; 3]| Node {
        tri,
        depth: node.depth + 1,
        world: pts.map(|q| q.0),
        screen: pts.map(|q| q.1),
        edges,
    };
    // Points: corners A, B, C (0, 1, 2), edge middles AB (3), CA (4), BC (5); the halves of
    // edge e are halves[e].0[0] (from its start) and halves[e].0[1] (towards its end).
    let (h0, h1, h2) = (halves[0], halves[1], halves[2]);
    [
        make(
            [a, ab, ca],
            [p(0), p(3), p(4), h0.0[0], h2.0[1], m_ab_ca],
            [h0.1[0], own, h2.1[1]],
        ),
        make(
            [ab, b, bc],
            [p(3), p(1), p(5), h0.0[1], m_ab_bc, h1.0[0]],
            [h0.1[1], h1.1[0], own],
        ),
        make(
            [ca, bc, c],
            [p(4), p(5), p(2), m_bc_ca, h2.0[0], h1.0[1]],
            [own, h1.1[1], h2.1[0]],
        ),
        make(
            [bc, ca, ab],
            [p(5), p(4), p(3), m_bc_ca, m_ab_bc, m_ab_ca],
            [own, own, own],
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::lembo::shapes::builtin_lembos;

    fn view(eye: [f64; 3], near: f64) -> View {
        View::new(
            &Camera {
                eye,
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 50.0,
                    near,
                    far: 100.0,
                },
            },
            Viewport {
                width: 256,
                height: 256,
            },
        )
    }

    /// The largest screen distance between a piece's quadratics and the true projection of
    /// the lembo at a 21 x 21 lattice of the piece's domain \[pixels\].
    fn worst(lembo: &Lembo, v: &View, p: &ScreenLembo<f64>) -> f64 {
        let mut worst = 0.0f64;
        for a in 0..=20 {
            for b in 0..=(20 - a) {
                let (u, w) = (a as f64 / 20.0, b as f64 / 20.0);
                let (lu, lv) = p.lembo_uv(u, w);
                let truth = v.project(lembo.position_at(lu, lv));
                let (x, y) = (p.x.eval(u, w), p.y.eval(u, w));
                worst = worst.max((x - truth.x).hypot(y - truth.y));
            }
        }
        worst
    }

    /// The estimate (edge quarter points, four interior points) is what Setup trusts; on
    /// sampled points of every piece the true error stays within 1.5 tol, and without the
    /// split it is far above it.
    #[test]
    fn pieces_are_within_the_tolerance_of_the_true_projection() {
        let v = view([0.4, 0.6, 1.8], 0.1);
        let lembos = builtin_lembos("sphere24").unwrap();
        for tol in [0.5, 0.05, 0.005] {
            let (mut split, mut whole_worst) = (0, 0.0f64);
            for (id, l) in lembos.iter().enumerate() {
                let mut out = Vec::new();
                let Ok(s) = setup_refined::<f64>(id as u32, l, [0.8; 3], &v, tol, &mut out) else {
                    continue;
                };
                split += s.perspective as u32;
                assert_eq!(s.capped, 0);
                for p in &out {
                    let e = worst(l, &v, p);
                    assert!(e <= 1.5 * tol, "lembo {id} tol {tol}: {e} px");
                }
                let mut whole = Vec::new();
                if super::super::setup::setup_pieces::<f64>(0, l, [0.8; 3], &v, None, &mut whole)
                    .is_ok()
                {
                    whole_worst = whole
                        .iter()
                        .map(|p| worst(l, &v, p))
                        .fold(whole_worst, f64::max);
                }
            }
            assert!(
                split > 0 && whole_worst > 4.0 * tol.min(0.5),
                "{split} {whole_worst}"
            );
        }
    }

    /// A lembo crossing the eye plane is split at the near plane: every piece drawn can be
    /// projected (its Bézier net in front of w = near/2), the parts nearer than the near
    /// plane are dropped, and the work stays bounded.
    #[test]
    fn a_lembo_through_the_eye_plane_is_split_at_the_near_plane() {
        // A large flat lembo on y = 0 under an eye at height 1, looking along -z: it runs
        // from 10 units behind the eye to 30 in front.
        let p = [
            DVec3::new(-20.0, 0.0, 10.0),
            DVec3::new(20.0, 0.0, 10.0),
            DVec3::new(0.0, 0.0, -30.0),
        ];
        let m = |a: DVec3, b: DVec3| (a + b) * 0.5;
        let l = Lembo::new(
            [
                p[0],
                p[1],
                p[2],
                m(p[0], p[1]),
                m(p[0], p[2]),
                m(p[1], p[2]),
            ],
            [DVec3::Y; 6],
        );
        let v = View::new(
            &Camera {
                eye: [0.0, 1.0, 0.0],
                target: [0.0, 0.8, -10.0],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 60.0,
                    near: 0.1,
                    far: 100.0,
                },
            },
            Viewport {
                width: 128,
                height: 128,
            },
        );
        let mut none = Vec::new();
        assert_eq!(
            super::super::setup::setup_pieces::<f32>(0, &l, [0.8; 3], &v, None, &mut none).err(),
            Some(Cull::BehindEye),
            "the paper's Setup drops it"
        );
        let mut out = Vec::new();
        let s = setup_refined::<f32>(0, &l, [0.8; 3], &v, 0.25, &mut out).unwrap();
        assert!(
            s.near && !out.is_empty() && out.len() <= MAX_PIECES,
            "{s:?}"
        );
        assert!(s.culled_near + s.culled > 0, "{s:?}");
        for piece in &out {
            let [a, b, c] = piece.domain.unwrap();
            for (u, w) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.3)] {
                let at = |k: usize| a[k] + u * (b[k] - a[k]) + w * (c[k] - a[k]);
                assert!(v.project(l.position_at(at(0), at(1))).w >= 0.05);
            }
        }
    }

    /// Far from the origin (10⁷) under a 0.001° field of view, projecting a point is
    /// rounding noise beyond a 10⁻⁴ px tolerance: the split must not chase it (the fuzzer's
    /// case walked 75 million segments over 1023 capped pieces before the noise floor and
    /// the guard band's restricted children). It splits as the paper's Setup does.
    #[test]
    fn rounding_noise_is_not_split_for() {
        let points = [
            DVec3::new(
                -4.0178843468598275e-07,
                -9350946.264265798,
                3194294.8382927338,
            ),
            DVec3::new(
                -5.984584631500639e-07,
                -9350946.26426625,
                3194294.8382922173,
            ),
            DVec3::new(
                -4.0948767840699985e-07,
                -9350946.264266629,
                3194294.838292417,
            ),
            DVec3::new(
                3.671684551033988e-08,
                -9350946.264265366,
                3194294.8382922183,
            ),
            DVec3::new(
                -4.460708523236915e-07,
                -9350946.264266318,
                3194294.8382923515,
            ),
            DVec3::new(
                -2.1879361066201438e-07,
                -9350946.264264904,
                3194294.8382929303,
            ),
        ];
        let l = Lembo::new(points, [DVec3::Z; 6]);
        let v = View::new(
            &Camera {
                eye: [
                    2.2805598618962026e-06,
                    -9350946.264269004,
                    3194294.8382904935,
                ],
                target: [
                    -4.730917155276137e-07,
                    -9350946.264265714,
                    3194294.8382926024,
                ],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 0.001,
                    near: 4.77966906581814e-07,
                    far: 0.47796690658181407,
                },
            },
            Viewport {
                width: 60,
                height: 64,
            },
        );
        let mut paper = Vec::new();
        let p = super::super::setup::setup_pieces::<f64>(0, &l, [0.8; 3], &v, None, &mut paper)
            .unwrap();
        let mut out = Vec::new();
        let s = setup_refined::<f64>(0, &l, [0.8; 3], &v, 1e-4, &mut out).unwrap();
        assert_eq!(s.capped, 0, "{s:?}");
        assert!(!s.perspective, "{s:?}");
        assert_eq!((out.len(), s.culled), (paper.len(), p.culled));
    }
}
