//! Tests of the triangle path's Tessellator (`lembo::tessellate`) on the shipped scenes: they
//! load scenes, which sit above the lembo module, so they live with the scene's tests. That
//! a tessellation's bytes are its indexed mesh's is the triangle source's test
//! (`raster::triangle::tests`).

use crate::lembo::lattice::subdivide;
use crate::lembo::tessellate::Tessellation;
use crate::lembo::{Lembo, REFERENCE_UV};
use crate::scene::Scene;
use glam::DVec3;
use std::collections::HashMap;
use std::path::Path;

/// The bits of `vectors`: a key equal for equal bits.
fn key_bits<const N: usize>(vectors: [DVec3; N]) -> [[u64; 3]; N] {
    vectors.map(|v| v.to_array().map(f64::to_bits))
}

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
    let tess = Tessellation::new(scene.lembo_sets(), 1);
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
            let tess = Tessellation::new(scene.lembo_sets(), n);
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
        }
    }
    // The closed sphere24 (14 vertices, 36 edges, 24 faces) shares every edge point.
    let sphere = trace("sphere24");
    for n in 1..=4u64 {
        let want = 14 + 36 * (n - 1) + 24 * (n - 1) * (n.max(2) - 2) / 2;
        let got = Tessellation::new(sphere.lembo_sets(), n as u32).vertex_count();
        assert_eq!(got, want, "sphere24 at n = {n}");
    }
}

#[test]
fn tessellate_vertices_lie_on_the_true_patch() {
    let mut out = Vec::new();
    for (name, levels) in [("sphere24", 1..=6), ("bunny", 3..=3)] {
        let scene = trace(name);
        for n in levels {
            let tess = Tessellation::new(scene.lembo_sets(), n);
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
            let tess = Tessellation::new(scene.lembo_sets(), n);
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
        let tess = Tessellation::new(scene.lembo_sets(), 1);
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
    Tessellation::new(flat.lembo_sets(), 2).lembo_triangles(0, &mut out);
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
    let tess = Tessellation::new(scene.lembo_sets(), 3);
    for id in 0..tess.len() {
        let t = tess.triangle(id);
        let [a, b, c] = t.positions;
        let geometric = (b - a).cross(c - a);
        let shading = t.normals[0] + t.normals[1] + t.normals[2];
        assert!(geometric.dot(shading) > 0.0, "triangle {id}: {t:?}");
    }
}
