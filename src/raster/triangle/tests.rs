//! Tests of the triangle path: setup, snapping, coverage, fragments and the sinks; the
//! clipping at the guard band and the depth planes is in `clip`.

mod clip;

use super::*;
use crate::camera::{Camera, Culling, Projection, Samples, Viewport, Winding};
use crate::datapath::Datapath;
use glam::{DVec3, DVec4};

const VP: Viewport = Viewport {
    width: 64,
    height: 48,
};

fn flat(z: f64) -> Vertex<f64> {
    Vertex {
        z,
        inv_w: 1.0,
        normal_w: [0.0, 0.0, 1.0],
        position_w: [0.0; 3],
    }
}

/// A triangle from sub-pixel vertex positions.
fn tri(id: u32, p: [(i64, i64); 3]) -> Option<ScreenTriangle<f64>> {
    ScreenTriangle::assemble(
        id,
        p.map(|p| p.0),
        p.map(|p| p.1),
        [flat(0.5); 3],
        [1.0; 3],
        VP,
        Samples::ONE,
        Culling::Off,
    )
    .ok()
}

/// A triangle from sub-pixel vertex positions in the datapath `R`, on `viewport`.
fn tri_in<R: Real>(p: [(i64, i64); 3], viewport: Viewport) -> ScreenTriangle<R> {
    let v = Vertex {
        z: R::of(0.25),
        inv_w: R::one(),
        normal_w: [R::zero(), R::zero(), R::one()],
        position_w: [R::zero(); 3],
    };
    let mut v = [v; 3];
    v[1].z = R::of(0.5);
    v[2].z = R::of(0.875);
    ScreenTriangle::assemble(
        7,
        p.map(|p| p.0),
        p.map(|p| p.1),
        v,
        [R::one(); 3],
        viewport,
        Samples::ONE,
        Culling::Off,
    )
    .expect("a triangle in view")
}

/// Sets up a triangle inside the guard band: its one piece, or why it was culled.
fn setup_one<R: Real>(
    id: u32,
    p: &[DVec3; 3],
    n: &[DVec3; 3],
    view: &View,
) -> Result<ScreenTriangle<R>, TriangleCull> {
    let mut out = Vec::new();
    let o = setup::<R>(id, p, n, [1.0; 3], view, &mut out);
    assert_eq!(o.fan, 0, "not clipped");
    match o.cull {
        Some(cull) => {
            assert!(out.is_empty());
            Err(cull)
        }
        None => {
            assert_eq!(out.len(), 1);
            Ok(out.remove(0))
        }
    }
}

/// The closed-form row span (plain datapaths) finds the columns the pixel-by-pixel
/// walk (counting datapaths) finds, on random triangles large and small, slivers, and
/// triangles reaching past the viewport.
#[test]
fn row_span_in_closed_form_is_the_pixel_walk() {
    let mut rng = crate::testkit::SplitMix64::new(3);
    let mut tested = 0;
    for n in 0..4000 {
        let reach = [300, 4_000, 40_000][n % 3];
        let p = [0; 3].map(|_| {
            (
                rng.range_i64(-reach, VP.width as i64 * SUBPIXEL + reach),
                rng.range_i64(-reach, VP.height as i64 * SUBPIXEL + reach),
            )
        });
        let Some(t) = tri(n as u32, p).or_else(|| tri(n as u32, [p[0], p[2], p[1]])) else {
            continue;
        };
        tested += 1;
        for j in 0..VP.height + 2 {
            let walked = t.row_span_by_pixels(j);
            let closed = t.row_span(j);
            let empty = |r: (u32, u32)| r.0 >= r.1;
            assert!(
                closed == walked || (empty(closed) && empty(walked)),
                "{p:?} row {j}: {closed:?} against {walked:?}"
            );
            if !empty(walked) {
                assert_eq!(closed, walked, "{p:?} row {j}");
            }
        }
    }
    assert!(tested > 3000, "{tested} triangles set up");
}

/// The hierarchical walk a hardware rasterizer would do finds the model's covered quads and
/// fragments exactly, on random triangles large and small, slivers and triangles reaching
/// past the viewport; it tests no more quads than the bounding box holds, and a rejected
/// tile holds no covered pixel (rejection is exact at the corners, so it only drops tiles
/// that are wholly outside one edge).
#[test]
fn the_hardware_walk_finds_the_models_quads_and_fragments() {
    let mut rng = crate::testkit::SplitMix64::new(5);
    let (mut tested, mut rejected_some) = (0, false);
    for n in 0..3000 {
        let reach = [300, 4_000, 40_000][n % 3];
        let p = [0; 3].map(|_| {
            (
                rng.range_i64(-reach, VP.width as i64 * SUBPIXEL + reach),
                rng.range_i64(-reach, VP.height as i64 * SUBPIXEL + reach),
            )
        });
        let Some(t) = tri(n as u32, p).or_else(|| tri(n as u32, [p[0], p[2], p[1]])) else {
            continue;
        };
        tested += 1;
        let mut counts = Counts::default();
        struct Nothing;
        impl<R: Real> TriangleSink<R> for Nothing {
            fn fragment(&mut self, _: &ScreenTriangle<R>, _: u32, _: u32, _: &TriangleFragment<R>) {
            }
            fn row(&mut self, _: &ScreenTriangle<R>, _: u32, _: u32, _: u32) {}
        }
        rasterize(&t, &mut Nothing, &mut counts);
        let w = t.walk();
        assert_eq!(w.quads_covered, counts.quads, "{p:?}");
        assert_eq!(w.fragments, counts.fragments, "{p:?}");
        let [i0, i1, j0, j1] = t.bbox;
        let box_quads = ((i1 - 1) / 2 - i0 / 2 + 1) as u64 * ((j1 - 1) / 2 - j0 / 2 + 1) as u64;
        assert!(w.quads_tested <= box_quads, "{p:?}");
        assert!(w.quads_covered <= w.quads_tested && w.tiles > 0);
        rejected_some |= w.quads_tested < box_quads;
    }
    assert!(tested > 2000 && rejected_some, "{tested} triangles set up");
}

/// On the sample grids of 2, 4 and 8 samples a pixel, a triangle covers exactly the samples
/// whose Direct3D position (read from the pattern's table, each row's sample found by its
/// vertical offset) is inside it by the fill rule, wherever they are in the viewport (the
/// bounding box holds them all); the rows in closed form, the pixel walk and the hardware
/// walk find the same samples.
#[test]
fn on_a_sample_grid_a_triangle_covers_the_samples_at_direct3ds_positions() {
    let mut rng = crate::testkit::SplitMix64::new(9);
    let mut tested = 0;
    for n in 0..600 {
        let samples = Samples::new([2, 4, 8][n % 3]).unwrap();
        let s = samples.get() as i64;
        let grid = Viewport {
            width: 24,
            height: 24 * s as u32,
        };
        let reach = [200, 2_000][n % 2];
        let p: [(i64, i64); 3] = [0; 3].map(|_| {
            (
                rng.range_i64(-reach, grid.width as i64 * SUBPIXEL + reach),
                rng.range_i64(-reach, grid.height as i64 * SUBPIXEL + reach),
            )
        });
        let assemble = |p: [(i64, i64); 3]| {
            ScreenTriangle::<f64>::assemble(
                n as u32,
                p.map(|p| p.0),
                p.map(|p| p.1),
                [flat(0.5); 3],
                [1.0; 3],
                grid,
                samples,
                Culling::Off,
            )
            .ok()
        };
        let t = assemble(p).or_else(|| assemble([p[0], p[2], p[1]]));
        // The samples inside by the fill rule, from the pattern's table.
        let inside = |i: i64, r: i64| {
            let dy = ((2 * (r % s) + 1 - s) * 8 / s) as i8;
            let dx = samples.positions().iter().find(|q| q.1 == dy).unwrap().0 as i64;
            let (x, y) = (
                i * SUBPIXEL + SUBPIXEL / 2 + 16 * dx,
                r * SUBPIXEL + SUBPIXEL / 2,
            );
            t.as_ref()
                .is_some_and(|t| t.edges.iter().all(|e| e.at(x, y) >= e.min))
        };
        let mut want = 0u64;
        for r in 0..grid.height as i64 {
            for i in 0..grid.width as i64 {
                if inside(i, r) {
                    want += 1;
                    let [i0, i1, j0, j1] = t.as_ref().expect("a covering triangle").bbox;
                    assert!((i0..i1).contains(&(i as u32)) && (j0..j1).contains(&(r as u32)));
                }
            }
        }
        let Some(t) = t.as_ref() else { continue };
        tested += 1;
        let mut got = 0u64;
        for r in 0..grid.height {
            let (a, b) = t.row_span(r);
            let (c, d) = t.row_span_by_pixels(r);
            assert_eq!(b.saturating_sub(a), d.saturating_sub(c), "{p:?} row {r}");
            for i in a..b {
                assert!(inside(i as i64, r as i64), "{p:?} ({i}, {r})");
                got += 1;
            }
        }
        assert_eq!(got, want, "{p:?}");
        assert_eq!(t.walk().fragments, want, "{p:?}");
    }
    assert!(tested > 300, "{tested} triangles set up");
}

/// A multisampled triangle is shaded at the pixel centre, whichever sample row asks: its
/// weights there where the centre is inside, clamped onto the triangle where it is not.
#[test]
fn a_multisampled_triangle_is_shaded_at_the_pixel_centre_clamped_to_it() {
    let four = Samples::new(4).unwrap();
    let grid = Viewport {
        width: 16,
        height: 64,
    };
    // On the 4-sample grid (rows 4 px a pixel): a triangle whose left edge is x = 5 px.
    let p = [
        (5 * SUBPIXEL, 0),
        (5 * SUBPIXEL, 64 * SUBPIXEL),
        (16 * SUBPIXEL, 32 * SUBPIXEL),
    ];
    let t = ScreenTriangle::<f64>::assemble(
        1,
        p.map(|p| p.0),
        p.map(|p| p.1),
        [flat(0.5); 3],
        [1.0; 3],
        grid,
        four,
        Culling::Off,
    )
    .unwrap();
    // Pixel (8, 3): its sample rows 12..16 all give the weights at (8.5, 14) on the grid.
    let (x, y) = (8 * SUBPIXEL + SUBPIXEL / 2, 14 * SUBPIXEL);
    let want = {
        let e = t.edges.map(|e| e.at(x, y) as f64 / t.area2 as f64);
        [e[0], e[1], e[2]]
    };
    for r in 12..16 {
        assert_eq!(t.shading_weights(8, r), want, "row {r}");
    }
    // Column 4's centre (4.5) is outside: clamped to weights in [0, 1] summing to 1, with
    // the weight of the vertex opposite the left edge at 0.
    let l = t.shading_weights(4, 13);
    assert!(l.iter().all(|w| (0.0..=1.0).contains(w)), "{l:?}");
    assert!(
        (l.iter().sum::<f64>() - 1.0).abs() < 1e-12 && l.contains(&0.0),
        "{l:?}"
    );
}

/// Pixel centre (i, j) in sub-pixel units.
fn c(i: i64, j: i64) -> (i64, i64) {
    (i * SUBPIXEL + SUBPIXEL / 2, j * SUBPIXEL + SUBPIXEL / 2)
}

/// How often each pixel is covered by the triangles, through the quad walk.
fn hits<R: Real>(tris: &[ScreenTriangle<R>]) -> Vec<u32> {
    struct Hits(Vec<u32>);
    impl<R: Real> TriangleSink<R> for Hits {
        fn fragment(&mut self, _: &ScreenTriangle<R>, i: u32, j: u32, _: &TriangleFragment<R>) {
            self.0[(j * VP.width + i) as usize] += 1;
        }
    }
    let mut sink = Hits(vec![0; VP.pixels()]);
    let mut counts = Counts::default();
    for t in tris {
        rasterize(t, &mut sink, &mut counts);
    }
    assert_eq!(
        counts.fragments,
        sink.0.iter().map(|&n| n as u64).sum::<u64>()
    );
    sink.0
}

fn covered(h: &[u32], i: i64, j: i64) -> u32 {
    h[(j * VP.width as i64 + i) as usize]
}

#[test]
fn top_left_rule_on_pixel_centres() {
    // A rectangle from centre (2, 2) to centre (10, 6), split along its diagonal: its
    // top and left sides pass exactly through pixel centres and are included, its
    // bottom and right sides too and are excluded.
    for winding in [false, true] {
        let (a, b, cc, d) = (c(2, 2), c(10, 2), c(10, 6), c(2, 6));
        let mut t = vec![tri(0, [a, b, cc]).unwrap(), tri(1, [a, cc, d]).unwrap()];
        if winding {
            t = vec![tri(0, [a, cc, b]).unwrap(), tri(1, [a, d, cc]).unwrap()];
        }
        let h = hits(&t);
        for j in 0..VP.height as i64 {
            for i in 0..VP.width as i64 {
                let want = (2..10).contains(&i) && (2..6).contains(&j);
                assert_eq!(covered(&h, i, j), want as u32, "pixel ({i}, {j})");
            }
        }
    }
}

#[test]
fn triangles_sharing_an_edge_cover_each_pixel_exactly_once() {
    // Shared edges of many slopes through many pixel centres, both windings: the union
    // of the two triangles (a convex quadrilateral) is covered exactly once.
    let mut rng = crate::testkit::SplitMix64::new(12345);
    let mut rnd = |lo: i64, hi: i64| rng.range_i64(lo, hi);
    for case in 0..400 {
        // The shared edge from p to q; on-centre end points half the time.
        let (p, q) = if case % 2 == 0 {
            // Even offsets: the edge's midpoint is a pixel centre too.
            let (i, j) = (rnd(8, 24), rnd(8, 40));
            (c(i, j), c(i + 2 * rnd(8, 16), j + 2 * rnd(-4, 4)))
        } else {
            (
                (rnd(2000, 6000), rnd(2000, 10000)),
                (rnd(10000, 14000), rnd(2000, 10000)),
            )
        };
        // Third vertices on either side of the edge, far enough to keep it convex.
        let (mx, my) = ((p.0 + q.0) / 2, (p.1 + q.1) / 2);
        let (nx, ny) = (-(q.1 - p.1), q.0 - p.0);
        let f = rnd(2, 9) as f64 / 10.0;
        let r = (mx + (nx as f64 * f) as i64, my + (ny as f64 * f) as i64);
        let g = rnd(2, 9) as f64 / 10.0;
        let s = (mx - (nx as f64 * g) as i64, my - (ny as f64 * g) as i64);
        let (Some(t0), Some(t1)) = (
            tri(0, if case % 3 == 0 { [p, q, r] } else { [q, p, r] }),
            tri(1, [p, q, s]),
        ) else {
            continue;
        };
        let h = hits(&[t0.clone(), t1.clone()]);
        let quad = |i: i64, j: i64| {
            let (x, y) = c(i, j);
            let side =
                |a: (i64, i64), b: (i64, i64)| (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0);
            // Strictly inside the quadrilateral p r q s (either orientation).
            let e = [side(p, r), side(r, q), side(q, s), side(s, p)];
            e.iter().all(|&v| v > 0) || e.iter().all(|&v| v < 0)
        };
        let mut on_edge = 0;
        for j in 0..VP.height as i64 {
            for i in 0..VP.width as i64 {
                let n = covered(&h, i, j);
                assert!(n <= 1, "case {case}: pixel ({i}, {j}) covered {n} times");
                if quad(i, j) {
                    assert_eq!(n, 1, "case {case}: pixel ({i}, {j}) missed");
                    let (x, y) = c(i, j);
                    if (q.0 - p.0) * (y - p.1) == (q.1 - p.1) * (x - p.0) {
                        on_edge += 1;
                    }
                }
            }
        }
        if case % 2 == 0 {
            // The edge passes through pixel centres: exactly the case the fill rule
            // decides.
            assert!(on_edge >= 1, "case {case}: no centre on the shared edge");
        }
    }
}

#[test]
fn a_fan_around_a_vertex_covers_each_pixel_exactly_once() {
    // Twelve triangles around a vertex on a pixel centre, outer vertices on a polygon
    // (some on centres, some not): every pixel strictly inside is covered once,
    // the centre pixel included.
    let o = c(30, 24);
    let ring: Vec<(i64, i64)> = (0..12)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 12.0;
            let r = if k % 2 == 0 {
                20.0 * 256.0
            } else {
                17.3 * 256.0
            };
            (
                o.0 + (r * a.cos()).round() as i64,
                o.1 + (r * a.sin()).round() as i64,
            )
        })
        .collect();
    let tris: Vec<_> = (0..12)
        .map(|k| tri(k as u32, [o, ring[k], ring[(k + 1) % 12]]).unwrap())
        .collect();
    let h = hits(&tris);
    assert_eq!(covered(&h, 30, 24), 1);
    for j in 0..VP.height as i64 {
        for i in 0..VP.width as i64 {
            let n = covered(&h, i, j);
            assert!(n <= 1, "pixel ({i}, {j}) covered {n} times");
            let (x, y) = c(i, j);
            let inside = (0..12).all(|k| {
                let (a, b) = (ring[k], ring[(k + 1) % 12]);
                (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0) > 0
            });
            if inside {
                assert_eq!(n, 1, "pixel ({i}, {j}) missed");
            }
        }
    }
}

#[test]
fn quads_counted_are_the_aligned_quads_with_a_covered_pixel_and_rows_bring_each_pixel() {
    let t = tri(
        0,
        [
            c(3, 1),
            (40 * 256 + 17, 9 * 256 + 3),
            (11 * 256 + 200, 30 * 256),
        ],
    )
    .unwrap();
    // Every 2x2 quad at even (qi, qj) with a covered pixel, found pixel by pixel.
    let covered = |i: u32, j: u32| i < VP.width && j < VP.height && t.covers(i, j);
    let quads = (0..VP.height)
        .step_by(2)
        .flat_map(|qj| (0..VP.width).step_by(2).map(move |qi| (qi, qj)))
        .filter(|&(qi, qj)| (0..4).any(|b| covered(qi + (b & 1), qj + (b >> 1))))
        .count() as u64;
    struct Rows(Vec<(u32, u32)>);
    impl<R: Real> TriangleSink<R> for Rows {
        fn fragment(&mut self, _: &ScreenTriangle<R>, _: u32, _: u32, _: &TriangleFragment<R>) {
            unreachable!("rows come whole")
        }
        fn row(&mut self, _: &ScreenTriangle<R>, j: u32, a: u32, b: u32) {
            self.0.extend((a..b).map(|i| (i, j)));
        }
    }
    let (mut sink, mut counts) = (Rows(Vec::new()), Counts::default());
    rasterize(&t, &mut sink, &mut counts);
    assert_eq!(counts.quads, quads);
    let all: Vec<_> = (0..VP.height)
        .flat_map(|j| (0..VP.width).map(move |i| (i, j)))
        .filter(|&(i, j)| covered(i, j))
        .collect();
    assert_eq!(sink.0, all, "each covered pixel once, row by row");
    assert_eq!(counts.fragments, all.len() as u64);
}

#[test]
fn weights_in_lanes_are_the_pixel_by_pixel_weights_bit_for_bit() {
    // Every (step)th row and column from the bounding box's corner, 8 pixels on from each.
    fn check<R: Real>(t: &ScreenTriangle<R>, step: usize) {
        let [i0, i1, j0, j1] = t.bbox;
        for j in (j0..j1).step_by(step) {
            let row = t.row_edges(j);
            for i in (i0..i1).step_by(step) {
                let (l, z) = t.weights_lanes(&row, i);
                for k in 0..WEIGHT_LANES {
                    let (want_l, want_z) = t.weights(i + k as u32, j);
                    let got = [l[0][k], l[1][k], l[2][k]];
                    let bits = |v: [R; 3]| v.map(|x| x.f64().to_bits());
                    assert_eq!(bits(got), bits(want_l), "({}, {j})", i + k as u32);
                    assert_eq!(z[k].f64().to_bits(), want_z.f64().to_bits());
                }
            }
        }
    }
    // A slanted triangle, and one from the guard band's corners over the largest viewport
    // (edge values near 2^49).
    let small = [
        c(3, 1),
        (40 * 256 + 17, 9 * 256 + 3),
        (11 * 256 + 200, 30 * 256),
    ];
    check(&tri_in::<f32>(small, VP), 1);
    check(&tri_in::<f64>(small, VP), 1);
    let far = (GUARD_BAND_PX as i64) * SUBPIXEL;
    let huge = [(-far, -far), (far, -far + 77), (-far + 300, far)];
    let largest = Viewport {
        width: 16384,
        height: 16384,
    };
    check(&tri_in::<f32>(huge, largest), 1001);
    check(&tri_in::<f64>(huge, largest), 1001);
}

#[test]
fn snapping_rounds_to_the_nearest_256th_of_a_pixel() {
    assert_eq!(snap(10.0f64), 2560);
    assert_eq!(snap(10.3f64), 2637); // 2636.8
    assert_eq!(snap(-0.3f64), -77); // -76.8
    assert_eq!(snap(1.0f64 / 512.0 * 0.99), 0);
    assert_eq!(snap(3.0f32 + 1.0 / 256.0), 3 * 256 + 1);
    // A triangle nudged by less than half a sub-pixel step covers the same pixels.
    let view = ortho_view();
    // On the sub-pixel grid, then nudged by less than half a step.
    let p = [
        DVec3::new(3.25, 4.125, 0.0),
        DVec3::new(40.5 + 3.0 / 256.0, 9.0, 0.0),
        DVec3::new(12.25, 30.0 + 255.0 / 256.0, 0.0),
    ];
    let nudge = DVec3::new(0.4 / 256.0, -0.45 / 256.0, 0.0);
    let a = setup_one::<f64>(0, &p, &[DVec3::Z; 3], &view).unwrap();
    let b = setup_one::<f64>(0, &p.map(|q| q + nudge), &[DVec3::Z; 3], &view).unwrap();
    assert_eq!((a.x, a.y), (b.x, b.y));
    assert_eq!((a.x[0], a.y[0]), (3 * 256 + 64, 4 * 256 + 32));
}

/// World x, y = screen x, y (pixels), y down, with an orthographic camera.
fn ortho_view() -> View {
    let (w, h) = (VP.width as f64, VP.height as f64);
    View::new(
        &Camera {
            eye: [w / 2.0, h / 2.0, -10.0],
            target: [w / 2.0, h / 2.0, 0.0],
            up: [0.0, -1.0, 0.0],
            projection: Projection::Orthographic {
                height: h,
                near: 1.0,
                far: 20.0,
            },
        },
        VP,
    )
}

/// Asserts that the fragment of `t` at pixel (i, j) has the depth and position of the
/// view ray's hit with the plane of the world triangle `p`, and the normal blended from
/// `n` by the hit's world barycentrics; returns the hit.
fn assert_fragment_on_plane(
    view: &View,
    t: &ScreenTriangle<f64>,
    i: u32,
    j: u32,
    p: &[DVec3; 3],
    n: &[DVec3; 3],
) -> DVec3 {
    let plane_n = (p[1] - p[0]).cross(p[2] - p[0]);
    let on_plane = |x: f64, y: f64| {
        let (o, d) = view.ray(x, y);
        o + d * (plane_n.dot(p[0] - o) / plane_n.dot(d))
    };
    let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
    let hit = on_plane(x, y);
    // The plane's depth gradient [per pixel] there (from a quarter pixel either side: a
    // pixel centre is half a pixel from a row or column where the plane may meet the
    // horizon).
    let z = |x: f64, y: f64| view.depth_of(on_plane(x, y));
    let gradient = 2.0 * (z(x + 0.25, y) - z(x - 0.25, y)).hypot(z(x, y + 0.25) - z(x, y - 0.25));
    // World barycentrics of the hit.
    let area = plane_n.length_squared();
    let b = [
        (p[1] - hit).cross(p[2] - hit).dot(plane_n) / area,
        (p[2] - hit).cross(p[0] - hit).dot(plane_n) / area,
        (p[0] - hit).cross(p[1] - hit).dot(plane_n) / area,
    ];
    let want_n = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize();
    let f = t.fragment(i, j);
    let got_n = DVec3::from_array(f.normal).normalize();
    let got_p = DVec3::from_array(f.position);
    // Tolerances: snapping moves the vertices by up to 1/512 pixel, about 4e-4 world
    // units at the far vertex, more along the grazing plane; each moved vertex tilts the
    // depth plane by up to the gradient times 1/512 at a pixel inside (a triangle cut
    // by the near plane has depth 0 on the cut: steep).
    assert!(
        (f.z - view.depth_of(hit)).abs() < 1e-5 + gradient / 128.0,
        "depth at ({i}, {j}): {} against {}, gradient {gradient}",
        f.z,
        view.depth_of(hit)
    );
    assert!((got_p - hit).length() < 3e-3, "position at ({i}, {j})");
    assert!((got_n - want_n).length() < 1e-3, "normal at ({i}, {j})");
    hit
}

#[test]
fn perspective_correct_depth_normal_and_position_match_the_plane() {
    // A triangle strongly slanted in depth, seen in perspective, with three different
    // vertex normals. At every covered pixel centre the ray meets the triangle's plane
    // at P: the fragment's depth is P's depth, its position is P, and its normal is the
    // world-space barycentric blend at P. Affine (not perspective-correct) weights miss
    // by far more than the tolerance, so the test can fail.
    let view = perspective_view();
    let p = [
        DVec3::new(-1.0, -0.6, -1.5),
        DVec3::new(2.5, -0.4, -8.0),
        DVec3::new(-0.5, 1.2, -2.0),
    ];
    let n = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    let t = setup_one::<f64>(7, &p, &n, &view).unwrap();
    let (mut checked, mut affine_miss) = (0, 0.0f64);
    for j in 0..VP.height {
        for i in 0..VP.width {
            if !t.covers(i, j) {
                continue;
            }
            let hit = assert_fragment_on_plane(&view, &t, i, j, &p, &n);
            // What affine screen-space weights would give.
            let e = t.edge_values(i, j).map(|v| v as f64 / t.area2 as f64);
            let affine: DVec3 = (0..3)
                .map(|k| DVec3::from_array(t.position_w[k]) / t.inv_w[k] * e[k])
                .sum();
            affine_miss = affine_miss.max((affine - hit).length());
            checked += 1;
        }
    }
    assert!(checked > 200, "{checked}");
    assert!(affine_miss > 0.1, "{affine_miss}");
}

#[test]
fn culls_are_classified() {
    let view = ortho_view();
    let z = DVec3::Z;
    let cull = |p: [DVec3; 3]| setup_one::<f32>(0, &p, &[z; 3], &view).err();
    let (a, b, c) = (
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(9.0, 1.0, 0.0),
        DVec3::new(1.0, 9.0, 0.0),
    );
    assert_eq!(cull([a, b, c]), None);
    let off = DVec3::new(500.0, 0.0, 0.0);
    assert_eq!(
        cull([a + off, b + off, c + off]),
        Some(TriangleCull::Outside)
    );
    assert_eq!(cull([a, b, a]), Some(TriangleCull::Degenerate));
    // A vertex beyond the guard band: clipped, and drawn.
    let mut out = Vec::new();
    let far = DVec3::new(1e6, 3e5, 0.0);
    let o = setup::<f32>(0, &[a, b, far], &[z; 3], [1.0; 3], &view, &mut out);
    assert!(o.fan >= 1 && o.cull.is_none() && !out.is_empty(), "{o:?}");
    // Clipped, but beyond one side of the viewport: trivially rejected.
    let right = DVec3::new(100.0, 0.0, 0.0);
    let o = setup::<f32>(
        0,
        &[a + right, b + right, far],
        &[z; 3],
        [1.0; 3],
        &view,
        &mut out,
    );
    assert_eq!(
        (o.fan, o.cull, out.len()),
        (0, Some(TriangleCull::Outside), 0)
    );
    // Spanning the viewport's x and y ranges, but passing outside the guard band's
    // corner: nothing is left after clipping.
    let corner = [
        DVec3::new(-1e6, 1.1e6, 0.0),
        DVec3::new(1.1e6, -1e6, 0.0),
        DVec3::new(-1e6, 1.1e6 + 10.0, 0.0),
    ];
    let o = setup::<f32>(0, &corner, &[z; 3], [1.0; 3], &view, &mut out);
    assert_eq!(
        (o.fan, o.cull, out.len()),
        (0, Some(TriangleCull::Outside), 0)
    );
    // Between two pixel centres: no sample inside.
    let tiny = [
        DVec3::new(1.6, 1.6, 0.0),
        DVec3::new(1.9, 1.6, 0.0),
        DVec3::new(1.6, 1.9, 0.0),
    ];
    assert_eq!(cull(tiny), Some(TriangleCull::Degenerate));
    // Beyond the far plane (the eye is at z = -10, far = 20).
    let behind = DVec3::new(0.0, 0.0, 30.0);
    assert_eq!(
        cull([a + behind, b + behind, c + behind]),
        Some(TriangleCull::Outside)
    );
}

/// The camera of the perspective tests: eye at the origin looking down -z, 60 degrees.
fn perspective_view() -> View {
    View::new(
        &Camera {
            eye: [0.0, 0.0, 0.0],
            target: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Perspective {
                fovy_deg: 60.0,
                near: 0.1,
                far: 100.0,
            },
        },
        VP,
    )
}

/// Back-face culling by the snapped signed area: a triangle whose corners run clockwise as
/// the eye sees them is a back face when the front is counter-clockwise, and the reverse;
/// a culled triangle is counted, and culling nothing draws both.
#[test]
fn back_faces_are_culled_by_their_signed_area() {
    // The eye looks along +z from z = -10: (b - a) x (c - a) = +z points away from it.
    let view = ortho_view();
    let z = DVec3::Z;
    let (a, b, c) = (
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(9.0, 1.0, 0.0),
        DVec3::new(1.0, 9.0, 0.0),
    );
    let away_from_eye = [a, b, c];
    let towards_eye = [a, c, b];
    for (culling, culled) in [
        (Culling::Off, None),
        (
            Culling::Back {
                front: Winding::Ccw,
            },
            Some(away_from_eye),
        ),
        (Culling::Back { front: Winding::Cw }, Some(towards_eye)),
    ] {
        let view = view.with_culling(culling);
        for p in [away_from_eye, towards_eye] {
            let got = setup_one::<f32>(0, &p, &[z; 3], &view).err();
            let want = (culled == Some(p)).then_some(TriangleCull::BackFace);
            assert_eq!(got, want, "{culling:?} {p:?}");
        }
    }
    // Counted as back-facing, beside the other culls.
    let view = view.with_culling(Culling::Back {
        front: Winding::Ccw,
    });
    let mut counts = Counts::default();
    let mut out = Vec::new();
    setup::<f32>(0, &away_from_eye, &[z; 3], [1.0; 3], &view, &mut out).count(&mut counts);
    assert!(out.is_empty());
    assert_eq!((counts.triangles, counts.triangles_culled_backface), (1, 1));
    // A clipped triangle's fan faces one way: all its pieces are culled, the triangle
    // counted once as back-facing.
    let far = DVec3::new(3e5, 1e6, 0.0);
    let o = setup::<f32>(0, &[a, b, far], &[z; 3], [1.0; 3], &view, &mut out);
    assert!(o.fan >= 1 && out.is_empty(), "{o:?}");
    assert_eq!(o.cull, Some(TriangleCull::BackFace));
    let o = setup::<f32>(0, &[a, far, b], &[z; 3], [1.0; 3], &view, &mut out);
    assert!(o.fan >= 1 && o.cull.is_none() && !out.is_empty(), "{o:?}");
}

/// A tessellation's bytes are its indexed mesh's at the architecture's default sizes: every
/// distinct vertex once, and a triangle's indices (moved from the Tessellator's tests, which
/// may not name the triangle source: it sits above them).
#[test]
fn a_tessellations_bytes_are_its_indexed_meshs() {
    use crate::lembo::tessellate::{Tessellation, INDEX_BYTES_PER_TRIANGLE, VERTEX_BYTES};
    let sizes = crate::config::FetchConfig::default();
    for (name, levels) in [("sphere24", 1..=4), ("bunny", 1..=2), ("bunny", 5..=5)] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("traces")
            .join(format!("{name}.json"));
        let scene = crate::scene::Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        for n in levels {
            let tess = Tessellation::new(scene.lembo_sets(), n);
            let count = tess.vertex_count();
            assert_eq!(
                TriangleSource::bytes(&tess, &sizes),
                count * VERTEX_BYTES + tess.len() * INDEX_BYTES_PER_TRIANGLE,
                "{name} at n = {n}"
            );
        }
    }
}
