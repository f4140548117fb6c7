//! Tests of the exact reference: ray hits on lembos against known points and edge cases, the
//! image from inside a closed surface, the tracer between pixel centres, determinism and
//! supersampled coverage.

use super::*;
use crate::camera::{Camera, Projection, Viewport};
use crate::lembo::shapes::builtin_lembos;
use crate::lembo::REFERENCE_UV;
use glam::DVec2;

/// The lembo of an exactly quadratic map (points and normals sampled from it).
fn lembo_of(f: impl Fn(f64, f64) -> DVec3, n: impl Fn(f64, f64) -> DVec3) -> Lembo {
    Lembo::new(
        REFERENCE_UV.map(|(u, v)| f(u, v)),
        REFERENCE_UV.map(|(u, v)| n(u, v)),
    )
}

/// The triangle (1,0,0), (3,0,0), (1,2,0) in the plane z = 0, linear in (u, v).
fn flat_lembo() -> Lembo {
    lembo_of(
        |u, v| DVec3::new(1.0 + 2.0 * u, 2.0 * v, 0.0),
        |_, _| DVec3::Z,
    )
}

#[test]
fn intersect_ray_hits_a_flat_lembo_at_the_known_point() {
    let l = flat_lembo();
    // Through b(0.25, 0.4) = (1.5, 0.8, 0), obliquely, from 3 units away.
    let target = DVec3::new(1.5, 0.8, 0.0);
    let dir = DVec3::new(0.3, -0.2, -1.0).normalize();
    let origin = target - 3.0 * dir;
    let hits = intersect_ray(&l, origin, dir);
    assert_eq!(hits.len(), 1, "{hits:?}");
    let (t, u, v) = hits[0];
    assert!(
        (t - 3.0).abs() < 1e-12 && (u - 0.25).abs() < 1e-12 && (v - 0.4).abs() < 1e-12,
        "{hits:?}"
    );
    // t is in units of an unnormalised direction.
    let hits = intersect_ray(&l, origin, 2.0 * dir);
    assert!((hits[0].0 - 1.5).abs() < 1e-12);
}

#[test]
fn intersect_ray_misses_outside_the_domain() {
    let l = flat_lembo();
    // b(0.75, 0.75) = (2.5, 1.5, 0) is on the plane but outside u + v <= 1.
    let hits = intersect_ray(&l, DVec3::new(2.5, 1.5, 2.0), -DVec3::Z);
    assert!(hits.is_empty(), "{hits:?}");
    // Parallel to the plane.
    assert!(intersect_ray(&l, DVec3::new(0.0, 0.5, 1.0), DVec3::X).is_empty());
}

#[test]
fn intersect_ray_hit_lies_on_a_curved_sphere24_lembo() {
    let lembos = builtin_lembos("sphere24").unwrap();
    let l = &lembos[8];
    let eye = DVec3::new(0.3, 0.2, 5.0);
    let target = l.position_at(0.3, 0.2);
    let dir = (target - eye).normalize();
    let hits = intersect_ray(l, eye, dir);
    assert!(!hits.is_empty());
    let mut found = false;
    for &(t, u, v) in &hits {
        assert!(
            (l.position_at(u, v) - (eye + t * dir)).length() < 1e-9,
            "{hits:?}"
        );
        found |= (u - 0.3).abs() < 1e-9 && (v - 0.2).abs() < 1e-9;
    }
    assert!(found, "{hits:?}");
}

/// z = 4 (u - 1/2)², a parabolic trough along v.
fn trough() -> Lembo {
    lembo_of(
        |u, v| DVec3::new(u, v, 4.0 * (u - 0.5) * (u - 0.5)),
        |u, _| DVec3::new(-8.0 * (u - 0.5), 0.0, 1.0),
    )
}

#[test]
fn intersect_ray_finds_both_hits_through_a_trough_sorted_by_t() {
    // The ray along x at z = 1/4 enters and leaves the trough at u = 1/4 and u = 3/4.
    let hits = intersect_ray(&trough(), DVec3::new(-1.0, 0.1, 0.25), DVec3::X);
    assert_eq!(hits.len(), 2, "{hits:?}");
    let expected = [(1.25, 0.25, 0.1), (1.75, 0.75, 0.1)];
    for ((t, u, v), (et, eu, ev)) in hits.iter().zip(expected) {
        assert!(
            (t - et).abs() < 1e-12 && (u - eu).abs() < 1e-12 && (v - ev).abs() < 1e-12,
            "{hits:?}"
        );
    }
}

#[test]
fn intersect_ray_through_an_edge_returns_one_root_clamped_into_the_domain() {
    let lembos = builtin_lembos("sphere24").unwrap();
    let l = &lembos[8];
    let eye = DVec3::new(0.0, 0.0, 5.0);
    for (u0, v0) in [(0.0, 0.4), (0.6, 0.4), (0.0, 0.0)] {
        let target = l.position_at(u0, v0);
        let dir = (target - eye).normalize();
        let hits: Vec<_> = intersect_ray(l, eye, dir)
            .into_iter()
            .filter(|h| (h.1 - u0).abs() + (h.2 - v0).abs() < 1e-6)
            .collect();
        assert_eq!(hits.len(), 1, "({u0}, {v0}): {hits:?}");
        let (_, u, v) = hits[0];
        assert!(
            u >= 0.0 && v >= 0.0 && u + v <= 1.0,
            "({u0}, {v0}): {hits:?}"
        );
    }
    // The trough is subdivided (its Jacobian is singular at u = 1/2), and these hits lie
    // on edges shared by sub-triangles as well as on the domain's edges v = 0 and
    // u + v = 1: each must come out once.
    let trough = trough();
    for (y, expected) in [
        (0.0, [(0.25, 0.0), (0.75, 0.0)]),
        (0.25, [(0.25, 0.25), (0.75, 0.25)]),
    ] {
        let hits = intersect_ray(&trough, DVec3::new(-1.0, y, 0.25), DVec3::X);
        assert_eq!(hits.len(), 2, "y = {y}: {hits:?}");
        for ((_, u, v), (eu, ev)) in hits.iter().zip(expected) {
            assert!(
                (u - eu).abs() < 1e-12 && (v - ev).abs() < 1e-12,
                "y = {y}: {hits:?}"
            );
            assert!(*u >= 0.0 && *v >= 0.0 && u + v <= 1.0, "y = {y}: {hits:?}");
        }
    }
}

#[test]
fn intersect_ray_terminates_on_a_flat_lembo_seen_edge_on() {
    // The ray lies in the lembo's plane: a continuum of roots, which the node budget
    // cuts short. Whatever comes back must lie on the ray.
    let l = flat_lembo();
    let (origin, dir) = (DVec3::new(0.0, 0.5, 0.0), DVec3::X);
    let start = std::time::Instant::now();
    let hits = intersect_ray(&l, origin, dir);
    assert!(start.elapsed().as_secs_f64() < 0.5);
    for (t, u, v) in hits {
        assert!((l.position_at(u, v) - (origin + t * dir)).length() < 1e-9);
    }
}

#[test]
fn render_reference_from_inside_a_closed_surface_covers_every_pixel() {
    // The control nets around the eye have points behind it (w <= 0): those lembos are
    // tested at every sample instead of being culled by a screen box.
    let camera = Camera {
        eye: [0.1, 0.0, 0.2],
        target: [1.0, 0.3, -1.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Perspective {
            fovy_deg: 100.0,
            near: 0.01,
            far: 10.0,
        },
    };
    let view = View::new(
        &camera,
        Viewport {
            width: 24,
            height: 16,
        },
    );
    let image = render_sphere(&view, 1);
    assert!(image.hits.iter().all(|h| h.is_some()));
}

fn sphere_view(size: u32) -> View {
    let camera = Camera {
        eye: [0.0, 0.0, 4.0],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Perspective {
            fovy_deg: 45.0,
            near: 1.0,
            far: 10.0,
        },
    };
    View::new(
        &camera,
        Viewport {
            width: size,
            height: size,
        },
    )
}

fn render_sphere(view: &View, supersample: u32) -> ReferenceImage {
    let lembos = builtin_lembos("sphere24").unwrap();
    let with_colors: Vec<(&Lembo, [f64; 3])> =
        lembos.iter().map(|l| (l, [0.8, 0.6, 0.4])).collect();
    render_reference(&ReferenceInput {
        lembos: &with_colors,
        view,
        light: &Light::default(),
        background: [0.0, 0.0, 0.1],
        supersample,
        tile: DEFAULT_TILE,
    })
}

/// Pixel centres inside the projection of a dense tessellation (n x n per lembo) of
/// the lembos: the silhouette computed independently of the ray solver.
fn tessellated_coverage(lembos: &[Lembo], view: &View, n: u32) -> Vec<bool> {
    let (w, h) = (view.viewport.width as usize, view.viewport.height as usize);
    let mut covered = vec![false; w * h];
    let step = 1.0 / n as f64;
    for l in lembos {
        let at = |a: u32, b: u32| {
            let p = view.project(l.position_at(a as f64 * step, b as f64 * step));
            DVec2::new(p.x, p.y)
        };
        for a in 0..n {
            for b in 0..n - a {
                let mut tris = vec![[at(a, b), at(a + 1, b), at(a, b + 1)]];
                if a + b + 1 < n {
                    tris.push([at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)]);
                }
                for [p, q, r] in tris {
                    let lo = p.min(q).min(r);
                    let hi = p.max(q).max(r);
                    for j in (lo.y - 0.5).ceil().max(0.0) as usize
                        ..=((hi.y - 0.5).floor() as usize).min(h - 1)
                    {
                        for i in (lo.x - 0.5).ceil().max(0.0) as usize
                            ..=((hi.x - 0.5).floor() as usize).min(w - 1)
                        {
                            let c = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                            let e = [
                                (q - p).perp_dot(c - p),
                                (r - q).perp_dot(c - q),
                                (p - r).perp_dot(c - r),
                            ];
                            if e.iter().all(|&x| x >= 0.0) || e.iter().all(|&x| x <= 0.0) {
                                covered[j * w + i] = true;
                            }
                        }
                    }
                }
            }
        }
    }
    covered
}

#[test]
fn render_reference_sphere24_covers_a_disc_of_the_projected_area() {
    let view = sphere_view(64);
    let image = render_sphere(&view, 1);
    let covered = image.hits.iter().filter(|h| h.is_some()).count();
    // A unit sphere 4 units away subtends asin(1/4); sphere24's lembos stay within
    // 0.85..1.05 of the unit sphere, and its silhouette is a slightly smaller disc.
    let r = (0.25f64.asin().tan() / 22.5f64.to_radians().tan()) * 32.0;
    let area = std::f64::consts::PI * r * r;
    assert!(
        (covered as f64 / area - 1.0).abs() < 0.1,
        "covered {covered}, pi r^2 = {area}"
    );
    for j in 0..64 {
        for i in 0..64 {
            let d = ((i as f64 + 0.5 - 32.0).powi(2) + (j as f64 + 0.5 - 32.0).powi(2)).sqrt();
            let hit = image.hits[(j * 64 + i) as usize];
            assert!(d > 0.85 * r - 1.0 || hit.is_some(), "hole at ({i}, {j})");
            assert!(
                d < 1.05 * r + 1.0 || hit.is_none(),
                "stray hit at ({i}, {j})"
            );
            if let Some(h) = hit {
                assert!((h.normal.length() - 1.0).abs() < 1e-12 && (0.0..=1.0).contains(&h.depth));
            }
        }
    }
    // The silhouette of the lembos themselves, from a fine tessellation: only pixel
    // centres within the tessellation's chord error of the outline may differ.
    let lembos = builtin_lembos("sphere24").unwrap();
    let tessellated = tessellated_coverage(&lembos, &view, 64);
    let expected = tessellated.iter().filter(|&&c| c).count();
    let differ = tessellated
        .iter()
        .zip(&image.hits)
        .filter(|(t, h)| **t != h.is_some())
        .count();
    assert!(
        differ <= 2,
        "{differ} pixels differ; covered {covered}, tessellation {expected}"
    );
    let background = [0, 0, to_u8(0.1)];
    assert_eq!(image.color[0], background);
    assert_ne!(image.color[32 * 64 + 32], background);
}

#[test]
fn tracer_answers_at_pixel_centres_as_the_image_and_between_them_as_the_image_would() {
    let view = sphere_view(48);
    let image = render_sphere(&view, 1);
    let lembos = builtin_lembos("sphere24").unwrap();
    let tracer = Tracer::of(lembos.iter(), &view);
    let mut scratch = TraceScratch::default();
    for j in 0..48 {
        for i in 0..48 {
            let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
            let want = image.hits[(j * 48 + i) as usize];
            assert_eq!(tracer.hit(x, y, &mut scratch), want, "({i}, {j})");
            assert_eq!(
                tracer.covers(x, y, &mut scratch),
                want.is_some(),
                "({i}, {j})"
            );
        }
    }
    // Between centres, coverage is that of a reference sampled there: a 3x3 supersampled
    // image's sub-samples.
    let three = render_sphere(&view, 3);
    let coverage = three.coverage.unwrap();
    for j in 0..48u32 {
        for i in 0..48u32 {
            let n = (0..3)
                .flat_map(|b| (0..3).map(move |a| (a, b)))
                .filter(|&(a, b)| {
                    let x = i as f64 + (a as f64 + 0.5) / 3.0;
                    let y = j as f64 + (b as f64 + 0.5) / 3.0;
                    tracer.covers(x, y, &mut scratch)
                })
                .count();
            assert_eq!(
                n as f32 / 9.0,
                coverage[(j * 48 + i) as usize],
                "({i}, {j})"
            );
        }
    }
}

#[test]
fn render_reference_is_deterministic_across_runs_and_thread_counts() {
    let view = sphere_view(64);
    let a = render_sphere(&view, 1);
    let b = render_sphere(&view, 1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let c = pool.install(|| render_sphere(&view, 1));
    assert_eq!(a, b);
    assert_eq!(a, c);
}

#[test]
fn render_reference_supersampling_gives_fractional_coverage_on_the_silhouette() {
    let view = sphere_view(32);
    let one = render_sphere(&view, 1);
    let three = render_sphere(&view, 3);
    // Odd s: the middle sub-sample is the centre sample.
    assert_eq!(one.hits, three.hits);
    assert_eq!(one.color, three.color);
    let coverage = three.coverage.unwrap();
    assert_eq!(coverage[16 * 32 + 16], 1.0);
    assert_eq!(coverage[0], 0.0);
    assert!(coverage.iter().any(|&c| c > 0.0 && c < 1.0));
    assert!(three.color_supersampled.is_some());
}

/// Any tile side gives the same image bit for bit, on a scene dense enough that rows of
/// tiles split into several spans (a span's tiles list at most 4 096 lembos), and the
/// tracer answers between pixel centres as at the default tile.
#[test]
fn render_reference_is_the_same_at_any_tile_side() {
    let lembos = crate::scene::Scene::from_json(
        r#"{"name": "t", "viewport": {"width": 96, "height": 64},
            "camera": {"eye": [0, 5.5, 8.5], "target": [0, 0, -0.5], "up": [0, 1, 0],
                       "projection": {"kind": "perspective", "fovy_deg": 45, "near": 0.1, "far": 100}},
            "objects": [{"builtin": "terrain96"}]}"#,
        "tests.rs",
        std::path::Path::new("."),
    )
    .unwrap();
    let held: Vec<Lembo> = lembos.lembos().map(|(l, _)| l).collect();
    let with_colors: Vec<(&Lembo, [f64; 3])> = held.iter().map(|l| (l, [0.5; 3])).collect();
    let view = View::new(&lembos.camera, lembos.viewport);
    let render = |tile: u32| {
        render_reference(&ReferenceInput {
            lembos: &with_colors,
            view: &view,
            light: &Light::default(),
            background: [0.0; 3],
            supersample: 2,
            tile,
        })
    };
    let tracer = Tracer::new(&with_colors, &view, 4);
    let default = Tracer::new(&with_colors, &view, DEFAULT_TILE);
    let rows = default.spans().last().unwrap().row as usize + 1;
    assert!(
        default.spans().len() > rows,
        "no row of tiles split into spans"
    );
    let base = render(DEFAULT_TILE);
    assert!(base.hits.iter().filter(|h| h.is_some()).count() > 1000);
    for tile in [4, 5, 64, 1024] {
        assert_eq!(render(tile), base, "tile {tile}");
    }
    let mut scratch = TraceScratch::default();
    for k in 0..400 {
        let (x, y) = ((k * 37 % 960) as f64 / 10.0, (k * 53 % 640) as f64 / 10.0);
        assert_eq!(
            tracer.hit(x, y, &mut scratch),
            default.hit(x, y, &mut scratch),
            "({x}, {y})"
        );
        assert_eq!(
            tracer.covers(x, y, &mut scratch),
            default.covers(x, y, &mut scratch)
        );
    }
}

/// A reference keeps the tiles it traced its hits in, and a tracer of the same lembos and
/// view takes them as they are (no second binning) and answers as one binned anew; for
/// another view, or other lembos, it bins anew at the same tile side.
#[test]
fn a_reference_lends_its_tiles_to_a_tracer_of_the_same_lembos_and_view() {
    use crate::reference::surface::fixtures::{flat, view};
    let view = view();
    let square = [
        flat([[-40.0, -40.0], [40.0, -40.0], [40.0, 40.0]], 0.0, DVec3::Z),
        flat([[-40.0, -40.0], [40.0, 40.0], [-40.0, 40.0]], 1.0, DVec3::Z),
    ];
    let lembos: Vec<(&Lembo, [f64; 3])> = square.iter().map(|l| (l, [0.5; 3])).collect();
    let render = render_reference(&ReferenceInput {
        lembos: &lembos,
        view: &view,
        light: &Light::default(),
        background: [0.0; 3],
        supersample: 1,
        tile: 5,
    });
    let bins = render
        .bins
        .clone()
        .expect("a traced reference keeps its tiles");
    assert_eq!(bins.tile(), 5);
    let lent = Tracer::with_bins(&lembos, &view, bins.clone());
    assert!(
        std::sync::Arc::ptr_eq(&lent.bins(), &bins),
        "not binned again"
    );
    let anew = Tracer::new(&lembos, &view, DEFAULT_TILE);
    let mut scratch = TraceScratch::default();
    for k in 0..400 {
        let (x, y) = ((k * 37 % 1280) as f64 / 10.0, (k * 53 % 1280) as f64 / 10.0);
        assert_eq!(lent.hit(x, y, &mut scratch), anew.hit(x, y, &mut scratch));
    }
    let moved = view.translated([0.25, 0.0]);
    let other_view = Tracer::with_bins(&lembos, &moved, bins.clone());
    assert!(!std::sync::Arc::ptr_eq(&other_view.bins(), &bins));
    assert_eq!(other_view.bins().tile(), 5);
    let fewer = lembos[..1].to_vec();
    let other_lembos = Tracer::with_bins(&fewer, &view, bins.clone());
    assert!(!std::sync::Arc::ptr_eq(&other_lembos.bins(), &bins));
}
