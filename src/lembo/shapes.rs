//! Builtin shapes: the surfaces of the paper's Figures 6-8, built as triangle meshes with
//! exact vertex normals and converted to lembos (one per triangle), so the same mesh also
//! serves the triangle path.
//!
//! The paper gives the element counts only; the tessellations below are ours:
//! - `sphere24`: unit sphere, 6 longitudes by 3 latitude bands (poles, +-30 degrees): two
//!   caps of 6 triangles and a band of 12;
//! - `cylinder24`: radius 1, height 2 along y, 12 sides, open ends, 2 triangles per side;
//! - `surface96`: the height field y = 0.35 sin(1.4 x) cos(1.1 z) over [-2, 2] x [-1.5, 1.5],
//!   an 8 x 6 grid of 2 triangles per cell.
//!
//! And one family for scale, not from the paper: `terrainN` (N from 1 to
//! [`MAX_TERRAIN_CELLS`]), a height field of three octaves of sines over [-4, 4] x [-4, 4]
//! on an N x N grid, 2N² triangles (`terrain320`: 204 800 lembos).

use super::construct::TriangleMesh;
use super::Lembo;
use glam::DVec3;
use std::f64::consts::PI;

/// Names accepted by the scene format's `builtin` objects, beside the `terrainN` family.
pub const BUILTIN_NAMES: [&str; 3] = ["sphere24", "cylinder24", "surface96"];

/// The largest N of a `terrainN` builtin: 2N² = 8 388 608 lembos, which a scene holds as
/// their mesh (36 bytes a lembo, each lembo made on demand: [`crate::lembo::set`]); a run
/// peaks near 80 bytes a lembo above its frame buffers (RESULTS.md, "How cost grows").
pub const MAX_TERRAIN_CELLS: u32 = 2048;

/// The largest number of lembos a scene's builtin shapes may make together: one
/// `terrain2048`'s. A few bytes of scene file must not ask for more memory than a machine
/// has.
pub const MAX_BUILTIN_LEMBOS: u64 = 2 * (MAX_TERRAIN_CELLS as u64) * (MAX_TERRAIN_CELLS as u64);

/// The mesh of a builtin shape, or `None` for an unknown name.
pub fn builtin_mesh(name: &str) -> Option<TriangleMesh> {
    match name {
        "sphere24" => Some(sphere_mesh(6, 3)),
        "cylinder24" => Some(cylinder_mesh(12)),
        "surface96" => Some(surface_mesh(8, 6)),
        _ => terrain_cells(name).map(terrain_mesh),
    }
}

/// The lembos a builtin shape makes, without making them; `None` for an unknown name.
pub fn builtin_lembo_count(name: &str) -> Option<u64> {
    match name {
        "sphere24" | "cylinder24" => Some(24),
        "surface96" => Some(96),
        _ => terrain_cells(name).map(|n| 2 * u64::from(n) * u64::from(n)),
    }
}

/// N of a `terrainN` name: a plain decimal (no sign, no leading zero) within the cap.
fn terrain_cells(name: &str) -> Option<u32> {
    let n = name.strip_prefix("terrain")?;
    if n.is_empty() || n.starts_with('0') || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let n: u32 = n.parse().ok()?;
    (n <= MAX_TERRAIN_CELLS).then_some(n)
}

/// The lembos of a builtin shape, or `None` for an unknown name.
pub fn builtin_lembos(name: &str) -> Option<Vec<Lembo>> {
    builtin_mesh(name).map(|m| {
        m.to_lembos()
            .expect("the builtin meshes have three distinct corners per triangle")
    })
}

/// A UV sphere with `slices` longitudes and `stacks` latitude bands (poles shared).
pub fn sphere_mesh(slices: u32, stacks: u32) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    m.positions.push(DVec3::Y);
    for i in 1..stacks {
        let theta = PI * i as f64 / stacks as f64;
        for s in 0..slices {
            let phi = 2.0 * PI * s as f64 / slices as f64;
            m.positions.push(DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ));
        }
    }
    m.positions.push(-DVec3::Y);
    let south = m.positions.len() as u32 - 1;
    let ring = |i: u32, s: u32| 1 + (i - 1) * slices + s % slices;
    for s in 0..slices {
        m.triangles.push([0, ring(1, s), ring(1, s + 1)]);
    }
    for i in 1..stacks - 1 {
        for s in 0..slices {
            let (a, b) = (ring(i, s), ring(i, s + 1));
            let (c, d) = (ring(i + 1, s), ring(i + 1, s + 1));
            m.triangles.push([a, c, d]);
            m.triangles.push([a, d, b]);
        }
    }
    for s in 0..slices {
        m.triangles
            .push([south, ring(stacks - 1, s + 1), ring(stacks - 1, s)]);
    }
    m.normals = m.positions.clone();
    m
}

/// An open cylinder of radius 1 from y = -1 to y = 1 with `sides` sides.
pub fn cylinder_mesh(sides: u32) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    for s in 0..sides {
        let phi = 2.0 * PI * s as f64 / sides as f64;
        let (x, z) = (phi.cos(), -phi.sin());
        m.positions.push(DVec3::new(x, 1.0, z));
        m.positions.push(DVec3::new(x, -1.0, z));
        m.normals.push(DVec3::new(x, 0.0, z));
        m.normals.push(DVec3::new(x, 0.0, z));
    }
    for s in 0..sides {
        let (t0, b0) = (2 * s, 2 * s + 1);
        let (t1, b1) = (2 * ((s + 1) % sides), 2 * ((s + 1) % sides) + 1);
        m.triangles.push([t0, b0, b1]);
        m.triangles.push([t0, b1, t1]);
    }
    m
}

/// The height field y = 0.35 sin(1.4 x) cos(1.1 z) on an `nx` x `nz` grid of cells.
pub fn surface_mesh(nx: u32, nz: u32) -> TriangleMesh {
    height_field((nx, nz), (-2.0, 2.0, -1.5, 1.5), |x, z| {
        let y = 0.35 * (1.4 * x).sin() * (1.1 * z).cos();
        let dydx = 0.35 * 1.4 * (1.4 * x).cos() * (1.1 * z).cos();
        let dydz = -0.35 * 1.1 * (1.4 * x).sin() * (1.1 * z).sin();
        (y, dydx, dydz)
    })
}

/// A terrain: y = h(x, z), three octaves of sines over [-4, 4] x [-4, 4], on an `n` x `n`
/// grid of cells, two triangles a cell, with the height field's exact normals.
pub fn terrain_mesh(n: u32) -> TriangleMesh {
    // (amplitude, frequency in x, frequency in z, phase) of each octave.
    const OCTAVES: [(f64, f64, f64, f64); 3] = [
        (0.6, 0.7, 0.5, 0.0),
        (0.2, 1.9, 2.3, 1.0),
        (0.06, 5.3, 4.7, 2.0),
    ];
    height_field((n, n), (-4.0, 4.0, -4.0, 4.0), |x, z| {
        let (mut y, mut dydx, mut dydz) = (0.0, 0.0, 0.0);
        for (a, fx, fz, p) in OCTAVES {
            let (sx, cx) = (fx * x + p).sin_cos();
            let (sz, cz) = (fz * z).sin_cos();
            y += a * sx * cz;
            dydx += a * fx * cx * cz;
            dydz -= a * fz * sx * sz;
        }
        (y, dydx, dydz)
    })
}

/// The height field y = h(x, z) over `[x0, x1] x [z0, z1]` on an `nx` x `nz` grid of cells,
/// two triangles a cell facing +y; `h` gives y and its two partial derivatives, from which
/// the vertex normals are exact.
fn height_field(
    (nx, nz): (u32, u32),
    (x0, x1, z0, z1): (f64, f64, f64, f64),
    h: impl Fn(f64, f64) -> (f64, f64, f64),
) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    for j in 0..=nz {
        for i in 0..=nx {
            let x = x0 + (x1 - x0) * i as f64 / nx as f64;
            let z = z0 + (z1 - z0) * j as f64 / nz as f64;
            let (y, dydx, dydz) = h(x, z);
            m.positions.push(DVec3::new(x, y, z));
            m.normals.push(DVec3::new(-dydx, 1.0, -dydz).normalize());
        }
    }
    let idx = |i: u32, j: u32| j * (nx + 1) + i;
    for j in 0..nz {
        for i in 0..nx {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1));
            m.triangles.push([a, c, d]);
            m.triangles.push([a, d, b]);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `terrainN` is 2N² lembos for N in 1..=MAX_TERRAIN_CELLS, facing up; other spellings
    /// are unknown names.
    #[test]
    fn terrain_builtins_have_two_triangles_a_cell() {
        assert_eq!(builtin_lembos("terrain1").unwrap().len(), 2);
        assert_eq!(builtin_lembos("terrain20").unwrap().len(), 800);
        let m = builtin_mesh("terrain7").unwrap();
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).y > 0.0, "{t:?} faces down");
        }
        for bad in [
            "terrain",
            "terrain0",
            "terrain007",
            "terrain+3",
            "terrain2049",
            "terrainx",
        ] {
            assert!(builtin_mesh(bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn builtins_have_the_papers_element_counts() {
        assert_eq!(builtin_lembos("sphere24").unwrap().len(), 24);
        assert_eq!(builtin_lembos("cylinder24").unwrap().len(), 24);
        assert_eq!(builtin_lembos("surface96").unwrap().len(), 96);
        assert!(builtin_lembos("teapot").is_none());
    }

    #[test]
    fn builtin_triangles_face_outward() {
        for name in ["sphere24", "cylinder24"] {
            let m = builtin_mesh(name).unwrap();
            for t in &m.triangles {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let n = (b - a).cross(c - a);
                assert!(n.dot(a + b + c) > 0.0, "{name}: inward triangle {t:?}");
            }
        }
    }

    #[test]
    fn sphere24_lembos_stay_near_the_unit_sphere() {
        for l in builtin_lembos("sphere24").unwrap() {
            for k in 0..=10 {
                for j in 0..=(10 - k) {
                    let r = l.position_at(k as f64 / 10.0, j as f64 / 10.0).length();
                    assert!((0.85..=1.05).contains(&r), "radius {r}");
                }
            }
        }
    }
}
