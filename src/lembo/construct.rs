//! Construction of lembos from triangles with vertex normals (Martinelli 2006, section 2).
//!
//! The edge midpoint comes from the near-least-squares quadratic edge of Barrera, Hast and
//! Bengtsson ("Surface construction with near least square acceleration", SIGRAD 2002) as
//! Martinelli prints it, with two repairs (DESIGN.md §13, "How the extreme method is completed"):
//! - the printed `T2 = -N1 - N2 (N1·N2)` is not tangent at P2; we use the tangent
//!   `T2 = -N1 + N2 (N1·N2)` (the mirror image of `T1`), which makes the construction
//!   symmetric and reproduces circular arcs' tangents on a sphere;
//! - `alpha * beta` simplifies to `(P·T1)/(T1·T1)` and `alpha' * beta'` to
//!   `(P·T2)/(T2·T2)`, which removes the division by `T1·T2` (zero for perpendicular end
//!   normals); a vanishing tangent (parallel end normals) contributes nothing, so parallel
//!   normals give a straight edge.
//!
//! The edge mid-normal is the PN-triangle mid-normal (the paper: "in the similar way used for
//! PN Triangles"): the average end normal reflected in the plane perpendicular to the edge.
//!
//! Both are computed from the edge's two end points in a canonical order (the smaller
//! position first, compared coordinate by coordinate), so two lembos that share an edge get
//! bit-identical edge points whatever their winding.
//!
//! A mesh with hard edges (split vertices: one position, a different normal on each side)
//! would still give two different midpoints for one edge, each side's from its own normals,
//! and the surface would leak between them. [`TriangleMesh::to_lembos`] therefore welds
//! positions ([`WELD_RELATIVE`]) and gives every lembo on an edge one shared midpoint: the
//! average of the distinct midpoints its sides compute (the quadratic analogue of PN-AEN,
//! McDonald and Kilgard 2010), which is today's midpoint where the sides agree. Shading
//! normals stay each side's own. [`TriangleMesh::with_crease_angle`] computes split normals
//! from a crease angle (auto-smooth).

use super::Lembo;
use glam::DVec3;
use std::cmp::Ordering;

/// The point and normal in the middle of the curved edge from `p1` (normal `n1`) to `p2`
/// (normal `n2`), computed in a canonical order of the two ends.
pub fn edge_midpoint(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> (DVec3, DVec3) {
    let (p1, n1, p2, n2) = canonical_ends(p1, n1, p2, n2);
    edge_midpoint_ordered(p1, n1, p2, n2)
}

/// An edge's two ends (position and normal) in [`canonical_order`] of their positions.
fn canonical_ends(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> (DVec3, DVec3, DVec3, DVec3) {
    if canonical_order(p1, p2) == Ordering::Greater {
        (p2, n2, p1, n1)
    } else {
        (p1, n1, p2, n2)
    }
}

/// Total order on positions used to make edge computations independent of winding.
pub fn canonical_order(p: DVec3, q: DVec3) -> Ordering {
    p.x.total_cmp(&q.x)
        .then(p.y.total_cmp(&q.y))
        .then(p.z.total_cmp(&q.z))
}

/// The most words [`bits_key`] hashes: the nine coordinates of a curve's three points.
pub const BITS_KEY_WORDS: usize = 9;

/// A 128-bit hash of a key made of coordinates' bits (an edge's corners, a curve's three
/// points; at most [`BITS_KEY_WORDS`] words), the same in every run and on every host:
/// XXH3-128 (seed 0) of the words' little-endian bytes. Lembos' edges are matched by it,
/// sorted, 32 bytes an edge's use instead of a map of the whole keys; two different keys
/// would be taken for one only if their hashes collided, which for a hash that behaves as a
/// random function happens with a probability below 2^-85 among the 3 x 2^20 edge uses of
/// 2^20 lembos ((3 x 2^20)² / 2^129).
///
/// # Panics
/// If `words` holds more than [`BITS_KEY_WORDS`] (a bug of the caller).
pub fn bits_key(words: &[u64]) -> u128 {
    assert!(
        words.len() <= BITS_KEY_WORDS,
        "a bits key holds at most {BITS_KEY_WORDS} words"
    );
    let mut bytes = [0u8; 8 * BITS_KEY_WORDS];
    for (b, w) in bytes.chunks_exact_mut(8).zip(words) {
        b.copy_from_slice(&w.to_le_bytes());
    }
    xxhash_rust::xxh3::xxh3_128(&bytes[..8 * words.len()])
}

/// The point in the middle of the curved edge of [`edge_midpoint`], without its normal: the
/// same bits as its point.
pub fn edge_midpoint_position(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> DVec3 {
    let (p1, n1, p2, n2) = canonical_ends(p1, n1, p2, n2);
    midpoint_position(p1, n1.normalize_or_zero(), p2, n2.normalize_or_zero())
}

/// The curved edge's midpoint from `p1` (unit normal `n1`) to `p2` (unit normal `n2`).
#[inline]
fn midpoint_position(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> DVec3 {
    let p = p2 - p1;
    let c = n1.dot(n2);
    let t1 = n2 - n1 * c;
    let t2 = -n1 + n2 * c;
    // alpha*beta*T1 and alpha'*beta'*T2: the projections of P on the two end tangents.
    let proj = |t: DVec3| {
        let tt = t.dot(t);
        if tt > 1e-24 {
            t * (p.dot(t) / tt)
        } else {
            DVec3::ZERO
        }
    };
    let (a1, a2) = (proj(t1), proj(t2));
    // f(t) = (a2 - a1)/2 t² + (P + (a1 - a2)/2) t + P1, so f(1/2) = P1 + P/2 + (a1 - a2)/8.
    p1 + 0.5 * p + 0.125 * (a1 - a2)
}

fn edge_midpoint_ordered(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> (DVec3, DVec3) {
    let n1 = n1.normalize_or_zero();
    let n2 = n2.normalize_or_zero();
    let mid = midpoint_position(p1, n1, p2, n2);
    let p = p2 - p1;
    let nsum = n1 + n2;
    let pp = p.dot(p);
    let v = if pp > 0.0 {
        2.0 * p.dot(nsum) / pp
    } else {
        0.0
    };
    let nmid = (nsum - v * p).normalize_or_zero();
    // Opposite end normals have no defined mid-normal; fall back to the first end's.
    let nmid = if nmid == DVec3::ZERO { n1 } else { nmid };
    (mid, nmid)
}

/// A lembo through the triangle `p` with vertex normals `n`: A, B, C are the vertices,
/// D, E, F the midpoints of edges AB, AC, BC.
pub fn lembo_from_triangle(p: [DVec3; 3], n: [DVec3; 3]) -> Lembo {
    let (d, nd) = edge_midpoint(p[0], n[0], p[1], n[1]);
    let (e, ne) = edge_midpoint(p[0], n[0], p[2], n[2]);
    let (f, nf) = edge_midpoint(p[1], n[1], p[2], n[2]);
    let unit = |v: DVec3| v.normalize_or_zero();
    Lembo::new(
        [p[0], p[1], p[2], d, e, f],
        [unit(n[0]), unit(n[1]), unit(n[2]), nd, ne, nf],
    )
}

/// How close two mesh positions must be to be welded into one, relative to the mesh's
/// bounding-box diagonal: 1e-9.
///
/// Welding decides which triangles share an edge (ends at the same welded positions), and
/// welded positions are snapped to one position, so shared edges are bit-identical. The
/// usual split vertex (an OBJ face corner `f 7//3` and its neighbour's `f 7//9`, or a
/// generator writing the same position twice) has bit-identical positions and welds at any
/// tolerance; the tolerance only decides what else welds. 1e-9 of the object's size is
/// far above the round-off of computing one position two ways in f64 (about 1e-16 of the
/// coordinates, which may be up to 10⁶ times the object's size away from the origin and
/// still weld) and far below anything visible (1e-9 × 16384 px, the largest viewport, is
/// 2e-5 px), so welding moves no vertex visibly; vertices that close are, for the image,
/// one vertex anyway (a triangle they would collapse is refused). Two positions weld when they are within the tolerance (Euclidean),
/// and welding is transitive (a chain of such pairs welds as one); unlike rounding
/// positions to a grid, no pair within the tolerance is ever split by a cell boundary.
pub const WELD_RELATIVE: f64 = 1e-9;

/// The weld's grid cells, in tolerances: wide enough that most vertices are near no face of
/// their cell and are compared with their own cell's vertices only.
const WELD_CELLS: f64 = 64.0;

/// An indexed triangle mesh with one normal per vertex. Vertices at the same position with
/// different normals (split vertices) make hard edges; [`TriangleMesh::to_lembos`] welds
/// them so the surface stays closed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Vertex normals, one per position.
    pub normals: Vec<DVec3>,
    /// Triangles as three vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// A triangle two of whose corners weld to the same position (or are the same vertex): it
/// has no area and no third edge, and is refused rather than drawn as a sliver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollapsedTriangle {
    /// Index of the triangle in the mesh.
    pub triangle: usize,
    /// The two corners (0, 1, 2 for A, B, C) that weld together.
    pub corners: [usize; 2],
    /// Their vertex indices.
    pub vertices: [u32; 2],
    /// The welded position.
    pub position: DVec3,
    /// The weld tolerance used [world units].
    pub tolerance: f64,
}

impl std::fmt::Display for CollapsedTriangle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = self.position;
        write!(
            f,
            "triangle {} (0-based, after triangulation): corners {} and {} (vertices {} and {}) \
             weld to the same position [{}, {}, {}] (positions within {:e} world units, \
             {WELD_RELATIVE:e} of the bounding-box diagonal, are one vertex); a triangle needs \
             three distinct corners",
            self.triangle,
            self.corners[0],
            self.corners[1],
            self.vertices[0],
            self.vertices[1],
            p.x,
            p.y,
            p.z,
            self.tolerance
        )
    }
}

/// The welded positions of a mesh: for every vertex, the lowest-numbered vertex it welds to.
#[derive(Clone, Debug)]
pub struct Weld {
    /// The representative vertex of each vertex (itself when it is the lowest of its set).
    pub representative: Vec<u32>,
    /// The tolerance used [world units]: [`WELD_RELATIVE`] × the bounding-box diagonal (0
    /// when that is not a positive finite number: then only bit-identical positions weld).
    pub tolerance: f64,
}

/// The root of vertex `i`'s set in the weld's union-find `rep`, halving the path on the
/// way up.
fn find(rep: &mut [u32], mut i: u32) -> u32 {
    while rep[i as usize] != i {
        let up = rep[rep[i as usize] as usize];
        rep[i as usize] = up;
        i = up;
    }
    i
}

/// Joins the sets of vertices `a` and `b` in `rep`.
fn union(rep: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(rep, a), find(rep, b));
    // The lower index becomes the root, so every set's root is its lowest vertex.
    let (lo, hi) = (ra.min(rb), ra.max(rb));
    rep[hi as usize] = lo;
}

impl TriangleMesh {
    /// Fills missing normals with area-weighted face-normal averages.
    pub fn with_computed_normals(mut self) -> Self {
        let mut acc = vec![DVec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc.into_iter().map(|n| n.normalize_or_zero()).collect();
        self
    }

    /// Which vertices are at the same position, within [`WELD_RELATIVE`] of the
    /// bounding-box diagonal (see there). Deterministic: it depends on the positions and
    /// their order only.
    pub fn weld(&self) -> Weld {
        let n = self.positions.len();
        let mut rep: Vec<u32> = (0..n as u32).collect();
        if n == 0 {
            return Weld {
                representative: rep,
                tolerance: 0.0,
            };
        }
        let (lo, tolerance) = self.weld_tolerance();
        if tolerance > 0.0 && tolerance.is_finite() {
            self.union_within(&mut rep, lo, tolerance);
        } else {
            self.union_identical(&mut rep);
        }
        for i in 0..n as u32 {
            let r = find(&mut rep, i);
            rep[i as usize] = r;
        }
        Weld {
            representative: rep,
            tolerance: if tolerance.is_finite() {
                tolerance
            } else {
                0.0
            },
        }
    }

    /// The low corner of the positions' bounding box and the weld tolerance,
    /// [`WELD_RELATIVE`] of its diagonal (0 for a box of no extent or an infinite one; the
    /// diagonal scaled by the largest extent so that it does not overflow). At least one
    /// position.
    fn weld_tolerance(&self) -> (DVec3, f64) {
        let (lo, hi) = self.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let extent = hi - lo;
        let m = extent.abs().max_element();
        let diagonal = if m > 0.0 && m.is_finite() {
            m * (extent / m).length()
        } else {
            0.0
        };
        (lo, WELD_RELATIVE * diagonal)
    }

    /// Joins in `rep` every pair of positions within `tolerance` (finite, > 0) of each
    /// other, found through a grid of cells from the box's low corner `lo`.
    fn union_within(&self, rep: &mut [u32], lo: DVec3, tolerance: f64) {
        // Cells WELD_CELLS tolerances wide, the vertices sorted by cell: two positions
        // within the tolerance are in the same cell, or in cells either side of a face
        // that one of them is within two tolerances of (twice, whatever the rounding of
        // the cell coordinates). Most vertices are near no face and look in their own
        // cell only; which pairs are compared changes nothing but the time, as the sets
        // are those of every pair within the tolerance.
        let cell = WELD_CELLS * tolerance;
        let near = 2.0 / WELD_CELLS;
        let at = |p: DVec3| (p - lo) / cell;
        let mut sorted: Vec<([i64; 3], u32)> = (self.positions.iter().enumerate())
            .map(|(i, &p)| (at(p).floor().as_i64vec3().to_array(), i as u32))
            .collect();
        sorted.sort_unstable();
        let run_of = |k: [i64; 3]| {
            let start = sorted.partition_point(|e| e.0 < k);
            let end = start + sorted[start..].partition_point(|e| e.0 == k);
            start..end
        };
        // In cell order, so that a cell's vertices are next to one another in memory.
        let mut run_start = 0;
        for (e, &(k, i)) in sorted.iter().enumerate() {
            if sorted[run_start].0 != k {
                run_start = e;
            }
            let p = self.positions[i as usize];
            let close = |j: u32| (self.positions[j as usize] - p).length() <= tolerance;
            for &(_, j) in &sorted[run_start..e] {
                if close(j) {
                    union(rep, i, j);
                }
            }
            let c = at(p);
            let f = c - c.floor();
            // Per axis, a neighbour across a face it is near.
            let span = |d: usize| {
                let lo = if f[d] < near { -1 } else { 0 };
                let hi = if f[d] > 1.0 - near { 1 } else { 0 };
                lo..=hi
            };
            for dx in span(0) {
                for dy in span(1) {
                    for dz in span(2) {
                        if (dx, dy, dz) == (0, 0, 0) {
                            continue;
                        }
                        for &(_, j) in &sorted[run_of([k[0] + dx, k[1] + dy, k[2] + dz])] {
                            if close(j) {
                                union(rep, i, j);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Joins in `rep` the positions that are bit for bit the same (where there is no
    /// tolerance to weld within).
    fn union_identical(&self, rep: &mut [u32]) {
        let mut seen: std::collections::HashMap<[u64; 3], u32> = std::collections::HashMap::new();
        for (i, p) in self.positions.iter().enumerate() {
            let bits = p.to_array().map(f64::to_bits);
            let first = *seen.entry(bits).or_insert(i as u32);
            union(rep, i as u32, first);
        }
    }

    /// The same mesh with every position replaced by its welded position (the position of
    /// the lowest-numbered vertex it welds to). Idempotent; a mesh whose split vertices
    /// have bit-identical positions is returned unchanged.
    pub fn welded(mut self) -> Self {
        let rep = self.weld().representative;
        for (i, &r) in rep.iter().enumerate() {
            self.positions[i] = self.positions[r as usize];
        }
        self
    }

    /// The first triangle two of whose corners weld together, if any.
    fn collapsed(&self, weld: &Weld) -> Option<CollapsedTriangle> {
        let rep = &weld.representative;
        self.triangles.iter().enumerate().find_map(|(t, tri)| {
            let r = tri.map(|i| rep[i as usize]);
            [(0, 1), (0, 2), (1, 2)]
                .into_iter()
                .find(|&(a, b)| r[a] == r[b])
                .map(|(a, b)| CollapsedTriangle {
                    triangle: t,
                    corners: [a, b],
                    vertices: [tri[a], tri[b]],
                    position: self.positions[r[a] as usize],
                    tolerance: weld.tolerance,
                })
        })
    }

    /// The mesh with new normals for a crease angle of `angle_deg` degrees (auto-smooth):
    /// each face corner gets the area-weighted average of the normals of the faces around
    /// its (welded) vertex whose face normal is within `angle_deg` of its own face's
    /// (inclusive, with 1e-12 slack on the cosine for rounding; the corner's own face always
    /// counts). Faces meeting at more than the angle are thus shaded apart (a hard edge,
    /// split normals) and faces meeting at less are shaded smooth. The file's normals are
    /// not used. A corner of a zero-area face averages all faces around its vertex; a
    /// corner whose average vanishes takes its face's normal. Sums run over the faces in
    /// mesh order, so at 180° the normals are [`Self::with_computed_normals`]'s bit for
    /// bit. Vertices are rebuilt: one per distinct (welded position, normal), numbered in
    /// order of first use by the triangles.
    pub fn with_crease_angle(&self, angle_deg: f64) -> Result<TriangleMesh, CollapsedTriangle> {
        let weld = self.weld();
        if let Some(c) = self.collapsed(&weld) {
            return Err(c);
        }
        let rep = &weld.representative;
        let pos = |i: u32| self.positions[rep[i as usize] as usize];
        let area_normals: Vec<DVec3> = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(pos);
                (b - a).cross(c - a)
            })
            .collect();
        let unit: Vec<DVec3> = area_normals.iter().map(|n| n.normalize_or_zero()).collect();
        // The faces around each welded vertex, in mesh order.
        let mut faces: Vec<Vec<u32>> = vec![Vec::new(); self.positions.len()];
        for (f, t) in self.triangles.iter().enumerate() {
            for &i in t {
                faces[rep[i as usize] as usize].push(f as u32);
            }
        }
        let cos_limit = angle_deg.to_radians().cos() - 1e-12;
        let all = angle_deg >= 180.0;
        let mut out = TriangleMesh {
            positions: Vec::new(),
            normals: Vec::new(),
            triangles: Vec::with_capacity(self.triangles.len()),
        };
        let mut index: std::collections::HashMap<(u32, [u64; 3]), u32> =
            std::collections::HashMap::new();
        for (f, t) in self.triangles.iter().enumerate() {
            let own = unit[f];
            let tri = t.map(|i| {
                let v = rep[i as usize];
                let mut sum = DVec3::ZERO;
                for &g in &faces[v as usize] {
                    let g = g as usize;
                    if all || g == f || own == DVec3::ZERO || unit[g].dot(own) >= cos_limit {
                        sum += area_normals[g];
                    }
                }
                let n = sum.normalize_or_zero();
                let n = if n == DVec3::ZERO { own } else { n };
                *index
                    .entry((v, n.to_array().map(f64::to_bits)))
                    .or_insert_with(|| {
                        out.positions.push(self.positions[v as usize]);
                        out.normals.push(n);
                        (out.positions.len() - 1) as u32
                    })
            });
            out.triangles.push(tri);
        }
        Ok(out)
    }

    /// One lembo per triangle (Martinelli 2006: "use the Lembo Model to refine a triangular mesh"),
    /// watertight across hard edges.
    ///
    /// Positions are welded first ([`Self::weld`]): corners are the welded positions, and an
    /// edge is identified by its two welded ends. Every lembo on an edge gets the same
    /// midpoint, bit for bit: each side computes the midpoint its own end normals give
    /// ([`edge_midpoint`], canonical order), and the shared midpoint is the average of the
    /// distinct ones, summed in the total order of [`canonical_order`] (PN-AEN's rule for
    /// PN triangles, McDonald and Kilgard 2010, for a quadratic edge). Where both sides have
    /// the same normals (a smooth mesh) their midpoints are identical and the shared one is
    /// that midpoint unchanged, so a smooth mesh gives the lembos of
    /// [`lembo_from_triangle`] bit for bit. Each lembo keeps its own corner normals and its
    /// own edge mid-normals, so a hard edge is still shaded hard.
    ///
    /// Refuses a triangle two of whose corners weld together.
    pub fn to_lembos(&self) -> Result<Vec<Lembo>, CollapsedTriangle> {
        let lembos = self.clone().into_lembos()?;
        Ok((0..lembos.len()).map(|t| lembos.get(t)).collect())
    }

    /// The lembos of [`Self::to_lembos`], made one at a time on demand from the welded mesh
    /// ([`MeshLembos`]): what a scene holds of a mesh object.
    pub fn into_lembos(self) -> Result<MeshLembos, CollapsedTriangle> {
        let weld = self.weld();
        if let Some(c) = self.collapsed(&weld) {
            return Err(c);
        }
        let rep = &weld.representative;
        let mut mesh = self;
        for (i, &r) in rep.iter().enumerate() {
            mesh.positions[i] = mesh.positions[r as usize];
        }
        // Every (edge key, triangle, edge) sorted by key: the sides of each edge are adjacent.
        let mut sides: Vec<((u32, u32), u32, u8)> = Vec::with_capacity(3 * mesh.triangles.len());
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for (k, (a, b)) in EDGES.into_iter().enumerate() {
                let (ra, rb) = (rep[tri[a] as usize], rep[tri[b] as usize]);
                sides.push(((ra.min(rb), ra.max(rb)), t as u32, k as u8));
            }
        }
        sides.sort_unstable();
        let mut shared = Vec::new();
        let mut distinct: Vec<DVec3> = Vec::new();
        for edge in sides.chunk_by(|x, y| x.0 == y.0) {
            distinct.clear();
            distinct.extend(edge.iter().map(|&(_, t, k)| mesh.own_midpoint(t, k).0));
            distinct.sort_unstable_by(|p, q| canonical_order(*p, *q));
            distinct.dedup_by(|p, q| canonical_order(*p, *q) == Ordering::Equal);
            if distinct.len() < 2 {
                continue;
            }
            let mid = shared_midpoint(&distinct);
            shared.extend(edge.iter().map(|&(_, t, k)| (3 * t as u64 + k as u64, mid)));
        }
        shared.sort_unstable_by_key(|&(key, _)| key);
        Ok(MeshLembos { mesh, shared })
    }

    /// Triangle `t`'s own midpoint and mid-normal of its edge `k` (AB, AC, BC: D, E, F).
    fn own_midpoint(&self, t: u32, k: u8) -> (DVec3, DVec3) {
        let (p1, n1, p2, n2) = self.edge_ends(t, k);
        edge_midpoint(p1, n1, p2, n2)
    }

    /// The ends (position and normal) of triangle `t`'s edge `k` (AB, AC, BC).
    fn edge_ends(&self, t: u32, k: u8) -> (DVec3, DVec3, DVec3, DVec3) {
        let tri = self.triangles[t as usize];
        let (a, b) = EDGES[k as usize];
        let (pa, pb) = (tri[a] as usize, tri[b] as usize);
        (
            self.positions[pa],
            self.normals[pa],
            self.positions[pb],
            self.normals[pb],
        )
    }
}

/// A mesh's lembos made on demand, one per triangle ([`TriangleMesh::to_lembos`]): the
/// welded mesh and the shared midpoints of the edges whose sides compute different ones (a
/// smooth mesh has none): 36 bytes a lembo for a mesh of 2 triangles a vertex (48 a
/// vertex, 12 a triangle) instead of a lembo's 576.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshLembos {
    /// The mesh, its positions welded.
    mesh: TriangleMesh,
    /// (3 × triangle + edge, the edge's shared midpoint), sorted, for every side of an edge
    /// whose sides compute different midpoints.
    shared: Vec<(u64, DVec3)>,
}

impl MeshLembos {
    /// The lembos: one a triangle.
    pub fn len(&self) -> usize {
        self.mesh.triangles.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.mesh.triangles.is_empty()
    }

    /// The mesh, its positions welded.
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// Lembo `t`, made from triangle `t`: its welded corners and unit corner normals, its
    /// own edge mid-normals, and each edge's shared midpoint (its own where the sides
    /// agree).
    pub fn get(&self, t: usize) -> Lembo {
        let own = [0, 1, 2].map(|k| self.mesh.own_midpoint(t as u32, k));
        let mid = [0, 1, 2].map(|k| self.shared_of_edge(t, k).unwrap_or(own[k as usize].0));
        let ([a, b, c], [na, nb, nc]) = self.corners(t);
        Lembo::new(
            [a, b, c, mid[0], mid[1], mid[2]],
            [na, nb, nc, own[0].1, own[1].1, own[2].1],
        )
    }

    /// Lembo `t`'s six reference points (corners, then the midpoints of AB, AC, BC), bit for
    /// bit those of [`MeshLembos::get`], without its normals.
    pub fn points(&self, t: usize) -> [DVec3; 6] {
        let m = &self.mesh;
        let mid = [0, 1, 2].map(|k| {
            self.shared_of_edge(t, k).unwrap_or_else(|| {
                let (p1, n1, p2, n2) = m.edge_ends(t as u32, k);
                edge_midpoint_position(p1, n1, p2, n2)
            })
        });
        let [a, b, c] = m.triangles[t].map(|i| m.positions[i as usize]);
        [a, b, c, mid[0], mid[1], mid[2]]
    }

    /// The shared midpoint of triangle `t`'s edge `k` (AB, AC, BC), when its sides compute
    /// different ones.
    fn shared_of_edge(&self, t: usize, k: u8) -> Option<DVec3> {
        let key = 3 * t as u64 + k as u64;
        let at = self
            .shared
            .binary_search_by_key(&key, |&(key, _)| key)
            .ok()?;
        Some(self.shared[at].1)
    }

    /// Lembo `t`'s corners A, B, C and their unit normals, bit for bit those of
    /// [`MeshLembos::get`], without making its edges: triangle `t` itself.
    pub fn corners(&self, t: usize) -> ([DVec3; 3], [DVec3; 3]) {
        let m = &self.mesh;
        let tri = m.triangles[t];
        (
            tri.map(|i| m.positions[i as usize]),
            tri.map(|i| m.normals[i as usize].normalize_or_zero()),
        )
    }

    /// The heap it holds \[bytes\].
    pub fn bytes(&self) -> usize {
        let m = &self.mesh;
        std::mem::size_of_val(&m.positions[..])
            + std::mem::size_of_val(&m.normals[..])
            + std::mem::size_of_val(&m.triangles[..])
            + std::mem::size_of_val(&self.shared[..])
    }
}

/// The corners of the lembo edges AB, AC, BC (midpoints D, E, F).
const EDGES: [(usize, usize); 3] = [(0, 1), (0, 2), (1, 2)];

/// The shared midpoint of an edge from the distinct midpoints its sides compute, in
/// [`canonical_order`]: their average (the two-sided case is `0.5 * (a + b)`).
pub fn shared_midpoint(distinct: &[DVec3]) -> DVec3 {
    match distinct {
        [m] => *m,
        [a, b] => 0.5 * (*a + *b),
        _ => distinct.iter().fold(DVec3::ZERO, |s, &m| s + m) / distinct.len() as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(v: DVec3) -> [u64; 3] {
        v.to_array().map(f64::to_bits)
    }

    fn lembo_bits(l: &Lembo) -> ([[u64; 3]; 6], [[u64; 3]; 6]) {
        (l.points.map(bits), l.normals.map(bits))
    }

    /// Today's construction: every lembo from its own triangle alone.
    fn independent(m: &TriangleMesh) -> Vec<Lembo> {
        m.triangles
            .iter()
            .map(|t| {
                let i = t.map(|i| i as usize);
                lembo_from_triangle(i.map(|i| m.positions[i]), i.map(|i| m.normals[i]))
            })
            .collect()
    }

    #[test]
    fn smooth_meshes_give_the_independent_lembos_bit_for_bit() {
        for name in crate::lembo::shapes::BUILTIN_NAMES {
            let m = crate::lembo::shapes::builtin_mesh(name).unwrap();
            let shared = m.to_lembos().unwrap();
            let alone = independent(&m);
            for (a, b) in shared.iter().zip(&alone) {
                assert_eq!(lembo_bits(a), lembo_bits(b), "{name}");
            }
        }
    }

    /// Two triangles on the edge (0,0,0)-(2,0,0), split: each side has its own normals.
    fn split_pair(n_left: [DVec3; 2], n_right: [DVec3; 2]) -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(1.0, -1.0, 0.3),
            ],
            normals: vec![
                n_left[0],
                n_left[1],
                DVec3::Z,
                n_right[0],
                n_right[1],
                DVec3::Z,
            ],
            // The edge is AB of the first and BA (as AB, reversed) of the second.
            triangles: vec![[0, 1, 2], [4, 3, 5]],
        }
    }

    #[test]
    fn a_split_edge_gets_the_average_of_both_sides_midpoints() {
        let left = [DVec3::new(-1.0, 0.0, 1.0), DVec3::new(1.0, 0.0, 1.0)];
        let right = [DVec3::Z, DVec3::Z];
        let m = split_pair(left, right);
        let l = m.to_lembos().unwrap();
        let (own_left, nl) = edge_midpoint(m.positions[0], left[0], m.positions[1], left[1]);
        let (own_right, nr) = edge_midpoint(m.positions[3], right[0], m.positions[4], right[1]);
        assert!(own_left.z > 0.1 && own_right == DVec3::new(1.0, 0.0, 0.0));
        // One midpoint, bit for bit, on both sides: the average.
        assert_eq!(bits(l[0].points[3]), bits(l[1].points[3]));
        assert_eq!(bits(l[0].points[3]), bits(0.5 * (own_left + own_right)));
        // Each side keeps its own corner normals and mid-normal.
        assert_eq!(l[0].normals[3], nl);
        assert_eq!(l[1].normals[3], nr);
        assert_eq!(l[0].normals[0], left[0].normalize());
        assert_eq!(l[1].normals[1], right[0]);
        // The other edges are not shared and keep their own midpoints.
        let alone = independent(&m);
        for k in [4, 5] {
            assert_eq!(bits(l[0].points[k]), bits(alone[0].points[k]));
            assert_eq!(bits(l[1].points[k]), bits(alone[1].points[k]));
        }
        // The order of the triangles (and of the sides) does not matter.
        let swapped = TriangleMesh {
            triangles: vec![m.triangles[1], m.triangles[0]],
            ..m.clone()
        };
        let s = swapped.to_lembos().unwrap();
        assert_eq!(lembo_bits(&s[0]), lembo_bits(&l[1]));
        assert_eq!(lembo_bits(&s[1]), lembo_bits(&l[0]));
    }

    #[test]
    fn capped_cylinder_rim_is_half_the_walls_bulge() {
        // A rim edge of a 12-sided cylinder of radius 1: radial normals seen from the wall,
        // +y from the cap.
        let (p, q) = (DVec3::new(1.0, 1.0, 0.0), {
            let phi = std::f64::consts::PI / 6.0;
            DVec3::new(phi.cos(), 1.0, -phi.sin())
        });
        let radial = |v: DVec3| DVec3::new(v.x, 0.0, v.z);
        let (wall, _) = edge_midpoint(p, radial(p), q, radial(q));
        let (cap, _) = edge_midpoint(p, DVec3::Y, q, DVec3::Y);
        let shared = 0.5 * (wall + cap);
        let r = |v: DVec3| radial(v).length();
        let chord = (15f64).to_radians().cos();
        assert!((r(cap) - chord).abs() < 1e-15);
        assert!((r(wall) - 0.998278).abs() < 1e-6, "wall {}", r(wall));
        assert!((r(shared) - 0.982102).abs() < 1e-6, "shared {}", r(shared));
        assert!((r(shared) - 0.5 * (r(wall) + chord)).abs() < 1e-12);
        assert_eq!(shared.y, 1.0);
    }

    #[test]
    fn positions_weld_within_the_tolerance_only_and_transitively() {
        // Diagonal 1e6 × sqrt(3): tolerance 1.73e-3.
        let far = DVec3::splat(1e6);
        let p = DVec3::new(0.5, 0.5, 0.5);
        let tol = WELD_RELATIVE * far.length();
        let m = TriangleMesh {
            positions: vec![
                DVec3::ZERO,
                far,
                p,
                p + DVec3::X * (0.9 * tol),
                p + DVec3::X * (1.8 * tol), // within of the previous one only
                p + DVec3::Y * (1.1 * tol), // beyond the tolerance of every other
                p,                          // bit-identical
            ],
            ..Default::default()
        };
        let w = m.weld();
        assert!((w.tolerance - tol).abs() < 1e-18);
        assert_eq!(w.representative, [0, 1, 2, 2, 2, 5, 2]);
        // Across a grid cell boundary (cells are WELD_CELLS tol wide, from the bounding box's
        // corner).
        let edge = WELD_CELLS * tol * 100.0;
        let m = TriangleMesh {
            positions: vec![
                DVec3::ZERO,
                far,
                DVec3::splat(edge - 1e-3 * tol),
                DVec3::splat(edge + 1e-3 * tol),
            ],
            ..Default::default()
        };
        assert_eq!(m.weld().representative, [0, 1, 2, 2]);
        let welded = m.clone().welded();
        assert_eq!(welded.positions[3], welded.positions[2]);
        assert_eq!(welded.clone().welded().positions, welded.positions);
    }

    /// The weld's sets are those of every pair within the tolerance, as comparing every pair
    /// finds them: clusters of points a fraction of a tolerance to two apart, scattered over
    /// cell faces, edges and corners.
    #[test]
    fn the_weld_finds_the_sets_every_pair_finds() {
        let mut rng = crate::testkit::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut random = move || rng.unit();
        let far = DVec3::splat(1e6);
        let tol = WELD_RELATIVE * far.length();
        let cell = WELD_CELLS * tol;
        let mut positions = vec![DVec3::ZERO, far];
        for c in 0..300 {
            // A cluster centre on a cell face, edge or corner, or inside a cell.
            let snap = |x: f64, on: bool| if on { (x / cell).round() * cell } else { x };
            let base =
                DVec3::splat(1000.0) + 40.0 * cell * DVec3::new(random(), random(), random());
            let centre = DVec3::new(
                snap(base.x, c % 2 == 0),
                snap(base.y, c % 3 == 0),
                snap(base.z, c % 5 == 0),
            );
            for _ in 0..4 {
                let d = DVec3::new(random(), random(), random()) - 0.5;
                positions.push(centre + d.normalize_or_zero() * (2.0 * tol * random()));
            }
        }
        let m = TriangleMesh {
            positions,
            ..Default::default()
        };
        let got = m.weld().representative;
        // Every pair, the lower index the root.
        let n = m.positions.len();
        let mut rep: Vec<usize> = (0..n).collect();
        fn root(rep: &[usize], mut i: usize) -> usize {
            while rep[i] != i {
                i = rep[i];
            }
            i
        }
        for i in 0..n {
            for j in 0..i {
                if (m.positions[i] - m.positions[j]).length() <= tol {
                    let (a, b) = (root(&rep, i), root(&rep, j));
                    rep[a.max(b)] = a.min(b);
                }
            }
        }
        let want: Vec<u32> = (0..n).map(|i| root(&rep, i) as u32).collect();
        let welded = want
            .iter()
            .enumerate()
            .filter(|&(i, &r)| r as usize != i)
            .count();
        assert!(welded > 300 && welded < 900, "{welded} welded of {n}");
        assert_eq!(got, want);
    }

    #[test]
    fn nearly_equal_split_vertices_are_snapped_and_share_the_edge() {
        let mut m = split_pair([DVec3::Z; 2], [DVec3::Y + DVec3::Z; 2]);
        m.positions[4] += DVec3::new(1e-12, 0.0, 0.0);
        let l = m.to_lembos().unwrap();
        assert_eq!(bits(l[1].points[0]), bits(l[0].points[1]));
        assert_eq!(bits(l[0].points[3]), bits(l[1].points[3]));
    }

    #[test]
    fn a_triangle_whose_corners_weld_is_refused_by_index() {
        let mut m = split_pair([DVec3::Z; 2], [DVec3::Z; 2]);
        m.positions[5] = m.positions[3] + DVec3::new(0.0, 1e-10, 0.0);
        let c = m.to_lembos().unwrap_err();
        assert_eq!(c.triangle, 1);
        assert_eq!(c.corners, [1, 2]);
        assert_eq!(c.vertices, [3, 5]);
        assert!(c.to_string().starts_with("triangle 1 "), "{c}");
        assert_eq!(m.with_crease_angle(40.0).unwrap_err(), c);
        // The same vertex twice.
        let m = TriangleMesh {
            triangles: vec![[0, 1, 0]],
            ..split_pair([DVec3::Z; 2], [DVec3::Z; 2])
        };
        assert_eq!(m.to_lembos().unwrap_err().corners, [0, 2]);
    }

    /// The unit cube as 12 triangles over 8 shared vertices, outward.
    fn cube() -> TriangleMesh {
        let positions = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriangleMesh {
            positions,
            normals: vec![],
            triangles,
        }
    }

    #[test]
    fn crease_angle_splits_normals_at_edges_sharper_than_it() {
        let m = cube();
        // 40°: every corner takes its face's normal (the faces meet at 90°).
        let c = m.with_crease_angle(40.0).unwrap();
        assert_eq!(c.triangles.len(), 12);
        assert_eq!(c.positions.len(), 24, "8 corners x 3 faces");
        for t in &c.triangles {
            let [a, b, p] = t.map(|i| c.positions[i as usize]);
            let face = (b - a).cross(p - a).normalize();
            for &i in t {
                assert!((c.normals[i as usize] - face).length() < 1e-15);
            }
        }
        // 90° (inclusive) and beyond: one normal per corner of the cube, pointing out of
        // the corner (area-weighted by triangle, so a face split through the corner counts
        // twice: not exactly the diagonal).
        for angle in [90.0, 180.0] {
            let c = m.with_crease_angle(angle).unwrap();
            assert_eq!(c.positions.len(), 8, "{angle}");
            for (p, n) in c.positions.iter().zip(&c.normals) {
                let d = (*p - DVec3::splat(0.5)).normalize();
                assert!(
                    n.dot(d) > 0.9 && (n.length() - 1.0).abs() < 1e-15,
                    "{angle}: {p} {n}"
                );
            }
        }
        // The lembos of the creased cube share every edge.
        let l = c.to_lembos().unwrap();
        assert_eq!(l.len(), 12);
    }

    #[test]
    fn crease_angle_180_is_the_computed_normals_bit_for_bit() {
        let m = crate::lembo::shapes::sphere_mesh(7, 5);
        let smooth = m.clone().with_computed_normals();
        let c = m.with_crease_angle(180.0).unwrap();
        // Same vertices (none is split), in order of first use by the triangles.
        assert_eq!(c.positions.len(), smooth.positions.len());
        for (t, s) in c.triangles.iter().zip(&smooth.triangles) {
            for (&i, &j) in t.iter().zip(s) {
                assert_eq!(
                    bits(c.positions[i as usize]),
                    bits(smooth.positions[j as usize])
                );
                assert_eq!(
                    bits(c.normals[i as usize]),
                    bits(smooth.normals[j as usize])
                );
            }
        }
    }

    #[test]
    fn shared_edge_gets_identical_points_from_both_sides() {
        let a = DVec3::new(0.3, 0.1, 0.9).normalize();
        let b = DVec3::new(0.9, 0.2, 0.1).normalize();
        let c = DVec3::new(0.1, 0.95, 0.2).normalize();
        let d = DVec3::new(0.7, 0.7, 0.6).normalize();
        // Triangles ABC and BDC share edge BC, traversed in opposite directions.
        let l1 = lembo_from_triangle([a, b, c], [a, b, c]);
        let l2 = lembo_from_triangle([b, d, c], [b, d, c]);
        // In l1 the BC midpoint is F; in l2 (A=b, B=d, C=c) it is E (edge AC).
        assert_eq!(l1.points[5].to_array(), l2.points[4].to_array());
        assert_eq!(l1.normals[5].to_array(), l2.normals[4].to_array());
    }

    #[test]
    fn parallel_end_normals_give_a_straight_edge() {
        let n = DVec3::Z;
        let (m, nm) = edge_midpoint(DVec3::ZERO, n, DVec3::new(2.0, 0.0, 0.0), n);
        assert_eq!(m, DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(nm, n);
    }

    #[test]
    fn perpendicular_end_normals_do_not_divide_by_zero() {
        // A quarter circle: the printed formula divides by T1·T2 = 0 here.
        let (m, nm) = edge_midpoint(DVec3::X, DVec3::X, DVec3::Y, DVec3::Y);
        assert!(m.is_finite() && nm.is_finite());
        // On the diagonal, bulging outward past the chord midpoint (|chord mid| = 0.707).
        assert!((m.x - m.y).abs() < 1e-15 && m.length() > 0.8 && m.length() < 1.0);
        assert!((nm - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-15);
    }

    #[test]
    fn sphere_edge_midpoint_bulges_towards_the_sphere() {
        // Ends on the unit sphere with radial normals: the midpoint leaves the chord
        // (|chord mid| = cos(theta/2)) and moves outward, without overshooting the sphere,
        // along the bisector.
        let p1 = DVec3::new(1.0, 0.0, 0.0);
        let p2 = DVec3::new(0.6, 0.8, 0.0);
        let (m, nm) = edge_midpoint(p1, p1, p2, p2);
        let chord = (0.5 * (p1 + p2)).length();
        assert!(
            m.length() > chord + 0.05 && m.length() <= 1.0,
            "{}",
            m.length()
        );
        assert!(m.normalize().cross((p1 + p2).normalize()).length() < 1e-12);
        assert!((nm - (p1 + p2).normalize()).length() < 1e-12);
    }
}
