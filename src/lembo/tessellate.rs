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
//! Input: a [`Scene`]'s lembos and the level n. Output: [`Triangle`]s in world space, one at
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
use super::Lembo;
use crate::scene::{LemboIndex, Scene};
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

/// A scene's lembos tessellated at level n: n² triangles per lembo, computed on demand.
#[derive(Clone, Debug)]
pub struct Tessellation<'a> {
    /// The scene whose lembos, in global-id order, are tessellated (each made when its
    /// triangles are asked for).
    scene: &'a Scene,
    /// Where its objects' lembos start.
    starts: LemboIndex,
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
    /// The tessellation of every lembo of `scene` at level `n` (n steps per domain edge;
    /// n >= 1, validated by the caller).
    pub fn new(scene: &'a Scene, n: u32) -> Self {
        debug_assert!(n >= 1, "tessellation level must be at least 1");
        Tessellation {
            scene,
            starts: scene.lembo_index(),
            count: scene.lembo_count(),
            n,
            index: OnceLock::new(),
        }
    }

    /// The level n: steps per domain edge.
    pub fn level(&self) -> u32 {
        self.n
    }

    /// The number of triangles: lembos × n².
    pub fn len(&self) -> u64 {
        self.count as u64 * self.triangles_per_lembo()
    }

    /// Whether there are no triangles (the scene has no lembos).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Lembos tessellated (the scene's, in scene order).
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
        let (lembo, color) = self.scene.lembo(&self.starts, (id / per_lembo) as usize);
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
        let (l, color) = self.scene.lembo(&self.starts, lembo);
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
            let lembos = self.scene.lembos().map(|(l, _)| l);
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
    use crate::lembo::lattice::subdivide;
    use crate::lembo::REFERENCE_UV;
    use std::path::Path;

    fn trace(name: &str) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("traces")
            .join(format!("{name}.json"));
        Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The lattice points of each local triangle, in local order, written out from the
    /// order's definition independently of the implementation.
    fn local_lattice(n: u32) -> Vec<[(u32, u32); 3]> {
        let mut t = Vec::new();
        for b in 0..n {
            for a in 0..n - b {
                t.push([(a, b), (a + 1, b), (a, b + 1)]);
                if a + b + 1 < n {
                    t.push([(a + 1, b), (a + 1, b + 1), (a, b + 1)]);
                }
            }
        }
        t
    }

    /// A subdivided lembo is 4^s lembos on the parent's surface (positions within rounding
    /// of the parent's at the same domain point), and neighbours share their corners bit
    /// for bit: the subdivided closed sphere24 has the corners Euler's formula gives.
    #[test]
    fn subdivided_lembos_stay_on_the_surface_without_cracks() {
        let scene = trace("sphere24");
        let lembos: Vec<Lembo> = scene.lembos().map(|(l, _)| l).collect();
        for s in 0..=2u32 {
            let m = 1u32 << s;
            let mut out = Vec::new();
            for l in &lembos {
                let first = out.len();
                subdivide(l, s, &mut out);
                assert_eq!(out.len() - first, (m * m) as usize);
                // Each sub-lembo's centre against the parent's at the same point: sub-triangle
                // t of the level-m lattice, in local order.
                for (t, sub) in local_lattice(m).iter().zip(&out[first..]) {
                    let (u, v) = t.iter().fold((0.0, 0.0), |(u, v), &(a, b)| {
                        (u + a as f64 / (3 * m) as f64, v + b as f64 / (3 * m) as f64)
                    });
                    let third = 1.0 / 3.0;
                    let got = sub.position_at(third, third);
                    let want = l.position_at(u, v);
                    assert!(
                        (got - want).length() < 1e-12,
                        "s = {s}: {got} against {want}"
                    );
                }
            }
            let corners: std::collections::HashSet<_> = out
                .iter()
                .flat_map(|l| (0..3).map(|k| key_bits([l.points[k]])))
                .collect();
            // V - E + F = 2 with F = 24 m², E = 3F/2.
            let faces = 24 * (m * m) as usize;
            assert_eq!(corners.len(), 2 + faces / 2, "s = {s}");
        }
    }

    #[test]
    fn tessellate_level_one_reproduces_the_mesh_bit_for_bit() {
        let scene = trace("bunny");
        let mesh = scene.objects[0].mesh().unwrap();
        let tess = Tessellation::new(&scene, 1);
        assert_eq!(tess.len(), mesh.triangles.len() as u64);
        for (id, t) in mesh.triangles.iter().enumerate() {
            let got = tess.triangle(id as u64);
            for (k, &i) in t.iter().enumerate() {
                let i = i as usize;
                assert_eq!(
                    got.positions[k].to_array().map(f64::to_bits),
                    mesh.positions[i].to_array().map(f64::to_bits),
                    "triangle {id} vertex {k}"
                );
                let want = mesh.normals[i].normalize_or_zero();
                assert!(
                    (got.normals[k] - want).length() < 1e-12,
                    "triangle {id} vertex {k}: normal {} want {want}",
                    got.normals[k]
                );
            }
            assert_eq!(got.color, scene.objects[0].color);
        }
    }

    /// The index buffer numbers the vertices the triangles hold one to one: a generated
    /// vertex's bits have one index and an index one vertex's bits, and the indices are
    /// exactly 0..vertex_count.
    #[test]
    fn tessellate_vertex_count_equals_distinct_generated_vertices_so_no_cracks() {
        let (mut out, mut ids) = (Vec::new(), Vec::new());
        for (name, levels) in [("sphere24", 1..=4), ("bunny", 1..=2), ("bunny", 5..=5)] {
            let scene = trace(name);
            for n in levels {
                let tess = Tessellation::new(&scene, n);
                let mut distinct = HashMap::new();
                let mut by_id = HashMap::new();
                for l in 0..scene.lembo_count() {
                    tess.lembo_triangles(l, &mut out);
                    tess.lembo_vertex_ids(l, &mut ids);
                    assert_eq!(ids.len(), out.len());
                    for (t, id) in out.iter().zip(&ids) {
                        for (k, &i) in id.iter().enumerate() {
                            let key = key_bits([t.positions[k], t.normals[k]]);
                            assert_eq!(*distinct.entry(key).or_insert(i), i, "{name}");
                            assert_eq!(*by_id.entry(i).or_insert(key), key, "{name}");
                        }
                    }
                }
                let count = tess.vertex_count();
                assert_eq!(count, distinct.len() as u64, "{name} at n = {n}");
                assert!(by_id.keys().all(|&i| i < count), "{name} at n = {n}");
                let sizes = crate::config::FetchConfig::default();
                assert_eq!(
                    crate::raster::triangle::TriangleSource::bytes(&tess, &sizes),
                    count * VERTEX_BYTES + tess.len() * INDEX_BYTES_PER_TRIANGLE
                );
            }
        }
        // The closed sphere24 (14 vertices, 36 edges, 24 faces) shares every edge point.
        let sphere = trace("sphere24");
        for n in 1..=4u64 {
            let want = 14 + 36 * (n - 1) + 24 * (n - 1) * (n.max(2) - 2) / 2;
            let got = Tessellation::new(&sphere, n as u32).vertex_count();
            assert_eq!(got, want, "sphere24 at n = {n}");
        }
    }

    #[test]
    fn tessellate_vertices_lie_on_the_true_patch() {
        let mut out = Vec::new();
        for (name, levels) in [("sphere24", 1..=6), ("bunny", 3..=3)] {
            let scene = trace(name);
            for n in levels {
                let tess = Tessellation::new(&scene, n);
                let lattice = local_lattice(n);
                for (l, (lembo, _)) in scene.lembos().enumerate() {
                    let scale = lembo
                        .points
                        .iter()
                        .map(|p| p.abs().max_element())
                        .fold(1.0, f64::max);
                    tess.lembo_triangles(l, &mut out);
                    assert_eq!(out.len(), lattice.len());
                    for (t, points) in out.iter().zip(&lattice) {
                        for (k, &(a, b)) in points.iter().enumerate() {
                            let (u, v) = (a as f64 / n as f64, b as f64 / n as f64);
                            let dp = (t.positions[k] - lembo.position_at(u, v)).length();
                            let dn = (t.normals[k] - lembo.unit_normal_at(u, v)).length();
                            assert!(
                                dp <= 1e-12 * scale,
                                "{name} n={n} lembo {l} ({a},{b}): {dp}"
                            );
                            assert!(dn <= 1e-12, "{name} n={n} lembo {l} ({a},{b}): {dn}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn tessellate_triangle_by_id_matches_lembo_triangles_in_local_order() {
        let mut out = Vec::new();
        for (name, levels, stride) in [("sphere24", 1..=5, 1), ("bunny", 1..=3, 997)] {
            let scene = trace(name);
            for n in levels {
                let tess = Tessellation::new(&scene, n);
                let per_lembo = u64::from(n * n);
                assert_eq!(tess.level(), n);
                assert_eq!(tess.triangles_per_lembo(), per_lembo);
                assert_eq!(tess.len(), scene.lembo_count() as u64 * per_lembo);
                assert!(!tess.is_empty());
                let mut ids: Vec<u64> = (0..tess.len()).step_by(stride).collect();
                ids.push(tess.len() - 1);
                for id in ids {
                    tess.lembo_triangles((id / per_lembo) as usize, &mut out);
                    assert_eq!(
                        tess.triangle(id),
                        out[(id % per_lembo) as usize],
                        "{name} {id}"
                    );
                }
            }
            // n = 1: the lembo's own corners A, B, C.
            let tess = Tessellation::new(&scene, 1);
            for (id, (lembo, color)) in scene.lembos().enumerate() {
                let t = tess.triangle(id as u64);
                assert_eq!(
                    t.positions,
                    [lembo.points[0], lembo.points[1], lembo.points[2]]
                );
                assert_eq!(t.color, color);
            }
        }

        // The local order spelled out on a flat lembo whose positions are its domain points.
        let domain = REFERENCE_UV.map(|(u, v)| [u, v, 0.0]);
        let json = format!(
            r#"{{"name": "flat", "camera": {{"eye": [0, 0, 5], "target": [0, 0, 0],
                "projection": {{"kind": "orthographic", "height": 2, "near": 1, "far": 10}}}},
                "objects": [{{"lembos": [{{"points": {domain:?}, "normals": {:?}}}]}}]}}"#,
            [[0.0, 0.0, 1.0]; 6]
        );
        let flat = Scene::from_json(&json, "flat", Path::new(".")).unwrap();
        Tessellation::new(&flat, 2).lembo_triangles(0, &mut out);
        let want = [
            [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)],
            [(0.5, 0.0), (0.5, 0.5), (0.0, 0.5)],
            [(0.5, 0.0), (1.0, 0.0), (0.5, 0.5)],
            [(0.0, 0.5), (0.5, 0.5), (0.0, 1.0)],
        ];
        assert_eq!(out.len(), want.len());
        for (t, want) in out.iter().zip(want) {
            for (p, (u, v)) in t.positions.iter().zip(want) {
                assert!(
                    (*p - DVec3::new(u, v, 0.0)).length() < 1e-15,
                    "{p} want ({u}, {v})"
                );
            }
            assert_eq!(t.normals, [DVec3::Z; 3]);
        }
    }

    #[test]
    fn tessellate_triangles_face_their_vertex_normals() {
        let scene = trace("sphere24");
        let tess = Tessellation::new(&scene, 3);
        for id in 0..tess.len() {
            let t = tess.triangle(id);
            let [a, b, c] = t.positions;
            let geometric = (b - a).cross(c - a);
            let shading = t.normals[0] + t.normals[1] + t.normals[2];
            assert!(geometric.dot(shading) > 0.0, "triangle {id}: {t:?}");
        }
    }
}
