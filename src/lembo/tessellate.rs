//! The Tessellator of the triangle path (DESIGN.md §2 and §5; Martinelli 2006 section 3's
//! fixed-step subdivision): each lembo becomes n² triangles, uniform in the domain, with their
//! vertices on the true patch and their normals from the lembo's normal function.
//!
//! ```text
//!   v                      lattice points (a, b), a + b <= n, at (u, v) = (a/n, b/n);
//!   1 C                    local triangle order, row b = 0..n, a = 0..n-b:
//!     | \                    up   [(a,b), (a+1,b), (a,b+1)]
//!     +---+                  down [(a+1,b), (a+1,b+1), (a,b+1)]  when a + b + 1 < n
//!     | \ | \              both counter-clockwise like A, B, C; n = 1 gives [A, B, C].
//!   0 A---+---B u          (n = 2: up(0,0), down(0,0), up(1,0), up(0,1))
//! ```
//!
//! Input: lembos (each object's [`Lembos`] with its colour, in order; a scene offers
//! its own as `Scene::lembo_sets`) and the level n. Output: [`Triangle`]s in world space, one at
//! a time by global id ([`Tessellation::triangle`]) or a lembo's n² at once
//! ([`Tessellation::lembo_triangles`]), and the size of the result as an indexed mesh
//! ([`Tessellation::vertex_count`], [`Tessellation::len`]; its bytes at the architecture's
//! sizes, `fetch.*` of the architecture file) without generating it.
//!
//! Shared edges: neighbouring lembos must produce bit-identical vertices on their common edge,
//! or the triangle path shows cracks. So a vertex is never computed from the lembo's
//! coefficients where it lies on the domain boundary:
//! - corners are the lembo's construction points, copied (so n = 1 on a mesh-built lembo gives
//!   back the mesh triangle bit for bit), and its normalised construction normals;
//! - edge points come from the edge's own three points (ends and middle) and normals, in the
//!   canonical order of [`canonical_order`](super::construct::canonical_order) that `construct.rs` also builds midpoints in,
//!   through one fixed Bézier expression; two lembos sharing an edge hold the same three
//!   points and normals, so they compute the same bits whatever their winding;
//! - interior points are [`Lembo::position_at`] and [`Lembo::unit_normal_at`].
//!
//! Not modelled here: the time a hardware tessellator takes (that belongs to the timed
//! pipeline: `pipeline::units::tessellator`) and adaptive (variable-step) subdivision.
//! The mesh's bytes (`TriangleSource::bytes`) are the size of the indexed mesh in which every shared vertex is
//! stored once; what a geometry fetch reads of it depends on its vertex cache, which reads
//! [`Tessellation::lembo_vertex_ids`].

use super::lattice::{canonical_edge, corner, key_bits, lattice_vertex, Vertex, EDGES};
use super::set::Lembos;
use super::Lembo;
use glam::DVec3;
use std::collections::HashMap;
use std::sync::OnceLock;

/// A triangle of the triangle path, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Vertex positions, counter-clockwise in the lembo's domain [world units].
    pub positions: [DVec3; 3],
    /// Unit vertex normals (zero where the lembo's normal function vanishes).
    pub normals: [DVec3; 3],
    /// The object's material colour, linear RGB in [0, 1].
    pub color: [f64; 3],
}

/// Bytes of one vertex of the indexed mesh: an f32 position and an f32 normal \[bytes\]; the
/// default of the architecture's `fetch.bytes_per_vertex`, which the counts use.
pub const VERTEX_BYTES: u64 = 24;

/// Bytes of one triangle's indices in the indexed mesh: three u32 indices \[bytes\]; the
/// default of the architecture's `fetch.index_bytes_per_triangle`.
pub const INDEX_BYTES_PER_TRIANGLE: u64 = 12;

/// Lembos tessellated at level n: n² triangles per lembo, computed on demand.
#[derive(Clone, Debug)]
pub struct Tessellation<'a> {
    /// Each object's lembos with its colour; their lembos in order, object after object,
    /// are the tessellated lembos in global-id order (each made when its triangles are
    /// asked for).
    objects: Vec<(&'a Lembos, [f64; 3])>,
    /// Where each object's lembos start in global-id order.
    starts: Vec<usize>,
    /// How many lembos it has.
    count: usize,
    /// Lattice steps per domain edge.
    n: u32,
    /// The indexed mesh's vertex numbering, made on first use.
    index: OnceLock<MeshIndex>,
}

/// The vertex numbering of the tessellation as an indexed mesh: the distinct corners
/// first, then each distinct edge's n - 1 inner points (from its canonical start), then
/// each lembo's interior points. Two lembos sharing a corner or an edge (same bits, the
/// keys of [`Tessellation::vertex_count`]) share its vertices' indices, as in a mesh that
/// stores each vertex once.
#[derive(Clone, Debug)]
struct MeshIndex {
    /// Each lembo's corners A, B, C: their indices.
    corners: Vec<[u64; 3]>,
    /// Each lembo's edges AB, AC, BC (in `EDGES` order): the edge's number among the
    /// distinct edges, and whether its canonical start is the edge's second end.
    edges: Vec<[(u64, bool); 3]>,
    /// Distinct corners.
    corner_count: u64,
    /// Distinct edges.
    edge_count: u64,
    /// Vertices in all.
    vertices: u64,
}

impl MeshIndex {
    fn new(lembos: impl Iterator<Item = Lembo>, count: usize, n: u32) -> MeshIndex {
        let mut corner_ids = HashMap::new();
        let mut edge_ids = HashMap::new();
        let mut corners = Vec::with_capacity(count);
        let mut edges = Vec::with_capacity(count);
        for l in lembos {
            let l = &l;
            corners.push(std::array::from_fn(|k| {
                let (p, nrm) = corner(l, k);
                let next = corner_ids.len() as u64;
                *corner_ids.entry(key_bits([p, nrm])).or_insert(next)
            }));
            edges.push(EDGES.map(|edge| {
                let (swapped, [p, m, q]) = canonical_edge(l, edge);
                let next = edge_ids.len() as u64;
                let id = *edge_ids
                    .entry(key_bits([p.0, p.1, m.0, m.1, q.0, q.1]))
                    .or_insert(next);
                (id, swapped)
            }));
        }
        let (corner_count, edge_count) = (corner_ids.len() as u64, edge_ids.len() as u64);
        let steps = u64::from(n) - 1;
        let interior = steps * steps.saturating_sub(1) / 2;
        MeshIndex {
            corners,
            edges,
            corner_count,
            edge_count,
            vertices: corner_count + edge_count * steps + count as u64 * interior,
        }
    }

    /// The index of lattice point (a, b) of lembo `l` at level n.
    fn vertex(&self, l: usize, n: u32, a: u32, b: u32) -> u64 {
        debug_assert!(a + b <= n);
        let steps = u64::from(n) - 1;
        let on_edge = |e: usize, step: u32| {
            let (id, swapped) = self.edges[l][e];
            let i = if swapped { n - step } else { step };
            self.corner_count + id * steps + u64::from(i) - 1
        };
        match (a, b) {
            (0, 0) => self.corners[l][0],
            (a, 0) if a == n => self.corners[l][1],
            (0, b) if b == n => self.corners[l][2],
            // Steps from the edge's first end in EDGES: A for AB and AC, B for BC.
            (a, 0) => on_edge(0, a),
            (0, b) => on_edge(1, b),
            (_, b) if a + b == n => on_edge(2, b),
            (a, b) => {
                // Interior rows b = 1..n-2 hold n - 1 - b points each, a = 1..n-b-1.
                let (a, b, n) = (u64::from(a), u64::from(b), u64::from(n));
                let before = (b - 1) * (n - 1) - (b - 1) * b / 2;
                let interior = steps * steps.saturating_sub(1) / 2;
                self.corner_count + self.edge_count * steps + l as u64 * interior + before + (a - 1)
            }
        }
    }
}

impl<'a> Tessellation<'a> {
    /// The tessellation at level `n` (n steps per domain edge; n >= 1, validated by the
    /// caller) of every lembo of `objects`: each object's lembos with its colour, in order
    /// (a scene's are `Scene::lembo_sets`).
    pub fn new(objects: impl IntoIterator<Item = (&'a Lembos, [f64; 3])>, n: u32) -> Self {
        debug_assert!(n >= 1, "tessellation level must be at least 1");
        let objects: Vec<(&'a Lembos, [f64; 3])> = objects.into_iter().collect();
        let mut count = 0;
        let starts = objects
            .iter()
            .map(|(lembos, _)| {
                let at = count;
                count += lembos.len();
                at
            })
            .collect();
        Tessellation {
            objects,
            starts,
            count,
            n,
            index: OnceLock::new(),
        }
    }

    /// Lembo `id` (global order) with its object's colour, made if it is not held.
    fn lembo(&self, id: usize) -> (Lembo, [f64; 3]) {
        let o = self.starts.partition_point(|&start| start <= id) - 1;
        let (lembos, color) = self.objects[o];
        (lembos.get(id - self.starts[o]), color)
    }

    /// The level n: steps per domain edge.
    pub fn level(&self) -> u32 {
        self.n
    }

    /// The number of triangles: lembos × n².
    pub fn len(&self) -> u64 {
        self.count as u64 * self.triangles_per_lembo()
    }

    /// Whether there are no triangles (there are no lembos).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Lembos tessellated.
    pub fn lembos(&self) -> usize {
        self.count
    }

    /// Triangles per lembo: n².
    pub fn triangles_per_lembo(&self) -> u64 {
        let n = u64::from(self.n);
        n * n
    }

    /// Triangle `id` (global id = lembo index * n² + local index), computed on demand.
    pub fn triangle(&self, id: u64) -> Triangle {
        debug_assert!(id < self.len(), "triangle {id} of {}", self.len());
        let per_lembo = self.triangles_per_lembo();
        let (lembo, color) = self.lembo((id / per_lembo) as usize);
        let lembo = &lembo;
        let local = id % per_lembo;
        // Row b starts at local index n² - (n - b)², so m = n - b is the smallest m with
        // n² - local <= m²; within the row, up and down triangles alternate.
        let n = u64::from(self.n);
        let rest = per_lembo - local;
        let m = (rest - 1).isqrt() + 1;
        let offset = m * m - rest;
        let (a, b) = ((offset / 2) as u32, (n - m) as u32);
        let lattice = if offset.is_multiple_of(2) {
            [(a, b), (a + 1, b), (a, b + 1)]
        } else {
            [(a + 1, b), (a + 1, b + 1), (a, b + 1)]
        };
        let vertices = lattice.map(|(a, b)| self.vertex(lembo, a, b));
        Triangle {
            positions: vertices.map(|v| v.0),
            normals: vertices.map(|v| v.1),
            color,
        }
    }

    /// All n² triangles of lembo `lembo` in local order into `out` (cleared first), each
    /// lattice point evaluated once.
    pub fn lembo_triangles(&self, lembo: usize, out: &mut Vec<Triangle>) {
        let (l, color) = self.lembo(lembo);
        let (l, n) = (&l, self.n);
        out.clear();
        out.reserve(self.triangles_per_lembo() as usize);
        let triangle = |p: [Vertex; 3]| Triangle {
            positions: p.map(|v| v.0),
            normals: p.map(|v| v.1),
            color,
        };
        // Every lattice point is first needed as the top of an up triangle (row b + 1) or,
        // on row 0, as a bottom corner; later uses copy it from the triangles already in
        // `out`, so no scratch buffer is needed.
        let mut previous_row = 0;
        for b in 0..n {
            let row = out.len();
            let bottom = |out: &[Triangle], a: u32| -> Vertex {
                if b == 0 {
                    self.vertex(l, a, 0)
                } else {
                    // (a, b) is the top of the up triangle at (a, b - 1).
                    let t = &out[previous_row + 2 * a as usize];
                    (t.positions[2], t.normals[2])
                }
            };
            let width = n - b;
            let mut left = bottom(out, 0);
            let mut top = self.vertex(l, 0, b + 1);
            for a in 0..width {
                let right = bottom(out, a + 1);
                out.push(triangle([left, right, top]));
                if a + 1 < width {
                    let top_right = self.vertex(l, a + 1, b + 1);
                    out.push(triangle([right, top_right, top]));
                    top = top_right;
                }
                left = right;
            }
            previous_row = row;
        }
        debug_assert_eq!(out.len() as u64, self.triangles_per_lembo());
    }

    /// Unique vertices of the tessellated mesh: a vertex is a (position, normal) pair; corners
    /// and edge points shared by neighbouring lembos count once.
    ///
    /// Counted from keys, without generating the triangles: distinct corners (position and
    /// unit-normal bits), distinct edges (their canonical three points and normals, bits)
    /// times the n - 1 points inside each, and every lembo's (n - 1)(n - 2)/2 interior points.
    /// This is the number of distinct vertices the triangles hold unless two different keys
    /// happen to produce the same bits (e.g. two edges whose normals differ only in length).
    pub fn vertex_count(&self) -> u64 {
        self.index().vertices
    }

    /// The indexed mesh's vertex numbering ([`MeshIndex`]), made on first use from the
    /// lembos' construction points alone (no vertex is evaluated).
    fn index(&self) -> &MeshIndex {
        self.index.get_or_init(|| {
            let lembos = self.objects.iter().flat_map(|(lembos, _)| lembos.iter());
            MeshIndex::new(lembos, self.count, self.n)
        })
    }

    /// The vertex indices of lembo `lembo`'s n² triangles in the indexed mesh, in the local
    /// order of [`Tessellation::lembo_triangles`], into `out` (cleared first): what a
    /// geometry fetch reads from the index buffer, for its vertex cache.
    pub fn lembo_vertex_ids(&self, lembo: usize, out: &mut Vec<[u64; 3]>) {
        let index = self.index();
        let n = self.n;
        let id = |a: u32, b: u32| index.vertex(lembo, n, a, b);
        out.clear();
        for b in 0..n {
            for a in 0..n - b {
                out.push([id(a, b), id(a + 1, b), id(a, b + 1)]);
                if a + b + 1 < n {
                    out.push([id(a + 1, b), id(a + 1, b + 1), id(a, b + 1)]);
                }
            }
        }
    }

    /// The lattice point (a, b) of lembo `l` at this level ([`lattice_vertex`]).
    fn vertex(&self, l: &Lembo, a: u32, b: u32) -> Vertex {
        lattice_vertex(l, a, b, self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The architecture file's fetch defaults are the formats' sizes: a lembo's, a mesh
    /// vertex's and a triangle's indices (moved from the configuration's tests, which may
    /// not name the lembo module: it sits above them).
    #[test]
    fn the_fetch_defaults_are_the_formats_sizes() {
        let d = crate::config::ArchConfig::default();
        assert_eq!(d.fetch.bytes_per_lembo, crate::lembo::LEMBO_BYTES);
        assert_eq!(d.fetch.bytes_per_vertex, VERTEX_BYTES);
        assert_eq!(d.fetch.index_bytes_per_triangle, INDEX_BYTES_PER_TRIANGLE);
    }
}
