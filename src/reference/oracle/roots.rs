//! One lembo against one ray (the module documentation): the two conics of the planes
//! through the ray, the subdivision of the domain triangle with its Bézier-net box (and,
//! for a yes-or-no answer, convex-hull) tests, Newton's method and the Jacobian test that
//! proves a sub-triangle holds no other root.

use crate::lembo::{bezier_controls, Lembo, Quadratic, Quadratic3};
use glam::{DVec2, DVec3};
use std::borrow::Cow;

/// Roots this far outside the domain [uv units] still count, clamped onto it.
pub const DOMAIN_TOLERANCE: f64 = 1e-9;
/// Roots closer than this in uv (L1 distance) are the same root.
pub const SAME_ROOT_UV: f64 = 1e-7;
/// Deepest subdivision: sub-triangles with legs of 2^-MAX_DEPTH in uv.
const MAX_DEPTH: u32 = 20;
/// Sub-triangles examined per ray and lembo before every remaining one becomes a leaf; only
/// degenerate configurations reach it (a flat lembo seen exactly edge-on has a continuum of
/// roots).
const NODE_BUDGET: usize = 4096;
/// Newton iterations at the deepest sub-triangles, where roots may be double and converge
/// only linearly.
const NEWTON_ITERATIONS: usize = 40;
/// Newton iterations elsewhere: a simple root converges in a few; failing to, the
/// sub-triangle is subdivided instead.
const NEWTON_PROBE_ITERATIONS: usize = 10;
/// Residual accepted by Newton, relative to the size of the problem (distance plus extent).
const RESIDUAL_TOLERANCE: f64 = 1e-11;
/// Slack on box tests, relative to the size of the problem, against rounding.
const BOX_SLACK: f64 = 1e-12;

/// One root of (Q1, Q2) in the domain.
#[derive(Clone, Copy, Debug)]
pub(super) struct Root {
    pub(super) t: f64,
    pub(super) u: f64,
    pub(super) v: f64,
}

/// A sub-triangle of the domain: corners in uv and subdivision depth.
#[derive(Clone, Copy, Debug)]
struct Node {
    a: DVec2,
    b: DVec2,
    c: DVec2,
    depth: u32,
}

/// Buffers reused from ray to ray.
#[derive(Default)]
pub(super) struct Scratch {
    stack: Vec<Node>,
    roots: Vec<Root>,
}

/// A lembo prepared for ray tests: its Bézier control net and size. It borrows the lembo,
/// or owns it where the lembo was made for a tile (`tracer.rs`).
pub(super) struct Patch<'a> {
    pub(super) lembo: Cow<'a, Lembo>,
    pub(super) controls: [DVec3; 6],
    /// Largest distance of a control point from the first one [world units].
    extent: f64,
}

/// The lembo seen from one ray: Q1, Q2 and t as quadratics in (u, v).
struct RayFrame {
    q: [Quadratic<f64>; 3],
    /// Residual accepted as a root of (Q1, Q2) [world units].
    residual_tolerance: f64,
    /// Slack on the box tests [world units].
    slack: f64,
}

impl<'a> Patch<'a> {
    pub(super) fn new(lembo: Cow<'a, Lembo>) -> Self {
        let controls = lembo.bezier_control_points();
        let extent = controls
            .iter()
            .map(|c| (*c - controls[0]).length())
            .fold(0.0, f64::max);
        Patch {
            lembo,
            controls,
            extent,
        }
    }

    /// Appends to `out` the roots with `t_lo <= t <= t_hi` along the unit direction `dir`.
    pub(super) fn roots(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_lo: f64,
        t_hi: f64,
        scratch: &mut Scratch,
        out: &mut Vec<Root>,
    ) {
        self.search(origin, dir, t_lo, t_hi, scratch, None);
        out.extend_from_slice(&scratch.roots);
    }

    /// Whether the line has a root with `t_lo <= t <= t_hi` that `accept` takes. Stops at
    /// the first: any root Newton converges to inside a sub-triangle proves a hit, so the
    /// uniqueness proofs and the deep subdivision near grazing rays (double roots) that
    /// [`Patch::roots`] needs are skipped where a root is found.
    pub(super) fn any_root(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_lo: f64,
        t_hi: f64,
        scratch: &mut Scratch,
        accept: &mut dyn FnMut(&Root) -> bool,
    ) -> bool {
        self.search(origin, dir, t_lo, t_hi, scratch, Some(accept))
    }

    /// The subdivision search (module documentation) for all roots into `scratch.roots`,
    /// or, with `accept`, until a root it takes is found (then true).
    fn search(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_lo: f64,
        t_hi: f64,
        scratch: &mut Scratch,
        mut accept: Option<&mut dyn FnMut(&Root) -> bool>,
    ) -> bool {
        let frame = self.ray_frame(origin, dir);
        scratch.roots.clear();
        scratch.stack.clear();
        scratch.stack.push(Node {
            a: DVec2::ZERO,
            b: DVec2::X,
            c: DVec2::Y,
            depth: 0,
        });
        let mut visited = 0usize;
        while let Some(node) = scratch.stack.pop() {
            visited += 1;
            let uv = node.net();
            if !frame.may_hold_root(&uv, t_lo, t_hi, accept.is_some()) {
                continue;
            }
            let centroid = (node.a + node.b + node.c) / 3.0;
            if let Some(r) = frame.newton(centroid, NEWTON_PROBE_ITERATIONS) {
                if let Some(accept) = accept.as_mut() {
                    if inside_triangle(r, &node) {
                        if let Some(root) = frame.keep(r, t_lo, t_hi, &mut scratch.roots) {
                            if accept(&root) {
                                return true;
                            }
                        }
                    }
                }
                // Another root x of the node would make J((x + r) / 2) singular.
                if frame.jacobian_is_regular(&node.halfway_to(r).net()) {
                    if inside_triangle(r, &node) {
                        frame.keep(r, t_lo, t_hi, &mut scratch.roots);
                    }
                    continue;
                }
            }
            if node.depth >= MAX_DEPTH || visited >= NODE_BUDGET {
                if let Some(r) = frame.newton(centroid, NEWTON_ITERATIONS) {
                    let kept = frame.keep(r, t_lo, t_hi, &mut scratch.roots);
                    if let (Some(accept), Some(root)) = (accept.as_mut(), kept) {
                        if accept(&root) {
                            return true;
                        }
                    }
                }
                continue;
            }
            node.push_children(uv, &mut scratch.stack);
        }
        false
    }

    /// The lembo seen from the ray `origin + t dir` (unit `dir`): Q1 and Q2 along two unit
    /// normals of the ray and t along it, with the tolerances scaled to the problem's size
    /// (the distance to the net plus its extent).
    fn ray_frame(&self, origin: DVec3, dir: DVec3) -> RayFrame {
        let (n1, n2) = dir.any_orthonormal_pair();
        let position = &self.lembo.position;
        let size = (self.controls[0] - origin).length() + self.extent;
        RayFrame {
            q: [
                along(position, n1, origin),
                along(position, n2, origin),
                along(position, dir, origin),
            ],
            residual_tolerance: RESIDUAL_TOLERANCE * size,
            slack: BOX_SLACK * size,
        }
    }
}

impl Node {
    /// The six reference points of the sub-triangle: its corners, then the midpoints of
    /// AB, AC and BC.
    fn net(&self) -> [DVec2; 6] {
        [
            self.a,
            self.b,
            self.c,
            mid(self.a, self.b),
            mid(self.a, self.c),
            mid(self.b, self.c),
        ]
    }

    /// The triangle halfway between the node's and the point `r`: its corners' midpoints
    /// with `r` (where the Jacobian test of a root `r` looks).
    fn halfway_to(&self, r: DVec2) -> Node {
        let [a, b, c] = [self.a, self.b, self.c].map(|p| mid(p, r));
        Node {
            a,
            b,
            c,
            depth: self.depth,
        }
    }

    /// Pushes the node's four children, from its reference points `uv` ([`Node::net`]),
    /// in reverse so that the corner A child is examined first.
    fn push_children(&self, uv: [DVec2; 6], stack: &mut Vec<Node>) {
        let [a, b, c, ab, ac, bc] = uv;
        let depth = self.depth + 1;
        stack.push(Node {
            a: bc,
            b: ac,
            c: ab,
            depth,
        });
        stack.push(Node {
            a: ac,
            b: bc,
            c,
            depth,
        });
        stack.push(Node {
            a: ab,
            b,
            c: bc,
            depth,
        });
        stack.push(Node {
            a,
            b: ab,
            c: ac,
            depth,
        });
    }
}

impl RayFrame {
    #[inline]
    fn eval(&self, p: DVec2) -> DVec3 {
        DVec3::new(
            self.q[0].eval(p.x, p.y),
            self.q[1].eval(p.x, p.y),
            self.q[2].eval(p.x, p.y),
        )
    }

    /// Whether the sub-triangle with these six reference points may hold a root with `t`
    /// in [t_lo, t_hi]: the box of its Bézier net contains the origin of (Q1, Q2) and
    /// meets the range of t.
    ///
    /// With `hull`, the origin must also lie within the net's convex hull in the (Q1, Q2)
    /// plane (up to the slack), a tighter test that prunes the sub-triangles along a ray
    /// grazing the surface, where the box holds the origin down to tiny sub-triangles.
    fn may_hold_root(&self, uv: &[DVec2; 6], t_lo: f64, t_hi: f64, hull: bool) -> bool {
        let net = bezier_controls(&uv.map(|p| self.eval(p)));
        let (mut lo, mut hi) = (net[0], net[0]);
        for p in &net[1..] {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let s = self.slack;
        let boxed = lo.x <= s
            && hi.x >= -s
            && lo.y <= s
            && hi.y >= -s
            && hi.z >= t_lo - s
            && lo.z <= t_hi + s;
        boxed && !(hull && separated(&net.map(|p| p.truncate()), s))
    }

    /// Whether the Jacobian determinant of (Q1, Q2) keeps one strict sign on the triangle
    /// with these six reference points (its Bernstein coefficients all share it).
    fn jacobian_is_regular(&self, uv: &[DVec2; 6]) -> bool {
        let det = uv.map(|p| {
            let (a, b) = self.q[0].grad(p.x, p.y);
            let (c, d) = self.q[1].grad(p.x, p.y);
            a * d - b * c
        });
        let net = [
            det[0],
            det[1],
            det[2],
            2.0 * det[3] - 0.5 * (det[0] + det[1]),
            2.0 * det[4] - 0.5 * (det[0] + det[2]),
            2.0 * det[5] - 0.5 * (det[1] + det[2]),
        ];
        net.iter().all(|&x| x > 0.0) || net.iter().all(|&x| x < 0.0)
    }

    /// 2D Newton on (Q1, Q2) from `start`, at most `iterations` steps; the root when the residual vanishes to the
    /// tolerance.
    fn newton(&self, start: DVec2, iterations: usize) -> Option<DVec2> {
        let (q1, q2) = (&self.q[0], &self.q[1]);
        let mut p = start;
        for _ in 0..iterations {
            let (f1, f2) = (q1.eval(p.x, p.y), q2.eval(p.x, p.y));
            let (a, b) = q1.grad(p.x, p.y);
            let (c, d) = q2.grad(p.x, p.y);
            let det = a * d - b * c;
            if det == 0.0 || !det.is_finite() {
                break;
            }
            let step = DVec2::new(f1 * d - f2 * b, a * f2 - c * f1) / det;
            p -= step;
            // Iterates far outside the domain will not come back to a root in it.
            if !(p.x > -1.0 && p.x < 2.0 && p.y > -1.0 && p.y < 2.0) {
                return None;
            }
            if step.x.abs() + step.y.abs() < 1e-15 {
                break;
            }
        }
        let tol = self.residual_tolerance;
        (q1.eval(p.x, p.y).abs() <= tol && q2.eval(p.x, p.y).abs() <= tol).then_some(p)
    }

    /// Keeps a root if it lies in the domain (within the tolerance, then clamped onto it),
    /// has `t` in [t_lo, t_hi] and is not a root already kept; the root kept.
    fn keep(&self, p: DVec2, t_lo: f64, t_hi: f64, roots: &mut Vec<Root>) -> Option<Root> {
        let tol = DOMAIN_TOLERANCE;
        if p.x < -tol || p.y < -tol || p.x + p.y > 1.0 + tol {
            return None;
        }
        let (mut u, mut v) = (p.x.max(0.0), p.y.max(0.0));
        let excess = u + v - 1.0;
        if excess > 0.0 {
            u = (u - 0.5 * excess).max(0.0);
            v = (1.0 - u).min(v);
        }
        if roots
            .iter()
            .any(|r| (r.u - u).abs() + (r.v - v).abs() < SAME_ROOT_UV)
        {
            return None;
        }
        let t = self.q[2].eval(u, v);
        if t >= t_lo && t <= t_hi {
            let root = Root { t, u, v };
            roots.push(root);
            return Some(root);
        }
        None
    }
}

/// The quadratic `axis · (b(u, v) - origin)`.
fn along(position: &Quadratic3<f64>, axis: DVec3, origin: DVec3) -> Quadratic<f64> {
    let dot = |f: fn(&Quadratic<f64>) -> f64| {
        axis.dot(DVec3::new(
            f(&position[0]),
            f(&position[1]),
            f(&position[2]),
        ))
    };
    Quadratic {
        a: dot(|q| q.a),
        b: dot(|q| q.b),
        c: dot(|q| q.c),
        d: dot(|q| q.d),
        e: dot(|q| q.e),
        f: axis.dot(DVec3::new(position[0].f, position[1].f, position[2].f) - origin),
    }
}

/// Whether the origin lies farther than `slack` from the convex hull of `points`: the
/// distance from a point to a convex polygon is attained along an edge's normal or towards
/// a vertex, so those directions are tried, each as min over the points of their
/// projection on it.
fn separated(points: &[DVec2; 6], slack: f64) -> bool {
    let margin = |d: DVec2| {
        points
            .iter()
            .map(|p| d.dot(*p))
            .fold(f64::INFINITY, f64::min)
    };
    for (i, p) in points.iter().enumerate() {
        let len = p.length();
        if len > 0.0 && margin(*p / len) > slack {
            return true;
        }
        for q in &points[i + 1..] {
            let n = (*q - *p).perp();
            let len = n.length();
            if len > 0.0 {
                let n = n / len;
                // The side of the line the points are on, facing away from the origin.
                let n = if n.dot(*p) >= 0.0 { n } else { -n };
                if margin(n) > slack {
                    return true;
                }
            }
        }
    }
    false
}

#[inline]
fn mid(p: DVec2, q: DVec2) -> DVec2 {
    0.5 * (p + q)
}

/// Whether `p` lies in the node's triangle, with a slack of 1e-6 of its size.
fn inside_triangle(p: DVec2, node: &Node) -> bool {
    let (e1, e2, r) = (node.b - node.a, node.c - node.a, p - node.a);
    let det = e1.perp_dot(e2);
    let s = r.perp_dot(e2) / det;
    let t = e1.perp_dot(r) / det;
    let slack = 1e-6;
    s >= -slack && t >= -slack && s + t <= 1.0 + slack
}
