//! The exact reference renderer (DESIGN.md §6): per sample, the ray against the true
//! world-space lembo, in `f64`, with no projection approximation.
//!
//! A ray is the intersection of two planes through it, with unit normals `n1` and `n2`
//! perpendicular to its direction `d` and to each other. On a lembo `b(u, v)` the planes
//! give two conics in the domain,
//!
//! ```text
//!   Q1(u, v) = n1 · (b(u, v) - O) = 0        Q2(u, v) = n2 · (b(u, v) - O) = 0
//! ```
//!
//! whose common roots in `u >= 0, v >= 0, u + v <= 1` are the hits, at ray parameter
//! `t = d · (b(u, v) - O)`. The roots are isolated by recursive subdivision of the domain
//! triangle: the map `(u, v) -> (Q1, Q2, t)` restricted to a sub-triangle is again a
//! quadratic triangle, whose Bézier control net (from its values at the corners and edge
//! midpoints) bounds it. A sub-triangle whose net's box excludes the origin of the (Q1, Q2)
//! plane, or lies outside the wanted range of `t`, holds no root. Otherwise 2D Newton runs
//! from the sub-triangle's centroid. When it converges to a root `r` (inside the
//! sub-triangle or not), the sub-triangle holds no other root if the Jacobian J of
//! (Q1, Q2) is regular on the triangle halfway between it and `r`, because for a quadratic
//! map `F(x) - F(r) = J((x + r) / 2) (x - r)` exactly; the determinant is a quadratic whose
//! Bernstein coefficients show a strict sign. Elsewhere (near the silhouette, where the ray
//! grazes the surface and two roots merge) subdivision continues down to a uv size of
//! 2^-20, where Newton runs from the centroid of every surviving sub-triangle.
//!
//! Roots within [`DOMAIN_TOLERANCE`] of the domain are kept and clamped onto it, so a ray
//! through a shared edge hits both neighbours; roots closer than [`SAME_ROOT_UV`] in uv
//! are one root.
//!
//! The image: per lembo, the Bézier control net is projected once; a lembo whose net has
//! a point at or behind the eye (`w <= 0`) is tested at every sample, otherwise only at the
//! samples inside the net's screen box, found through 16 x 16 pixel tiles whose lists are
//! sorted nearest first, so that an early hit bounds the range of `t` searched in the rest.
//! The nearest hit with `t > 0` and depth in [0, 1] wins, ties going to the smaller lembo
//! index as in the rasterizer's depth test, and is shaded with the exact unit normal of the
//! normal function.
//! Rows are rendered in parallel; every sample is computed by the same sequential code, so
//! the image does not depend on the thread count.
//!
//! The same machinery answers at any screen position ([`Tracer`]), which the accuracy
//! metrics use between pixel centres. [`Tracer::covers`] asks only whether a ray hits: it
//! stops at the first root Newton finds inside a sub-triangle (no uniqueness proof), and
//! also prunes sub-triangles whose Bézier net's convex hull in the (Q1, Q2) plane excludes
//! the origin, which the box test cannot do for rays grazing the surface until the
//! sub-triangles are tiny. The image keeps the box test alone.

use crate::camera::View;
use crate::lembo::{bezier_controls, Lembo, Quadratic, Quadratic3};
use crate::rop::shade::{to_u8, Shader};
use crate::scene::Light;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

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
/// Side of the square screen tiles that lembos are binned into \[pixels\].
const TILE: u32 = 16;

/// The winning surface at a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceHit {
    /// Depth in [0, 1] of the hit point, as [`View::depth_of`] gives it.
    pub depth: f64,
    /// Unit normal of the normal function at (u, v), as shaded before the two-sided flip
    /// (zero where the normal function vanishes).
    pub normal: DVec3,
    /// Index of the lembo in [`ReferenceInput::lembos`].
    pub lembo: u32,
    /// Domain coordinates of the hit.
    pub u: f64,
    /// Domain v of the hit.
    pub v: f64,
}

/// The reference image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceImage {
    /// Width \[pixels\].
    pub width: u32,
    /// Height \[pixels\].
    pub height: u32,
    /// Sub-samples per pixel side `s` (1 = the pixel centre only).
    pub supersample: u32,
    /// The hit at each pixel's point (i + 0.5, j + 0.5) + [`Self::hits_offset_px`].
    pub hits: Vec<Option<ReferenceHit>>,
    /// Where `hits` were traced from the pixel centres \[pixels\]: (0, 0), or for a
    /// multisampled run's reference ([`Self::for_samples`]) the offset of the sample a
    /// resolved frame keeps its depth, winner and normal from.
    pub hits_offset_px: [f64; 2],
    /// The colour a render is compared with: the pixel centre shaded (the background where
    /// nothing is hit), or for a multisampled run's reference the area-averaged colour.
    pub color: Vec<[u8; 3]>,
    /// The mean of the s x s sub-samples' linear colours (a box filter), when s > 1.
    pub color_supersampled: Option<Vec<[u8; 3]>>,
    /// The fraction of the s x s sub-samples that hit a surface, when s > 1.
    pub coverage: Option<Vec<f32>>,
}

impl ReferenceImage {
    /// The centre-sample colour buffer as an `image` RGB8 image.
    pub fn to_image(&self) -> image::RgbImage {
        rgb_image(self.width, self.height, &self.color)
    }

    /// This supersampled reference made the reference of a multisampled render: its hits
    /// those of `at_sample`, the same scene traced from the pixel centres moved by `offset`
    /// \[pixels\] (where the resolved frame keeps its depth, winner and normal), and its
    /// colours the area-averaged ones, which a resolve approximates (DESIGN.md §6).
    ///
    /// # Panics
    /// If this reference is not supersampled, or the two differ in size: bugs of the caller.
    pub fn for_samples(mut self, at_sample: ReferenceImage, offset: [f64; 2]) -> ReferenceImage {
        assert_eq!(
            (self.width, self.height),
            (at_sample.width, at_sample.height)
        );
        self.color = self
            .color_supersampled
            .clone()
            .expect("a multisampled run's reference is supersampled");
        self.hits = at_sample.hits;
        self.hits_offset_px = offset;
        self
    }

    /// This supersampled reference with the area-averaged colours as the colours a render is
    /// compared with, its hits staying at the pixel centres: the target of a one-sample
    /// render measured beside multisampled ones (a sweep with `samples` on an axis).
    ///
    /// # Panics
    /// If this reference is not supersampled: a bug of the caller.
    pub fn with_area_colours(mut self) -> ReferenceImage {
        self.color = self
            .color_supersampled
            .clone()
            .expect("an area-averaged target is supersampled");
        self
    }

    /// The box-filtered colour buffer, when supersampled.
    pub fn to_image_supersampled(&self) -> Option<image::RgbImage> {
        self.color_supersampled
            .as_ref()
            .map(|c| rgb_image(self.width, self.height, c))
    }
}

fn rgb_image(width: u32, height: u32, color: &[[u8; 3]]) -> image::RgbImage {
    let raw: Vec<u8> = color.iter().flatten().copied().collect();
    image::RgbImage::from_raw(width, height, raw).expect("buffer matches its size")
}

/// What the reference renders.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceInput<'a> {
    /// Each lembo with its linear RGB colour in [0, 1]; the index is the lembo id.
    pub lembos: &'a [(&'a Lembo, [f64; 3])],
    /// The camera and viewport.
    pub view: &'a View,
    /// The light and material terms.
    pub light: &'a Light,
    /// Linear RGB in [0, 1] where nothing is hit.
    pub background: [f64; 3],
    /// Sub-samples per pixel side (1 = the pixel centre only; 0 is taken as 1).
    pub supersample: u32,
}

/// All intersections of the line `origin + t dir` with the lembo inside its domain, as
/// `(t, u, v)` sorted by `t`, including any behind the origin (`t < 0`); callers that want
/// a ray filter on `t`. `t` is in units of `dir`, so `origin + t dir` is the hit point
/// (up to the solver's tolerance) whatever the length of `dir`; a zero or non-finite `dir`
/// gives no hits.
pub fn intersect_ray(lembo: &Lembo, origin: DVec3, dir: DVec3) -> Vec<(f64, f64, f64)> {
    let len = dir.length();
    if !(len > 0.0 && len.is_finite()) {
        return Vec::new();
    }
    let patch = Patch::new(lembo);
    let mut scratch = Scratch::default();
    let mut roots = Vec::new();
    patch.roots(
        origin,
        dir / len,
        f64::NEG_INFINITY,
        f64::INFINITY,
        &mut scratch,
        &mut roots,
    );
    let mut hits: Vec<(f64, f64, f64)> = roots.iter().map(|r| (r.t / len, r.u, r.v)).collect();
    hits.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then(a.1.total_cmp(&b.1))
            .then(a.2.total_cmp(&b.2))
    });
    hits
}

/// Renders the reference image: the centre sample of every pixel and, when
/// `supersample > 1`, an s x s grid of sub-samples at ((a + 0.5) / s, (b + 0.5) / s) within
/// the pixel.
pub fn render_reference(input: &ReferenceInput) -> ReferenceImage {
    let (width, height) = (input.view.viewport.width, input.view.viewport.height);
    let s = input.supersample.max(1);
    let scene = Scene::new(input);
    let rows: Vec<Row> = (0..height)
        .into_par_iter()
        .map(|j| scene.render_row(j, s))
        .collect();

    let n = width as usize * height as usize;
    let mut image = ReferenceImage {
        width,
        height,
        supersample: s,
        hits: Vec::with_capacity(n),
        hits_offset_px: [0.0; 2],
        color: Vec::with_capacity(n),
        color_supersampled: (s > 1).then(|| Vec::with_capacity(n)),
        coverage: (s > 1).then(|| Vec::with_capacity(n)),
    };
    for row in rows {
        image.hits.extend(row.hits);
        image.color.extend(row.color);
        if let (Some(all), Some(part)) = (image.color_supersampled.as_mut(), row.color_supersampled)
        {
            all.extend(part);
        }
        if let (Some(all), Some(part)) = (image.coverage.as_mut(), row.coverage) {
            all.extend(part);
        }
    }
    image
}

/// One root of (Q1, Q2) in the domain.
#[derive(Clone, Copy, Debug)]
struct Root {
    t: f64,
    u: f64,
    v: f64,
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
struct Scratch {
    stack: Vec<Node>,
    roots: Vec<Root>,
}

/// A lembo prepared for ray tests: its Bézier control net and size.
struct Patch<'a> {
    lembo: &'a Lembo,
    controls: [DVec3; 6],
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
    fn new(lembo: &'a Lembo) -> Self {
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
    fn roots(
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
    fn any_root(
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
        let (n1, n2) = dir.any_orthonormal_pair();
        let position = &self.lembo.position;
        let size = (self.controls[0] - origin).length() + self.extent;
        let frame = RayFrame {
            q: [
                along(position, n1, origin),
                along(position, n2, origin),
                along(position, dir, origin),
            ],
            residual_tolerance: RESIDUAL_TOLERANCE * size,
            slack: BOX_SLACK * size,
        };
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
            let uv = [
                node.a,
                node.b,
                node.c,
                mid(node.a, node.b),
                mid(node.a, node.c),
                mid(node.b, node.c),
            ];
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
                let half = [node.a, node.b, node.c].map(|p| mid(p, r));
                let half = [
                    half[0],
                    half[1],
                    half[2],
                    mid(half[0], half[1]),
                    mid(half[0], half[2]),
                    mid(half[1], half[2]),
                ];
                if frame.jacobian_is_regular(&half) {
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
            let [a, b, c, ab, ac, bc] = uv;
            let depth = node.depth + 1;
            // Pushed in reverse so the corner A child is examined first.
            scratch.stack.push(Node {
                a: bc,
                b: ac,
                c: ab,
                depth,
            });
            scratch.stack.push(Node {
                a: ac,
                b: bc,
                c,
                depth,
            });
            scratch.stack.push(Node {
                a: ab,
                b,
                c: bc,
                depth,
            });
            scratch.stack.push(Node {
                a,
                b: ab,
                c: ac,
                depth,
            });
        }
        false
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

/// Where a lembo can appear on screen.
#[derive(Clone, Copy, Debug)]
enum Footprint {
    /// Part of the control net is at or behind the eye: test every sample.
    Everywhere,
    /// The screen box of the projected control net \[pixels\] and its nearest depth.
    Box {
        x0: f64,
        y0: f64,
        x1: f64,
        y1: f64,
        z0: f64,
    },
}

impl Footprint {
    #[inline]
    fn contains(&self, x: f64, y: f64) -> bool {
        match *self {
            Footprint::Everywhere => true,
            Footprint::Box { x0, y0, x1, y1, .. } => x >= x0 && x <= x1 && y >= y0 && y <= y1,
        }
    }
}

/// Slack on screen boxes \[pixels\]: the hit of a sample on the box's edge projects to it
/// only up to rounding.
const SCREEN_SLACK: f64 = 1e-6;

/// The footprint of a lembo, or `None` when it cannot be visible (outside the viewport or
/// the depth range).
fn footprint(patch: &Patch, view: &View) -> Option<Footprint> {
    let projected = patch.controls.map(|c| view.project(c));
    if projected.iter().any(|p| p.w <= 0.0 || p.w.is_nan()) {
        return Some(Footprint::Everywhere);
    }
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    let (mut z0, mut z1) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &projected {
        (x0, x1, y0, y1) = (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y));
        (z0, z1) = (z0.min(p.depth), z1.max(p.depth));
    }
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    let s = SCREEN_SLACK;
    let (x0, y0, x1, y1) = (x0 - s, y0 - s, x1 + s, y1 + s);
    let outside = x1 < 0.0 || y1 < 0.0 || x0 > w || y0 > h || z1 < -s || z0 > 1.0 + s;
    (!outside).then_some(Footprint::Box { x0, y0, x1, y1, z0 })
}

/// The lembos prepared for ray queries at any screen position: patches, footprints and the
/// lembos binned per tile. The reference image samples it at fixed positions; the accuracy
/// metrics ask it about any point (the sub-pixel silhouette, `metrics.rs`).
pub struct Tracer<'a> {
    view: &'a View,
    patches: Vec<Patch<'a>>,
    footprints: Vec<Option<Footprint>>,
    tiles_x: u32,
    tiles_y: u32,
    /// Per tile, the lembos whose footprint meets it, nearest first.
    bins: Vec<Vec<u32>>,
}

/// Buffers a [`Tracer`] reuses from query to query (one per thread).
#[derive(Default)]
pub struct TraceScratch {
    scratch: Scratch,
    roots: Vec<Root>,
}

impl<'a> Tracer<'a> {
    /// The lembos (index = lembo id) seen by `view`.
    pub fn new(lembos: impl IntoIterator<Item = &'a Lembo>, view: &'a View) -> Self {
        let patches: Vec<Patch> = lembos.into_iter().map(Patch::new).collect();
        let footprints: Vec<Option<Footprint>> =
            patches.iter().map(|p| footprint(p, view)).collect();
        let tiles_x = view.viewport.width.div_ceil(TILE);
        let tiles_y = view.viewport.height.div_ceil(TILE);
        let mut bins = vec![Vec::new(); (tiles_x * tiles_y) as usize];
        for (id, f) in footprints.iter().enumerate() {
            let Some(f) = f else { continue };
            let (tx0, ty0, tx1, ty1) = match *f {
                Footprint::Everywhere => (0, 0, tiles_x - 1, tiles_y - 1),
                Footprint::Box { x0, y0, x1, y1, .. } => {
                    let tile =
                        |x: f64, n: u32| ((x / TILE as f64).floor().max(0.0) as u32).min(n - 1);
                    (
                        tile(x0, tiles_x),
                        tile(y0, tiles_y),
                        tile(x1, tiles_x),
                        tile(y1, tiles_y),
                    )
                }
            };
            for ty in ty0..=ty1 {
                for tx in tx0..=tx1 {
                    bins[(ty * tiles_x + tx) as usize].push(id as u32);
                }
            }
        }
        // Nearest first, so that the hits found early bound the search of the rest.
        let near = |id: &u32| match footprints[*id as usize] {
            Some(Footprint::Box { z0, .. }) => z0,
            _ => f64::NEG_INFINITY,
        };
        for bin in &mut bins {
            bin.sort_by(|a, b| near(a).total_cmp(&near(b)).then(a.cmp(b)));
        }
        Tracer {
            view,
            patches,
            footprints,
            tiles_x,
            tiles_y,
            bins,
        }
    }

    /// The lembos of the tile holding screen position (x, y), clamped into the viewport.
    fn bin_at(&self, x: f64, y: f64) -> &[u32] {
        let tile = |x: f64, n: u32| ((x / TILE as f64).floor().max(0.0) as u32).min(n - 1);
        let (tx, ty) = (tile(x, self.tiles_x), tile(y, self.tiles_y));
        &self.bins[(ty * self.tiles_x + tx) as usize]
    }

    /// The nearest hit at screen position (x, y) [pixels; pixel (i, j)'s centre is
    /// (i + 0.5, j + 0.5)], as the reference image's samples are computed: at a pixel centre
    /// it is that pixel's `hits` entry. Positions outside the viewport see only the lembos
    /// whose footprint meets the viewport.
    pub fn hit(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> Option<ReferenceHit> {
        let bin = self.bin_at(x, y);
        self.trace(x, y, bin, &mut scratch.scratch, &mut scratch.roots)
    }

    /// Whether the ray through screen position (x, y) \[pixels\] hits a surface: the same
    /// condition as [`Tracer::hit`] being `Some` (a root with t > 0 and depth in [0, 1]),
    /// decided at the first such root found, which makes rays grazing an outline far
    /// cheaper to answer.
    pub fn covers(&self, x: f64, y: f64, scratch: &mut TraceScratch) -> bool {
        let view = self.view;
        let (origin, dir) = view.ray(x, y);
        for &id in self.bin_at(x, y) {
            let footprint = self.footprints[id as usize].expect("binned lembos have a footprint");
            if !footprint.contains(x, y) {
                continue;
            }
            let patch = &self.patches[id as usize];
            let mut accept = |r: &Root| {
                r.t > 0.0 && (0.0..=1.0).contains(&view.depth_of(patch.lembo.position_at(r.u, r.v)))
            };
            if patch.any_root(
                origin,
                dir,
                0.0,
                f64::INFINITY,
                &mut scratch.scratch,
                &mut accept,
            ) {
                return true;
            }
        }
        false
    }

    /// The nearest hit at screen position (x, y) \[pixels\] among the lembos of `bin`.
    fn trace(
        &self,
        x: f64,
        y: f64,
        bin: &[u32],
        scratch: &mut Scratch,
        roots: &mut Vec<Root>,
    ) -> Option<ReferenceHit> {
        let view = self.view;
        let (origin, dir) = view.ray(x, y);
        let mut best: Option<ReferenceHit> = None;
        let mut best_t = f64::INFINITY;
        for &id in bin {
            let footprint = self.footprints[id as usize].expect("binned lembos have a footprint");
            if !footprint.contains(x, y) {
                continue;
            }
            let patch = &self.patches[id as usize];
            roots.clear();
            patch.roots(origin, dir, 0.0, best_t, scratch, roots);
            for r in roots.iter() {
                if r.t <= 0.0 || r.t.is_nan() {
                    continue;
                }
                let depth = view.depth_of(patch.lembo.position_at(r.u, r.v));
                let nearer =
                    best.is_none_or(|b| depth < b.depth || (depth == b.depth && id < b.lembo));
                if (0.0..=1.0).contains(&depth) && nearer {
                    best_t = r.t;
                    best = Some(ReferenceHit {
                        depth,
                        normal: patch.lembo.unit_normal_at(r.u, r.v),
                        lembo: id,
                        u: r.u,
                        v: r.v,
                    });
                }
            }
        }
        best
    }
}

/// The prepared scene: the tracer, the colours and the shader.
struct Scene<'a> {
    input: &'a ReferenceInput<'a>,
    tracer: Tracer<'a>,
    shader: Shader<f64>,
    background: [f64; 3],
}

/// One rendered row.
struct Row {
    hits: Vec<Option<ReferenceHit>>,
    color: Vec<[u8; 3]>,
    color_supersampled: Option<Vec<[u8; 3]>>,
    coverage: Option<Vec<f32>>,
}

impl<'a> Scene<'a> {
    fn new(input: &'a ReferenceInput<'a>) -> Self {
        Scene {
            input,
            tracer: Tracer::new(input.lembos.iter().map(|(l, _)| *l), input.view),
            shader: Shader::new(input.light),
            background: input.background,
        }
    }

    /// Linear RGB of a sample.
    fn shade(&self, hit: &Option<ReferenceHit>) -> [f64; 3] {
        match hit {
            None => self.background,
            Some(h) => {
                let p = self.tracer.patches[h.lembo as usize]
                    .lembo
                    .position_at(h.u, h.v);
                let to_eye = self.input.view.to_eye(p);
                let color = self.input.lembos[h.lembo as usize].1;
                self.shader
                    .shade(h.normal.to_array(), to_eye.to_array(), color)
            }
        }
    }

    fn render_row(&self, j: u32, s: u32) -> Row {
        let width = self.input.view.viewport.width;
        let mut scratch = Scratch::default();
        let mut roots = Vec::new();
        let mut row = Row {
            hits: Vec::with_capacity(width as usize),
            color: Vec::with_capacity(width as usize),
            color_supersampled: (s > 1).then(|| Vec::with_capacity(width as usize)),
            coverage: (s > 1).then(|| Vec::with_capacity(width as usize)),
        };
        let quantise = |c: [f64; 3]| c.map(to_u8);
        let ty = j / TILE;
        for i in 0..width {
            let bin = &self.tracer.bins[(ty * self.tracer.tiles_x + i / TILE) as usize];
            let (x, y) = (i as f64, j as f64);
            // For odd s the middle sub-sample is the pixel centre, (k + 0.5) / (2k + 1) = 0.5
            // exactly, so it is traced once.
            let centre_in_grid = s > 1 && s % 2 == 1;
            let centre = if centre_in_grid {
                None
            } else {
                Some(
                    self.tracer
                        .trace(x + 0.5, y + 0.5, bin, &mut scratch, &mut roots),
                )
            };
            let mut centre_hit = centre.flatten();
            if s > 1 {
                let mut sum = [0.0; 3];
                let mut covered = 0u32;
                for b in 0..s {
                    for a in 0..s {
                        let sx = x + (a as f64 + 0.5) / s as f64;
                        let sy = y + (b as f64 + 0.5) / s as f64;
                        let hit = self.tracer.trace(sx, sy, bin, &mut scratch, &mut roots);
                        if centre_in_grid && a == s / 2 && b == s / 2 {
                            centre_hit = hit;
                        }
                        covered += hit.is_some() as u32;
                        let c = self.shade(&hit);
                        for k in 0..3 {
                            sum[k] += c[k];
                        }
                    }
                }
                let n = (s * s) as f64;
                row.color_supersampled
                    .as_mut()
                    .expect("s > 1")
                    .push(quantise(sum.map(|c| c / n)));
                row.coverage
                    .as_mut()
                    .expect("s > 1")
                    .push(covered as f32 / n as f32);
            }
            row.color.push(quantise(self.shade(&centre_hit)));
            row.hits.push(centre_hit);
        }
        row
    }
}

#[cfg(test)]
mod tests;
