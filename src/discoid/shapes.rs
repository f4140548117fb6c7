//! Discoid shapes: the curved discoids of the paper's Figure 10 (Piranda et al. 2006: "a sphere
//! covered by 20 curved discoids") and planar discoids at the vertices of a triangle mesh
//! (the atlases of Figures 11 and 12, and the surfels of Pfister et al. 2000).
//!
//! ## `sphere20`
//!
//! One curved discoid per face of the icosahedron inscribed in the unit sphere. For a face
//! with centre direction c (unit), the discoid is the planar discoid
//! `Discoid { center: c, normal: c, radius: R }` projected onto the sphere: a sphere point q
//! is inside it when its tangent-plane offset q - (q·c) c is shorter than R (and q·c > 0),
//! and its texture coordinates are [`Discoid::texcoord`] of q, i.e.
//! s = 0.5 + q·e1 / 2R, t = 0.5 + q·e2 / 2R with (e1, e2) = that discoid's
//! [`Discoid::frame`]. The surface carrying it is a lembo over an enlarged spherical
//! triangle around c: its corners are the face's vertices turned away from c to the angle
//! [`SPHERE20_CORNER_ANGLE_DEG`], its edge points the great-circle midpoints of the corners,
//! all on the unit sphere, with normals equal to the positions. The six texture coordinates
//! are those of the six points; inside the lembo they are interpolated by the same
//! quadratic basis as the position ([`lembo_texcoord`]).
//!
//! The numbers (angles from the face centre, measured on the unit sphere):
//! - a face's circumradius is 37.38° (its vertices), so the caps of tangent radius
//!   R > sin 37.38° = 0.6071 cover the sphere; neighbouring face centres are 41.81° apart;
//! - [`SPHERE20_RADIUS`] R = 0.65, a cap of asin 0.65 = 40.54°: every point of the sphere is
//!   inside at least one disk and all but small spots around the face centres (about 0.4% of
//!   the sphere, where the neighbours' caps at 40.54° do not reach 41.81°) inside two or more;
//! - corners at 62° from c give a lembo whose inscribed cap (the edge midpoints) is at
//!   atan(tan 62° / 2) = 43.24° > 40.54°: the enlarged triangle contains its disk. On the
//!   lembo's edges the interpolated texture coordinates stay at least 0.527 from (0.5, 0.5)
//!   (the rim is at 0.5), so beta is 0 along every edge.
//!
//! A quadratic patch this large sags below the sphere: inside its disk the one lembo's
//! distance from the centre is in [0.815, 0.982], and where disks overlap, the overlapping
//! lembos lie up to about 0.167 apart along the ray from the sphere's centre, more than the
//! default threshold (0.25 R = 0.1625): seams and dark spots where the threshold cut them.
//! So each discoid is drawn as [`SPHERE20_LEVELS`] = 3 splits of its spherical triangle by
//! great-circle midpoints ([`split_spherical`]): 64 lembos whose points all lie on the
//! sphere and carry the disk's texture coordinates, within [`SPHERE20_MAX_SAG`] = 0.001 of
//! the sphere inside the disk (two splits give 0.003), so overlapping discoids lie within
//! 0.002 of each other and the default threshold blends them. [`sphere20_at`]`(0)` is the
//! one-lembo construction; the figures of both are tested below.
//!
//! ## Planar discoids from a mesh
//!
//! [`discoids_from_mesh`] puts one planar discoid at every vertex, with the vertex normal
//! and a radius of `radius_scale` times the mean length of the distinct edges at that
//! vertex; [`subdivide_mesh`] first adds every edge's midpoint (1-to-4 split of every
//! triangle), so a closed mesh of V vertices and E edges gives V + E discoids.

use super::Discoid;
use crate::lembo::construct::TriangleMesh;
use crate::lembo::{Lembo, Quadratic};
use glam::DVec3;
use std::collections::HashMap;
use std::fmt;

/// Names accepted by the scene format's `"discoids": {"builtin": NAME}`.
pub const BUILTIN_DISCOID_NAMES: [&str; 1] = ["sphere20"];

/// The tangent-plane radius R of each of `sphere20`'s discoids [world units, unit sphere].
pub const SPHERE20_RADIUS: f64 = 0.65;

/// The angle between a `sphere20` lembo's corners and its face centre \[degrees\].
pub const SPHERE20_CORNER_ANGLE_DEG: f64 = 62.0;

/// How often each `sphere20` discoid's spherical triangle is split into four: it is drawn
/// as 4^levels lembos, so that it lies within [`SPHERE20_MAX_SAG`] of the sphere.
pub const SPHERE20_LEVELS: u32 = 3;

/// The largest distance of a `sphere20` discoid's lembos from the unit sphere inside the
/// discoid's disk, at [`SPHERE20_LEVELS`] (tested) \[world units, unit sphere\].
pub const SPHERE20_MAX_SAG: f64 = 1e-3;

/// How often the icosahedron's faces are split for the sphere the exact reference of the
/// builtin discoids renders ([`sphere_lembos`]).
pub const SPHERE_REFERENCE_LEVELS: u32 = 5;

/// Curved discoids: lembos with texture coordinates at their six reference points.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvedDiscoids {
    /// The lembos carrying the discoids, in world space.
    pub lembos: Vec<Lembo>,
    /// Texture coordinates (s, t) at A, B, C, D, E, F of each lembo, in the same order.
    pub texcoords: Vec<[[f64; 2]; 6]>,
    /// The radius of each discoid's disk [world units]: texture distance 0.5 from
    /// (0.5, 0.5) lies this far from the disk's centre.
    pub radii: Vec<f64>,
}

/// The curved discoids of a builtin shape, or `None` for an unknown name.
pub fn builtin_discoids(name: &str) -> Option<CurvedDiscoids> {
    match name {
        "sphere20" => Some(sphere20()),
        _ => None,
    }
}

/// The paper's Figure 10: the unit sphere covered by 20 curved discoids (module doc), each
/// drawn as `4^SPHERE20_LEVELS` lembos.
pub fn sphere20() -> CurvedDiscoids {
    sphere20_at(SPHERE20_LEVELS)
}

/// `sphere20` with each discoid's spherical triangle split `levels` times (0: one lembo
/// per discoid, the construction before the split, kept for its tests and the figures of
/// the module doc).
pub fn sphere20_at(levels: u32) -> CurvedDiscoids {
    let (vertices, faces) = icosahedron();
    let (sin_rho, cos_rho) = SPHERE20_CORNER_ANGLE_DEG.to_radians().sin_cos();
    let per_discoid = 4usize.pow(levels);
    let mut out = CurvedDiscoids {
        lembos: Vec::with_capacity(20 * per_discoid),
        texcoords: Vec::with_capacity(20 * per_discoid),
        radii: vec![SPHERE20_RADIUS; 20 * per_discoid],
    };
    for face in faces {
        let c = face.iter().map(|&i| vertices[i]).sum::<DVec3>().normalize();
        // Turn each vertex away from c, in its own direction, to the corner angle.
        let corner = |p: DVec3| cos_rho * c + sin_rho * (p - p.dot(c) * c).normalize();
        let disk = Discoid {
            center: c,
            normal: c,
            radius: SPHERE20_RADIUS,
        };
        for tri in split_spherical(face.map(|i| corner(vertices[i])), levels) {
            let points = spherical_lembo_points(tri);
            out.lembos.push(Lembo::new(points, points));
            out.texcoords.push(points.map(|p| disk.texcoord(p)));
        }
    }
    out
}

/// The six reference points of the lembo over the spherical triangle (a, b, c) of the unit
/// sphere: its corners and its edges' great-circle midpoints, in lembo order.
fn spherical_lembo_points([a, b, c]: [DVec3; 3]) -> [DVec3; 6] {
    [
        a,
        b,
        c,
        (a + b).normalize(),
        (a + c).normalize(),
        (b + c).normalize(),
    ]
}

/// The spherical triangle (a, b, c) of the unit sphere split `levels` times into four by its
/// edges' great-circle midpoints, counter-clockwise as given; neighbours share their
/// edges' midpoints exactly.
pub fn split_spherical(tri: [DVec3; 3], levels: u32) -> Vec<[DVec3; 3]> {
    let mut tris = vec![tri];
    for _ in 0..levels {
        tris = tris
            .into_iter()
            .flat_map(|[a, b, c]| {
                // IEEE addition commutes: both triangles at an edge get the same midpoint.
                let mid = |p: DVec3, q: DVec3| (p + q).normalize();
                let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

/// The unit sphere as `20 * 4^levels` lembos over the split faces of the icosahedron, with
/// normals equal to the positions: for the exact reference of the builtin discoids'
/// sphere ([`SPHERE_REFERENCE_LEVELS`] is within 1e-6 of it; tested).
pub fn sphere_lembos(levels: u32) -> Vec<Lembo> {
    let (vertices, faces) = icosahedron();
    faces
        .iter()
        .flat_map(|f| split_spherical(f.map(|i| vertices[i]), levels))
        .map(|tri| {
            let points = spherical_lembo_points(tri);
            Lembo::new(points, points)
        })
        .collect()
}

/// The texture coordinates of a curved discoid at domain point (u, v): the quadratic
/// through its six reference values, the same basis as the lembo's position.
pub fn lembo_texcoord(texcoords: &[[f64; 2]; 6], u: f64, v: f64) -> [f64; 2] {
    [0, 1].map(|k| Quadratic::from_reference_values(texcoords.map(|st| st[k])).eval(u, v))
}

/// The icosahedron inscribed in the unit sphere: 12 unit vertices (the cyclic permutations
/// of (0, ±1, ±φ), normalised) and 20 faces wound counter-clockwise seen from outside.
fn icosahedron() -> ([DVec3; 12], [[usize; 3]; 20]) {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v = [DVec3::ZERO; 12];
    let mut k = 0;
    for s1 in [-1.0, 1.0] {
        for s2 in [-1.0, 1.0] {
            v[k] = DVec3::new(0.0, s1, s2 * phi);
            v[k + 1] = DVec3::new(s1, s2 * phi, 0.0);
            v[k + 2] = DVec3::new(s2 * phi, 0.0, s1);
            k += 3;
        }
    }
    // Faces are the triples of mutually adjacent vertices (edge length 2 before scaling).
    let adjacent = |a: usize, b: usize| ((v[a] - v[b]).length() - 2.0).abs() < 1e-9;
    let mut faces = [[0; 3]; 20];
    let mut n = 0;
    for i in 0..12 {
        for j in i + 1..12 {
            for l in j + 1..12 {
                if adjacent(i, j) && adjacent(j, l) && adjacent(i, l) {
                    let outward = (v[j] - v[i]).cross(v[l] - v[i]).dot(v[i] + v[j] + v[l]) > 0.0;
                    faces[n] = if outward { [i, j, l] } else { [i, l, j] };
                    n += 1;
                }
            }
        }
    }
    debug_assert_eq!(n, 20);
    (v.map(|p| p.normalize()), faces)
}

/// Why a mesh cannot carry a planar discoid at every vertex. Indices are the mesh's
/// (0-based; for a subdivided mesh, of the subdivided vertices).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshDiscoidError {
    /// The vertex has a zero normal.
    ZeroNormal {
        /// The vertex's index.
        vertex: usize,
    },
    /// The two ends of an edge have opposite normals: its midpoint has none.
    OppositeNormals {
        /// The edge's two vertices.
        vertices: [usize; 2],
    },
    /// The vertex belongs to no triangle, so no edge gives it a radius.
    UnusedVertex {
        /// The vertex's index.
        vertex: usize,
    },
    /// Every edge at the vertex has zero length.
    ZeroRadius {
        /// The vertex's index.
        vertex: usize,
    },
}

impl fmt::Display for MeshDiscoidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MeshDiscoidError::ZeroNormal { vertex } => {
                write!(f, "vertex {vertex} has a zero normal")
            }
            MeshDiscoidError::OppositeNormals { vertices: [a, b] } => write!(
                f,
                "vertices {a} and {b} have opposite normals: their edge's midpoint has no normal"
            ),
            MeshDiscoidError::UnusedVertex { vertex } => write!(
                f,
                "vertex {vertex} is in no triangle: no edge gives its discoid a radius"
            ),
            MeshDiscoidError::ZeroRadius { vertex } => {
                write!(f, "every edge at vertex {vertex} has zero length")
            }
        }
    }
}

/// A planar discoid at every vertex of `mesh` (after [`subdivide_mesh`] when `subdivide`):
/// the vertex's position and unit normal, radius = `radius_scale` × the mean length of the
/// distinct edges at the vertex.
pub fn discoids_from_mesh(
    mesh: &TriangleMesh,
    subdivide: bool,
    radius_scale: f64,
) -> Result<Vec<Discoid>, MeshDiscoidError> {
    if subdivide {
        vertex_discoids(&subdivide_mesh(mesh)?, radius_scale)
    } else {
        vertex_discoids(mesh, radius_scale)
    }
}

/// The midpoint subdivision of `mesh`: every edge gains its (straight) midpoint, with the
/// normalised average of its ends' unit normals, and every triangle becomes four. Midpoints
/// are numbered after the original vertices, in order of first use by the triangles.
pub fn subdivide_mesh(mesh: &TriangleMesh) -> Result<TriangleMesh, MeshDiscoidError> {
    let unit = |i: u32| unit_normal(mesh.normals[i as usize], i as usize);
    let mut out = TriangleMesh {
        positions: mesh.positions.clone(),
        normals: Vec::with_capacity(mesh.normals.len()),
        triangles: Vec::with_capacity(4 * mesh.triangles.len()),
    };
    for i in 0..mesh.normals.len() {
        out.normals.push(unit(i as u32)?);
    }
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
    for &[a, b, c] in &mesh.triangles {
        let mut mid = |p: u32, q: u32| -> Result<u32, MeshDiscoidError> {
            let key = (p.min(q), p.max(q));
            if let Some(&m) = midpoints.get(&key) {
                return Ok(m);
            }
            let n = out.normals[p as usize] + out.normals[q as usize];
            let Some(n) = n.try_normalize() else {
                return Err(MeshDiscoidError::OppositeNormals {
                    vertices: [key.0 as usize, key.1 as usize],
                });
            };
            let m = out.positions.len() as u32;
            let (pp, pq) = (mesh.positions[p as usize], mesh.positions[q as usize]);
            out.positions.push(0.5 * (pp + pq));
            out.normals.push(n);
            midpoints.insert(key, m);
            Ok(m)
        };
        let (ab, bc, ca) = (mid(a, b)?, mid(b, c)?, mid(c, a)?);
        out.triangles
            .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Ok(out)
}

/// The unit normal of vertex `i`, robust to very small and very large finite normals.
fn unit_normal(n: DVec3, vertex: usize) -> Result<DVec3, MeshDiscoidError> {
    let m = n.abs().max_element();
    if m > 0.0 {
        if let Some(u) = (n / m).try_normalize() {
            return Ok(u);
        }
    }
    Err(MeshDiscoidError::ZeroNormal { vertex })
}

fn vertex_discoids(
    mesh: &TriangleMesh,
    radius_scale: f64,
) -> Result<Vec<Discoid>, MeshDiscoidError> {
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(p, q)| (p.min(q), p.max(q)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut length_sum = vec![0.0; mesh.positions.len()];
    let mut count = vec![0u32; mesh.positions.len()];
    for (p, q) in edges {
        let (p, q) = (p as usize, q as usize);
        let len = mesh.positions[p].distance(mesh.positions[q]);
        length_sum[p] += len;
        length_sum[q] += len;
        count[p] += 1;
        count[q] += 1;
    }
    (0..mesh.positions.len())
        .map(|i| {
            if count[i] == 0 {
                return Err(MeshDiscoidError::UnusedVertex { vertex: i });
            }
            let mean = length_sum[i] / count[i] as f64;
            if mean <= 0.0 {
                return Err(MeshDiscoidError::ZeroRadius { vertex: i });
            }
            Ok(Discoid {
                center: mesh.positions[i],
                normal: unit_normal(mesh.normals[i], i)?,
                radius: radius_scale * mean,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` points spread evenly over the unit sphere (Fibonacci lattice).
    fn sphere_sample(n: usize) -> Vec<DVec3> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - y * y).sqrt();
                let a = golden * i as f64;
                DVec3::new(r * a.cos(), y, r * a.sin())
            })
            .collect()
    }

    fn face_centres() -> Vec<DVec3> {
        let (v, faces) = icosahedron();
        faces
            .iter()
            .map(|f| f.iter().map(|&i| v[i]).sum::<DVec3>().normalize())
            .collect()
    }

    /// Distance of texture coordinates from the disk's centre (the rim is at 0.5).
    fn from_centre(st: [f64; 2]) -> f64 {
        (st[0] - 0.5).hypot(st[1] - 0.5)
    }

    /// The domain point (u, v) where the lembo crosses the ray from the origin through the
    /// unit vector q, found by Newton's method from the domain's centre; None if the
    /// crossing is outside the domain.
    fn crossing(l: &Lembo, q: DVec3) -> Option<(f64, f64)> {
        let g1 = q.any_orthonormal_vector();
        let g2 = q.cross(g1);
        let (mut u, mut v) = (1.0 / 3.0, 1.0 / 3.0);
        for _ in 0..60 {
            let b = l.position_at(u, v);
            let (bu, bv) = l.position_derivatives(u, v);
            let (f1, f2) = (b.dot(g1), b.dot(g2));
            let (j11, j12, j21, j22) = (bu.dot(g1), bv.dot(g1), bu.dot(g2), bv.dot(g2));
            let det = j11 * j22 - j12 * j21;
            if det == 0.0 {
                return None;
            }
            let (du, dv) = ((f1 * j22 - f2 * j12) / det, (j11 * f2 - j21 * f1) / det);
            u -= du;
            v -= dv;
            if du.abs() + dv.abs() < 1e-14 {
                break;
            }
        }
        let b = l.position_at(u, v);
        let on_ray = b.dot(q) > 0.0 && (b.normalize() - q).length() < 1e-9;
        let inside = u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9;
        (on_ray && inside).then_some((u, v))
    }

    #[test]
    fn icosahedron_has_twenty_outward_faces_of_equal_edges() {
        let (v, faces) = icosahedron();
        let edge = v[faces[0][0]].distance(v[faces[0][1]]);
        for f in faces {
            let [a, b, c] = f.map(|i| v[i]);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "{f:?}");
            for (p, q) in [(a, b), (b, c), (c, a)] {
                assert!((p.distance(q) - edge).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn sphere20_disks_cover_the_sphere_mostly_twice() {
        // The paper's criterion: a point is inside a discoid where beta > 0, here inside
        // radius R of the tangent-plane disk at the face centre.
        let centres = face_centres();
        let sample = sphere_sample(20_000);
        let mut twice = 0;
        for q in &sample {
            let n = centres
                .iter()
                .filter(|&&c| q.dot(c) > 0.0 && (*q - q.dot(c) * c).length() < SPHERE20_RADIUS)
                .count();
            assert!(n >= 1, "{q} is in no discoid");
            twice += usize::from(n >= 2);
        }
        let fraction = twice as f64 / sample.len() as f64;
        assert!(fraction > 0.99, "{fraction}");
    }

    #[test]
    fn sphere20_drawn_discoids_leave_no_hole() {
        // What the renderer blends: along every ray from the centre, at least one lembo
        // whose interpolated texture coordinates are inside the disk, mostly two.
        let s = sphere20();
        let sample = sphere_sample(5_000);
        let mut twice = 0;
        for &q in &sample {
            let n = s
                .lembos
                .iter()
                .zip(&s.texcoords)
                .filter(|(l, st)| {
                    crossing(l, q).is_some_and(|(u, v)| from_centre(lembo_texcoord(st, u, v)) < 0.5)
                })
                .count();
            assert!(n >= 1, "{q} is in no drawn discoid");
            twice += usize::from(n >= 2);
        }
        assert!(twice as f64 / sample.len() as f64 > 0.99);
    }

    #[test]
    fn sphere20_lembos_contain_their_disks() {
        // beta = 0 on every edge of every lembo (the texture rim is at distance 0.5).
        let s = sphere20_at(0);
        let n = 400;
        let mut nearest = f64::INFINITY;
        for st in &s.texcoords {
            for k in 0..=n {
                let a = k as f64 / n as f64;
                for (u, v) in [(a, 0.0), (0.0, a), (a, 1.0 - a)] {
                    nearest = nearest.min(from_centre(lembo_texcoord(st, u, v)));
                }
            }
        }
        assert!(nearest > 0.52, "{nearest}");
    }

    #[test]
    fn sphere20_texcoords_are_centred_on_the_face_centre() {
        let s = sphere20_at(0);
        for ((l, st), c) in s.lembos.iter().zip(&s.texcoords).zip(face_centres()) {
            let disk = Discoid {
                center: c,
                normal: c,
                radius: SPHERE20_RADIUS,
            };
            assert_eq!(disk.texcoord(c), [0.5, 0.5]);
            // The construction is symmetric under the face's 120° turn, so the domain's
            // centre lies on the axis c and carries the disk's centre.
            let [s0, t0] = lembo_texcoord(st, 1.0 / 3.0, 1.0 / 3.0);
            assert!(
                (s0 - 0.5).abs() < 1e-12 && (t0 - 0.5).abs() < 1e-12,
                "{s0} {t0}"
            );
            let p = l.position_at(1.0 / 3.0, 1.0 / 3.0);
            assert!(p.normalize().distance(c) < 1e-12);
            // The six reference texcoords are the disk's texcoords of the six points.
            assert_eq!(*st, l.points.map(|p| disk.texcoord(p)));
            assert_eq!(l.normals, l.points);
            assert!(l.points.iter().all(|p| (p.length() - 1.0).abs() < 1e-15));
        }
        assert_eq!(s.radii, vec![SPHERE20_RADIUS; 20]);
    }

    #[test]
    fn sphere20_sag_and_overlap_gap_are_as_documented() {
        let s = sphere20_at(0);
        // Inside each disk the lembo stays within [0.815, 0.982] of the centre.
        let n = 60;
        for (l, st) in s.lembos.iter().zip(&s.texcoords) {
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    if from_centre(lembo_texcoord(st, u, v)) < 0.5 {
                        let r = l.position_at(u, v).length();
                        assert!((0.81..=0.99).contains(&r), "{r}");
                    }
                }
            }
        }
        // Overlapping discoids lie at most 0.17 apart along a ray: more than the default
        // threshold (0.25 R = 0.16), so the one-lembo discoids needed 0.2.
        let mut gap = 0f64;
        for q in sphere_sample(2_000) {
            let radii = drawn_radii(&s, q);
            let lo = radii.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = radii.iter().copied().fold(0.0, f64::max);
            gap = gap.max(hi - lo);
        }
        assert!(gap > 0.1 && gap < 0.17, "{gap}");
    }

    /// The distances from the centre at which the ray from the centre through `q` meets
    /// the drawn part (inside the disk) of each discoid of `s` it crosses.
    fn drawn_radii(s: &CurvedDiscoids, q: DVec3) -> Vec<f64> {
        s.lembos
            .iter()
            .zip(&s.texcoords)
            .filter_map(|(l, st)| {
                let (u, v) = crossing(l, q)?;
                (from_centre(lembo_texcoord(st, u, v)) < 0.5).then(|| l.position_at(u, v).length())
            })
            .collect()
    }

    /// The largest |r - 1| of `lembos` (with texture coordinates `st`, restricted to the
    /// inside of their disks when given), over a grid of 20 steps a side.
    fn sag(lembos: &[Lembo], st: Option<&[[[f64; 2]; 6]]>) -> f64 {
        let n = 20;
        let mut worst = 0f64;
        for (k, l) in lembos.iter().enumerate() {
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    if st.is_some_and(|st| from_centre(lembo_texcoord(&st[k], u, v)) >= 0.5) {
                        continue;
                    }
                    worst = worst.max((l.position_at(u, v).length() - 1.0).abs());
                }
            }
        }
        worst
    }

    #[test]
    fn sphere20_split_discoids_fit_the_sphere() {
        let s = sphere20();
        assert_eq!(s.lembos.len(), 20 * 4usize.pow(SPHERE20_LEVELS));
        let worst = sag(&s.lembos, Some(&s.texcoords));
        assert!(worst <= SPHERE20_MAX_SAG, "{worst}");
        // One level fewer would not do: the bound is what the level buys.
        let coarser = sphere20_at(SPHERE20_LEVELS - 1);
        assert!(sag(&coarser.lembos, Some(&coarser.texcoords)) > SPHERE20_MAX_SAG);
        // Overlapping discoids now lie within twice the sag along a ray, far below the
        // default threshold.
        let mut gap = 0f64;
        for q in sphere_sample(300) {
            let radii = drawn_radii(&s, q);
            assert!(!radii.is_empty(), "{q} is in no drawn discoid");
            let lo = radii.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = radii.iter().copied().fold(0.0, f64::max);
            gap = gap.max(hi - lo);
        }
        assert!(gap <= 2.0 * SPHERE20_MAX_SAG, "{gap}");
        // Every sub-lembo of a discoid carries that discoid's texture coordinates: where a
        // sub-lembo's point is a corner of the whole discoid's triangle, it has the
        // coordinates the one-lembo discoid has there.
        let whole = sphere20_at(0);
        assert_eq!(whole.lembos.len(), 20);
        let per = 4usize.pow(SPHERE20_LEVELS);
        let mut matched = 0;
        for (k, (l, st)) in s.lembos.iter().zip(&s.texcoords).enumerate() {
            let g = k / per;
            for (p, t) in l.points.iter().zip(st) {
                if let Some(c) = whole.lembos[g].points[..3].iter().position(|q| q == p) {
                    assert_eq!(*t, whole.texcoords[g][c]);
                    matched += 1;
                }
            }
        }
        assert_eq!(matched, 20 * 3, "each discoid's three corners, once each");
    }

    #[test]
    fn the_reference_sphere_is_within_a_millionth_of_the_unit_sphere() {
        let lembos = sphere_lembos(SPHERE_REFERENCE_LEVELS);
        assert_eq!(lembos.len(), 20 * 4usize.pow(SPHERE_REFERENCE_LEVELS));
        let worst = sag(&lembos, None);
        assert!(worst < 1e-6, "{worst}");
    }

    fn square() -> TriangleMesh {
        // Unit square in z = 0 split along its diagonal 0-2.
        TriangleMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            normals: vec![DVec3::new(0.0, 0.0, 3.0); 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn vertex_radius_is_the_mean_incident_edge_length() {
        let d = discoids_from_mesh(&square(), false, 1.0).unwrap();
        assert_eq!(d.len(), 4);
        // Vertex 0: edges of length 1, 1 and the diagonal; vertex 1: two of length 1.
        let diag = 2f64.sqrt();
        assert!((d[0].radius - (2.0 + diag) / 3.0).abs() < 1e-15);
        assert!((d[1].radius - 1.0).abs() < 1e-15);
        assert_eq!(d[1].normal, DVec3::Z);
        assert_eq!(d[2].center, DVec3::new(1.0, 1.0, 0.0));
        let scaled = discoids_from_mesh(&square(), false, 0.5).unwrap();
        assert!((scaled[1].radius - 0.5).abs() < 1e-15);
    }

    #[test]
    fn subdivision_adds_every_edge_midpoint() {
        let m = subdivide_mesh(&square()).unwrap();
        // 4 vertices + 5 edges; 2 triangles become 8.
        assert_eq!(m.positions.len(), 9);
        assert_eq!(m.triangles.len(), 8);
        // The first midpoint is that of edge 0-1.
        assert_eq!(m.positions[4], DVec3::new(0.5, 0.0, 0.0));
        assert!(m.normals.iter().all(|&n| n == DVec3::Z));
        let d = discoids_from_mesh(&square(), true, 1.0).unwrap();
        assert_eq!(d.len(), 9);
        // A corner's edges are halved.
        assert!((d[1].radius - 0.5).abs() < 1e-15);
    }

    #[test]
    fn bad_meshes_name_the_vertex() {
        let mut m = square();
        m.normals[2] = DVec3::ZERO;
        assert_eq!(
            discoids_from_mesh(&m, false, 1.0),
            Err(MeshDiscoidError::ZeroNormal { vertex: 2 })
        );
        let mut m = square();
        m.normals[1] = -m.normals[0];
        assert_eq!(
            subdivide_mesh(&m).err(),
            Some(MeshDiscoidError::OppositeNormals { vertices: [0, 1] })
        );
        let mut m = square();
        m.positions.push(DVec3::ONE);
        m.normals.push(DVec3::Z);
        assert_eq!(
            discoids_from_mesh(&m, false, 1.0),
            Err(MeshDiscoidError::UnusedVertex { vertex: 4 })
        );
        let mut m = square();
        m.positions = vec![DVec3::ONE; 4];
        assert_eq!(
            discoids_from_mesh(&m, false, 1.0),
            Err(MeshDiscoidError::ZeroRadius { vertex: 0 })
        );
        // Normals far below and above 1 still normalise.
        let mut m = square();
        m.normals[0] = DVec3::new(0.0, 0.0, 1e-310);
        m.normals[1] = DVec3::new(0.0, 0.0, 1e300);
        let d = discoids_from_mesh(&m, false, 1.0).unwrap();
        assert_eq!((d[0].normal, d[1].normal), (DVec3::Z, DVec3::Z));
    }
}
