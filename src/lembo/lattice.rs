//! The level-n lattice of a lembo's domain, evaluated so that neighbours share their points
//! bit for bit (the tessellation's "Shared edges", [`super::tessellate`]): corners copied,
//! edge points from the edge's own three points in canonical order, interior points from the
//! lembo's functions; and the subdivision of a lembo into 4^s lembos on that lattice
//! ([`subdivide`], [`subdivided`]), which the scene's subdivided objects make on demand.

use super::construct::canonical_order;
use super::Lembo;
use glam::DVec3;
use std::cmp::Ordering;

/// A lattice point evaluated: position [world units] and unit normal.
pub(super) type Vertex = (DVec3, DVec3);

/// The lattice point (a, b) of lembo `l` at level n: copied at corners, from the edge's own
/// three points on domain edges, from the lembo's functions inside (the module's "Shared
/// edges").
pub(super) fn lattice_vertex(l: &Lembo, a: u32, b: u32, n: u32) -> Vertex {
    debug_assert!(a + b <= n);
    match (a, b) {
        (0, 0) => corner(l, 0),
        (a, 0) if a == n => corner(l, 1),
        (0, b) if b == n => corner(l, 2),
        // Steps counted from the edge's first end in EDGES: A for AB and AC, B for BC.
        (a, 0) => edge_point(l, EDGES[0], a, n),
        (0, b) => edge_point(l, EDGES[1], b, n),
        (_, b) if a + b == n => edge_point(l, EDGES[2], b, n),
        (a, b) => {
            let (u, v) = (a as f64 / n as f64, b as f64 / n as f64);
            (l.position_at(u, v), l.unit_normal_at(u, v))
        }
    }
}

/// The largest accepted subdivision of a lembo: 4^5 = 1024 lembos each.
pub const MAX_SUBDIVIDE: u32 = 5;

/// Lembo `l` subdivided `s` times: 4^s lembos over the same surface, each the quadratic
/// patch of one triangle of the level-2^s lattice (the tessellation's local order), its six
/// construction points and unit normals taken from the level-2^(s+1) lattice, so that
/// neighbours (within `l` and across its edges) share their edge points bit for bit.
/// A quadratic restricted to a sub-triangle is a quadratic, so the positions are the
/// parent's; the normals are its unit normals at the six points (the normal function
/// interpolates them, as a lembo built from a mesh interpolates its vertex normals).
pub fn subdivide(l: &Lembo, s: u32, out: &mut Vec<Lembo>) {
    out.extend((0..1usize << (2 * s)).map(|k| subdivided(l, s, k)));
}

/// Lembo `k` of the 4^s lembos [`subdivide`] makes of `l`, made alone: rows of the lattice
/// from edge AB towards C, in each row an up triangle then a down one, left to right.
pub fn subdivided(l: &Lembo, s: u32, k: usize) -> Lembo {
    debug_assert!(s <= MAX_SUBDIVIDE && k < 1 << (2 * s));
    let m = 1u32 << s;
    let n = 2 * m;
    // Row b holds m - b up triangles and m - b - 1 down ones, alternating.
    let (mut b, mut k) = (0, k as u32);
    while k >= 2 * (m - b) - 1 {
        k -= 2 * (m - b) - 1;
        b += 1;
    }
    let (a2, b2) = (2 * (k / 2), 2 * b);
    let points = if k % 2 == 0 {
        // Up: A (a, b), B (a + 1, b), C (a, b + 1); D, E, F the middles of AB, AC, BC.
        [
            (a2, b2),
            (a2 + 2, b2),
            (a2, b2 + 2),
            (a2 + 1, b2),
            (a2, b2 + 1),
            (a2 + 1, b2 + 1),
        ]
    } else {
        // Down: A (a + 1, b), B (a + 1, b + 1), C (a, b + 1).
        [
            (a2 + 2, b2),
            (a2 + 2, b2 + 2),
            (a2, b2 + 2),
            (a2 + 2, b2 + 1),
            (a2 + 1, b2 + 1),
            (a2 + 1, b2 + 2),
        ]
    };
    let v = points.map(|(a, b)| lattice_vertex(l, a, b, n));
    Lembo::new(v.map(|v| v.0), v.map(|v| v.1))
}

/// The domain edges as (first end, second end, middle) indices into a lembo's six points:
/// AB with middle D, AC with middle E, BC with middle F.
pub(super) const EDGES: [(usize, usize, usize); 3] = [(0, 1, 3), (0, 2, 4), (1, 2, 5)];

/// Corner `k` (A, B or C): the construction point itself and its normalised normal.
pub(super) fn corner(l: &Lembo, k: usize) -> Vertex {
    (l.points[k], l.normals[k].normalize_or_zero())
}

/// An edge's (start, middle, end) points with their construction normals, ends in
/// canonical order, and whether the ends were swapped from the order in [`EDGES`]. The
/// normals are not normalised, so along the edge they follow the lembo's normal function.
pub(super) fn canonical_edge(l: &Lembo, (p, q, m): (usize, usize, usize)) -> (bool, [Vertex; 3]) {
    let swapped = canonical_order(l.points[p], l.points[q]) == Ordering::Greater;
    let (p, q) = if swapped { (q, p) } else { (p, q) };
    (swapped, [p, m, q].map(|k| (l.points[k], l.normals[k])))
}

/// The point `step` of n along an edge from its first end in [`EDGES`], evaluated from the
/// canonical start so both lembos sharing the edge run the same arithmetic.
fn edge_point(l: &Lembo, edge: (usize, usize, usize), step: u32, n: u32) -> Vertex {
    let (swapped, [p, m, q]) = canonical_edge(l, edge);
    let i = if swapped { n - step } else { step };
    let t = i as f64 / n as f64;
    (
        quadratic_bezier(p.0, m.0, q.0, t),
        quadratic_bezier(p.1, m.1, q.1, t).normalize_or_zero(),
    )
}

/// The bits of some vectors, a hash key that tells apart every value the output can hold.
pub(super) fn key_bits<const N: usize>(vectors: [DVec3; N]) -> [[u64; 3]; N] {
    vectors.map(|v| v.to_array().map(f64::to_bits))
}

/// The quadratic through `p` (t = 0), `m` (t = ½) and `q` (t = 1) at `t`, as a Bézier curve
/// with control point 2m − (p + q)/2. One fixed expression: the crack-freedom of shared
/// edges rests on both sides evaluating exactly this.
fn quadratic_bezier(p: DVec3, m: DVec3, q: DVec3, t: f64) -> DVec3 {
    let control = 2.0 * m - 0.5 * (p + q);
    let s = 1.0 - t;
    s * s * p + 2.0 * t * s * control + t * t * q
}
