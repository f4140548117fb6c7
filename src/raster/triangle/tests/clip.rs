//! Tests of the triangle path's clipping: against the guard band and the near and far
//! planes, each checked against an exact rasterizer or the rays through pixel centres.

use super::*;
use crate::camera::{Culling, Samples};
use crate::testkit::SplitMix64;

/// Per pixel: whether an unbounded-precision rasterizer covers it for the triangle with
/// world vertices `p` (projected, snapped to 1/256 pixel in f64 however far, edge
/// functions in i128, the top-left rule), and the pixel centre's distance \[pixels\] to
/// the nearest of the snapped triangle's edge lines.
fn exact_coverage(p: &[DVec3; 3], view: &View) -> Vec<(bool, f64)> {
    let s = p.map(|q| view.project(q));
    let mut x = s.map(|s| (s.x * SUBPIXEL as f64).round() as i128);
    let mut y = s.map(|s| (s.y * SUBPIXEL as f64).round() as i128);
    if (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]) < 0 {
        x.swap(1, 2);
        y.swap(1, 2);
    }
    let mut cover = Vec::new();
    for j in 0..VP.height as i128 {
        for i in 0..VP.width as i128 {
            let (px, py) = (i * 256 + 128, j * 256 + 128);
            let (mut inside, mut dist) = (true, f64::INFINITY);
            for k in 0..3 {
                let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                let (dx, dy) = (x[b] - x[a], y[b] - y[a]);
                let e = dx * (py - y[a]) - dy * (px - x[a]);
                let top_left = dy < 0 || (dy == 0 && dx > 0);
                inside &= e > 0 || (e == 0 && top_left);
                let length = ((dx * dx + dy * dy) as f64).sqrt();
                dist = dist.min(e.abs() as f64 / length / SUBPIXEL as f64);
            }
            cover.push((inside, dist));
        }
    }
    cover
}

/// Sets up triangle `p` (unit normals +z) and checks its pieces against
/// [`exact_coverage`]: clipped and fanned exactly when a vertex is beyond the guard band
/// (|x| or |y| over [`GUARD_BAND_PX`]), no pixel twice, and a pixel covered exactly when
/// the exact rasterizer covers it, except a centre within 1/128 pixel of an edge (a
/// clipped vertex, snapped on its clip line, is up to 1/512 pixel off the exact edge; an
/// f32 datapath adds up to 1/2048 before snapping). Returns the pieces and the mismatches.
fn clip_against_exact<R: Real>(p: &[DVec3; 3], view: &View) -> (Vec<ScreenTriangle<R>>, u32) {
    let mut pieces = Vec::new();
    let o = setup::<R>(3, p, &[DVec3::Z; 3], [1.0; 3], view, &mut pieces);
    let exact = exact_coverage(p, view);
    let beyond = p
        .map(|q| view.project(q))
        .iter()
        .any(|s| s.x.abs() > GUARD_BAND_PX || s.y.abs() > GUARD_BAND_PX);
    if exact.iter().any(|e| e.0) {
        assert!(o.cull.is_none() && (o.fan >= 1) == beyond, "{p:?}: {o:?}");
    }
    assert!(o.fan <= 5 && pieces.len() <= o.fan.max(1), "{o:?}");
    assert!(pieces.iter().all(|t| t.id == 3));
    let h = hits(&pieces);
    let mut mismatches = 0;
    for (k, (&n, &(want, dist))) in h.iter().zip(&exact).enumerate() {
        let (i, j) = (k as u32 % VP.width, k as u32 / VP.width);
        assert!(n <= 1, "{p:?}: pixel ({i}, {j}) covered {n} times");
        if (n == 1) != want {
            assert!(dist < 1.0 / 128.0, "{p:?}: pixel ({i}, {j}), {dist} px off");
            mismatches += 1;
        }
    }
    (pieces, mismatches)
}

#[test]
fn a_triangle_a_million_pixels_across_covers_the_viewport_once() {
    let view = ortho_view();
    let p = [
        DVec3::new(-1e6, -1e6, 0.0),
        DVec3::new(1e6 + 0.3, -2e5, 0.0),
        DVec3::new(-3e5, 1e6, 0.0),
    ];
    let (pieces, mismatches) = clip_against_exact::<f64>(&p, &view);
    assert_eq!(mismatches, 0);
    assert!(hits(&pieces).iter().all(|&n| n == 1));
    // The snapped pieces stay inside the 16.8 range.
    let limit = (CLIP_PX * SUBPIXEL as f64) as i64;
    assert!(pieces
        .iter()
        .all(|t| t.x.iter().chain(&t.y).all(|c| c.abs() <= limit)));
    let (pieces, mismatches) = clip_against_exact::<f32>(&p, &view);
    assert_eq!(mismatches, 0);
    assert!(hits(&pieces).iter().all(|&n| n == 1));
}

#[test]
fn clipped_triangles_cover_the_exact_pixels_of_the_unclipped_ones() {
    // Random triangles with one, two or three vertices 4·10^4 to 10^7 pixels away in the
    // larger of x and y, so beyond the guard band's square (±32 767) at every angle, edges
    // through the viewport at every angle. Both datapaths.
    let view = ortho_view();
    let mut rng = SplitMix64::new(987654321);
    let mut rnd = || rng.unit();
    let (mut drawn, mut mismatches, mut pixels) = (0, 0, 0);
    for case in 0..300 {
        let p: [DVec3; 3] = std::array::from_fn(|k| {
            if k < 1 + case % 3 {
                let (a, r) = (rnd() * std::f64::consts::TAU, 10f64.powf(4.6 + 2.4 * rnd()));
                let (c, s) = (a.cos(), a.sin());
                let r = r / c.abs().max(s.abs());
                DVec3::new(32.0 + r * c, 24.0 + r * s, 0.0)
            } else {
                DVec3::new(-20.0 + 104.0 * rnd(), -20.0 + 88.0 * rnd(), 0.0)
            }
        });
        let (p64, m64) = clip_against_exact::<f64>(&p, &view);
        let (p32, m32) = clip_against_exact::<f32>(&p, &view);
        drawn += !p64.is_empty() as u32;
        mismatches += m64 + m32;
        pixels += hits(&p64).iter().sum::<u32>();
        assert_eq!(p64.len(), p32.len(), "{p:?}");
    }
    assert!(drawn > 150, "{drawn}");
    // Only centres a rounding step from an edge can differ.
    assert!(mismatches * 10_000 < pixels, "{mismatches} of {pixels}");
}

#[test]
fn a_vertex_far_away_on_a_diagonal_but_inside_the_guard_band_is_not_clipped() {
    // 44 755 pixels from the viewport's centre, but |x| and |y| are under 32 767: inside
    // the guard band's square (whose corners are 46 340 pixels out), so the triangle is
    // set up whole, unclipped, and covers the exact pixels. Moved 2 % further out, x passes
    // the guard band and the triangle is clipped, still to the exact pixels.
    let view = ortho_view();
    let far = DVec3::new(32441.26099477036, -30840.890562303503, 0.0);
    let near = [
        DVec3::new(72.67126469480847, 2.765186318569242, 0.0),
        DVec3::new(28.598403838048384, 67.43338686335176, 0.0),
    ];
    for (far, clipped) in [(far, false), (far * 1.02, true)] {
        let p = [far, near[0], near[1]];
        let mut pieces = Vec::<ScreenTriangle<f64>>::new();
        let o = setup(3, &p, &[DVec3::Z; 3], [1.0; 3], &view, &mut pieces);
        assert_eq!((o.fan >= 1, o.guard_band, o.cull), (clipped, clipped, None));
        assert_eq!(pieces.len(), if clipped { o.fan } else { 1 });
        let (p64, m64) = clip_against_exact::<f64>(&p, &view);
        let (p32, m32) = clip_against_exact::<f32>(&p, &view);
        assert_eq!((m64, m32), (0, 0), "{p:?}");
        // It reaches the view (a wedge about 16 pixels wide across it: 255 pixels unclipped).
        let covered = hits(&p64).iter().sum::<u32>();
        assert!(covered > 100, "{p:?}: {covered}");
        assert_eq!(p64.len(), p32.len());
    }
}

#[test]
fn two_clipped_triangles_sharing_an_edge_through_pixel_centres_cover_each_pixel_once() {
    // The shared edge runs through the centres (20.5 + 3k, 20.5 + k), and both its ends
    // are about 10^6 pixels away, so both triangles clip it at the same guard-band
    // crossings (computed from the same end).
    let view = ortho_view();
    let k = 333_333.0;
    let p = DVec3::new(20.5 - 3.0 * k, 20.5 - k, 0.0);
    let q = DVec3::new(20.5 + 3.0 * k, 20.5 + k, 0.0);
    let r1 = DVec3::new(-1e6, 1e6, 0.0);
    let r2 = DVec3::new(1e6, -1e6, 0.0);
    for (a, b) in [([p, q, r1], [q, p, r2]), ([q, r1, p], [r2, p, q])] {
        let (mut pa, _) = clip_against_exact::<f64>(&a, &view);
        let (pb, _) = clip_against_exact::<f64>(&b, &view);
        pa.extend(pb);
        let h = hits(&pa);
        for (k, &n) in h.iter().enumerate() {
            assert_eq!(
                n,
                1,
                "pixel ({}, {})",
                k as u32 % VP.width,
                k as u32 / VP.width
            );
        }
    }
}

fn unclipped_bit_for_bit<R: Real>() {
    // One vertex between the clip line and the end of the 16.8 range: inside the guard
    // band, so not clipped (clipping would move it onto x = CLIP_PX and count the
    // triangle as clipped).
    let view = ortho_view();
    let p = [
        DVec3::new(2.3, 3.1, 0.5),
        DVec3::new(CLIP_PX + 0.75, 20.2, -1.0),
        DVec3::new(-GUARD_BAND_PX, 40.9, 2.0),
    ];
    let n = [
        DVec3::Z,
        DVec3::new(0.6, 0.0, 0.8),
        DVec3::new(0.0, -0.8, 0.6),
    ];
    let color = [0.25, 0.5, 1.0];
    // The setup of a triangle before guard-band clipping existed, written out.
    let s = p.map(|q| view.project(q));
    let r3 = |v: DVec3| v.to_array().map(R::of);
    let v = [0, 1, 2].map(|k| Vertex {
        z: R::of(s[k].depth),
        inv_w: R::of(1.0),
        normal_w: r3(n[k]),
        position_w: r3(p[k]),
    });
    let x = s.map(|s| snap(R::of(s.x)));
    let y = s.map(|s| snap(R::of(s.y)));
    let want =
        ScreenTriangle::assemble(5, x, y, v, color.map(R::of), VP, Samples::ONE, Culling::Off)
            .unwrap();
    assert!(want.x.contains(&(CLIP_PX as i64 * SUBPIXEL + 192)));
    let mut out = Vec::new();
    let o = setup::<R>(5, &p, &n, color, &view, &mut out);
    assert_eq!(o, SetupOutcome::default());
    assert_eq!(out, vec![want]);
    let mut counts = Counts::default();
    o.count(&mut counts);
    assert_eq!((counts.triangles, counts.triangles_clipped), (1, 0));
    // Half a pixel further, past the guard band: clipped onto x = CLIP_PX.
    let beyond = [p[0], p[1] + DVec3::X, p[2]];
    let o = setup::<R>(5, &beyond, &n, color, &view, &mut out);
    assert!(o.fan >= 1 && o.cull.is_none(), "{o:?}");
    let xmax = out.iter().flat_map(|t| t.x).max().unwrap();
    assert_eq!(xmax, CLIP_PX as i64 * SUBPIXEL);
    o.count(&mut counts);
    assert_eq!((counts.triangles, counts.triangles_clipped), (2, 1));
}

#[test]
fn a_triangle_inside_the_guard_band_is_set_up_unclipped_bit_for_bit() {
    unclipped_bit_for_bit::<f64>();
    unclipped_bit_for_bit::<f32>();
}

#[test]
fn clipped_pieces_interpolate_perspective_correctly_like_the_whole_triangle() {
    // As perspective_correct_depth_normal_and_position_match_the_plane, with a vertex
    // about 70 000 pixels to the right: every piece's fragment at a pixel is the ray's
    // hit with the whole triangle's plane, and the blend of the whole triangle's
    // normals there.
    let view = perspective_view();
    let p = [
        DVec3::new(-1.0, -0.6, -1.5),
        DVec3::new(5000.0, -0.4, -3.0),
        DVec3::new(-0.5, 1.2, -2.0),
    ];
    let n = [
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    assert!(view.project(p[1]).x > 2.0 * GUARD_BAND_PX);
    let mut pieces = Vec::new();
    let o = setup::<f64>(7, &p, &n, [1.0; 3], &view, &mut pieces);
    assert!(o.fan >= 2 && pieces.len() >= 2, "{o:?}");
    assert!(o.guard_band && !o.depth, "{o:?}");
    let checked = pieces_on_plane(&view, &pieces, &p, &n);
    assert!(checked > 200, "{checked}");
    // A vertex behind the eye: the triangle is clipped at the near plane (and what is
    // left of it at the guard band), and the pieces are still the whole triangle's.
    let behind = [p[0], p[1], DVec3::new(0.0, 0.0, 1.0)];
    let o = setup::<f64>(7, &behind, &n, [1.0; 3], &view, &mut pieces);
    assert!(
        o.fan >= 2 && o.cull.is_none() && o.depth && o.guard_band,
        "{o:?}"
    );
    let checked = pieces_on_plane(&view, &pieces, &behind, &n);
    assert!(checked > 200, "{checked}");
}

/// Asserts that the pieces of the triangle with world vertices `p` and normals `n` cover
/// each pixel at most once and that each fragment lies on the triangle's plane
/// ([`assert_fragment_on_plane`]); returns the fragments checked.
fn pieces_on_plane(
    view: &View,
    pieces: &[ScreenTriangle<f64>],
    p: &[DVec3; 3],
    n: &[DVec3; 3],
) -> u32 {
    let h = hits(pieces);
    let mut checked = 0;
    for t in pieces {
        for j in 0..VP.height {
            for i in 0..VP.width {
                if !t.covers(i, j) {
                    continue;
                }
                assert_eq!(h[(j * VP.width + i) as usize], 1, "({i}, {j})");
                assert_fragment_on_plane(view, t, i, j, p, n);
                checked += 1;
            }
        }
    }
    checked
}

#[test]
fn triangles_sharing_an_edge_clip_it_at_the_same_points() {
    // Edges through the view with both ends far beyond the guard band, each shared by
    // two triangles that walk it in opposite directions: their clipped polygons share
    // exactly the two crossings, bit for bit, so their pieces meet without a crack.
    let view = perspective_view();
    let planes = guard_band_planes(&view);
    let mut rng = SplitMix64::new(4242);
    let mut rnd = || rng.unit();
    let clip_all = |t: [DVec3; 3]| {
        let mut polygon = Polygon::new(&t, &[DVec3::Z; 3]);
        for q in planes {
            polygon = polygon.clip(q).unwrap();
        }
        polygon
    };
    for case in 0..200 {
        let mid = DVec3::new(rnd() - 0.5, rnd() - 0.5, -2.0 - 3.0 * rnd());
        let a = rnd() * std::f64::consts::TAU;
        let dir = DVec3::new(a.cos(), a.sin(), 0.0);
        let far = |r: f64| 10f64.powf(4.0 + 2.0 * r);
        let (p, q) = (mid - dir * far(rnd()), mid + dir * far(rnd()));
        let side = DVec3::new(-dir.y, dir.x, 0.0);
        let (r1, r2) = (mid + side * far(rnd()), mid - side * far(rnd()));
        let (a, b) = (clip_all([p, q, r1]), clip_all([q, p, r2]));
        let shared = a
            .vertices()
            .iter()
            .filter(|u| b.vertices().iter().any(|v| v.p == u.p))
            .count();
        assert_eq!(shared, 2, "case {case}");
    }
}

#[test]
fn a_snapped_polygon_is_made_strictly_convex() {
    // A duplicate, a collinear vertex and a dent go; the square's corners stay.
    let x = [0, 0, 100, 200, 200, 200, 0, 99];
    let y = [0, 0, 1, 0, 100, 200, 200, 100];
    let mut order: [usize; 8] = std::array::from_fn(|k| k);
    let n = make_convex(&x, &y, &mut order, 8);
    assert_eq!(&order[..n], &[1, 3, 5, 6]);
    // Everything on one line: no area.
    let mut order: [usize; 3] = [0, 1, 2];
    assert_eq!(make_convex(&[0, 1, 2], &[0, 1, 2], &mut order, 3), 0);
}

/// Per pixel: fragments received, and the range of their depths.
struct Fragments {
    hits: Vec<u32>,
    z: [f64; 2],
}

impl<R: Real> TriangleSink<R> for Fragments {
    fn fragment(&mut self, _: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        self.hits[(j * VP.width + i) as usize] += 1;
        let z = f.z.f64();
        self.z = [self.z[0].min(z), self.z[1].max(z)];
    }
}

impl Fragments {
    fn new() -> Self {
        Fragments {
            hits: vec![0; VP.pixels()],
            z: [f64::INFINITY, f64::NEG_INFINITY],
        }
    }
}

/// Whether the view ray through screen point (sx, sy) meets the world triangle `p`
/// between the near plane (the ray's origin) and the far plane: exact visible coverage.
fn sees(view: &View, p: &[DVec3; 3], sx: f64, sy: f64) -> bool {
    let (o, d) = view.ray(sx, sy);
    let normal = (p[1] - p[0]).cross(p[2] - p[0]);
    let t = normal.dot(p[0] - o) / normal.dot(d);
    // A ray in the triangle's plane (t not a number) or meeting it before the near plane
    // does not see it.
    if t.is_nan() || t < 0.0 {
        return false;
    }
    let hit = o + d * t;
    (0..3).all(|k| {
        (p[(k + 1) % 3] - hit)
            .cross(p[(k + 2) % 3] - hit)
            .dot(normal)
            >= 0.0
    }) && view.depth_of(hit) <= 1.0
}

/// Exact visible coverage of pixel (i, j) by any of `tris`, when it is the same at the
/// centre and 1/64 pixel away from it in the four axis directions; `None` for a centre
/// that close to the outline of what is visible (snapping moves a vertex by up to 1/512
/// pixel, a crossing on the near plane is exact up to rounding).
fn sees_clearly(view: &View, tris: &[[DVec3; 3]], i: u32, j: u32) -> Option<bool> {
    let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
    let d = 1.0 / 64.0;
    let at = |x: f64, y: f64| tris.iter().any(|p| sees(view, p, x, y));
    let c = at(x, y);
    [(d, 0.0), (-d, 0.0), (0.0, d), (0.0, -d)]
        .iter()
        .all(|&(dx, dy)| at(x + dx, y + dy) == c)
        .then_some(c)
}

/// Sets up and rasterizes `tris` (unit normals +z) through a [`TriangleProbe`] and
/// checks the union of their pieces against [`sees_clearly`]: no pixel twice, no double
/// hit on a shared edge, each fragment's depth in [0, 1], and a pixel covered exactly
/// when the rays see the triangles, except within 1/64 pixel of the outline. Returns the
/// outcomes, the pixels covered and the pixels within 1/64 pixel of the outline.
fn clip_against_rays<R: Real>(tris: &[[DVec3; 3]], view: &View) -> (Vec<SetupOutcome>, u32, u32) {
    let mut sink = Fragments::new();
    let mut probe = TriangleProbe::new(VP.width, &mut sink);
    let (mut pieces, mut outcomes, mut counts) = (Vec::new(), Vec::new(), Counts::default());
    for (k, p) in tris.iter().enumerate() {
        let o = setup::<R>(k as u32, p, &[DVec3::Z; 3], [1.0; 3], view, &mut pieces);
        assert!(o.fan <= 7 && pieces.len() <= o.fan.max(1), "{o:?}");
        for t in &pieces {
            rasterize(t, &mut probe, &mut counts);
        }
        outcomes.push(o);
    }
    assert_eq!(probe.double_hit_pixels(), 0, "{tris:?}");
    let (mut covered, mut unclear) = (0, 0);
    for (k, &n) in sink.hits.iter().enumerate() {
        let (i, j) = (k as u32 % VP.width, k as u32 / VP.width);
        assert!(n <= 1, "{tris:?}: pixel ({i}, {j}) covered {n} times");
        covered += n;
        match sees_clearly(view, tris, i, j) {
            Some(want) => assert_eq!(n == 1, want, "{tris:?}: pixel ({i}, {j})"),
            None => unclear += 1,
        }
    }
    if covered > 0 {
        assert!(
            0.0 <= sink.z[0] && sink.z[1] <= 1.0,
            "{tris:?}: depths {:?}",
            sink.z
        );
    }
    (outcomes, covered, unclear)
}

#[test]
fn a_triangle_straddling_the_near_plane_covers_its_visible_side_once() {
    let view = perspective_view();
    // A floor 3 cm below the eye, from behind it to 6 units ahead: the near plane cuts it
    // along row 36.5 (y_ndc = -0.03 / (0.1 tan 30°)), its far vertex is on row 24.2.
    let floor = [
        DVec3::new(-3.0, -0.03, 1.0),
        DVec3::new(3.0, -0.03, 1.0),
        DVec3::new(0.0, -0.03, -6.0),
    ];
    for datapath in [Datapath::F32, Datapath::F64] {
        let (o, covered, unclear) = match datapath {
            Datapath::F32 => clip_against_rays::<f32>(&[floor], &view),
            Datapath::F64 => clip_against_rays::<f64>(&[floor], &view),
        };
        assert!(o[0].depth && o[0].cull.is_none(), "{o:?}");
        // Rows 24 to 36, narrowing towards the far vertex.
        assert!((11 * 64..=13 * 64).contains(&covered), "{covered}");
        assert!(unclear <= 2 * 64, "{unclear}");
    }
    // A ramp from 1 unit ahead, 0.5 below the eye, up to a vertex behind the eye: the near
    // plane cuts it along row 32.3 (y = -0.02 there), its front edge is on row 44.8. The
    // pieces interpolate like the whole triangle.
    let ramp = [
        DVec3::new(-1.0, -0.5, -1.0),
        DVec3::new(1.0, -0.5, -1.0),
        DVec3::new(0.0, 0.3, 0.5),
    ];
    let n = [DVec3::Y, DVec3::new(0.0, 0.8, 0.6), DVec3::Z];
    let (o, covered, _) = clip_against_rays::<f64>(&[ramp], &view);
    assert!(
        o[0].depth && (11 * 64..=13 * 64).contains(&covered),
        "{o:?} {covered}"
    );
    let mut pieces = Vec::new();
    let o = setup::<f64>(0, &ramp, &n, [1.0; 3], &view, &mut pieces);
    assert_eq!(pieces_on_plane(&view, &pieces, &ramp, &n), covered);
    let mut counts = Counts::default();
    o.count(&mut counts);
    assert_eq!(
        (counts.triangles_clipped_depth, counts.triangles_clipped),
        (1, 0)
    );

    // Random triangles around a point near the near plane, vertices 0.03 to 3 units from
    // it in any direction (behind the eye too), both datapaths.
    let mut rng = SplitMix64::new(20240611);
    let mut rnd = || rng.unit();
    let (mut clipped, mut pixels, mut unclear) = (0, 0, 0);
    for _ in 0..300 {
        let m = DVec3::new(
            0.06 * (2.0 * rnd() - 1.0),
            0.05 * (2.0 * rnd() - 1.0),
            -0.1 + 0.04 * (2.0 * rnd() - 1.0),
        );
        let p: [DVec3; 3] = std::array::from_fn(|_| {
            let (a, z) = (rnd() * std::f64::consts::TAU, 2.0 * rnd() - 1.0);
            let r = (1.0 - z * z).sqrt();
            m + DVec3::new(r * a.cos(), r * a.sin(), z) * 0.03 * 100f64.powf(rnd())
        });
        let (o64, c64, u64_) = clip_against_rays::<f64>(&[p], &view);
        let (o32, c32, u32_) = clip_against_rays::<f32>(&[p], &view);
        assert_eq!(o64[0].depth, o32[0].depth, "{p:?}");
        clipped += o64[0].depth as u32;
        pixels += c64 + c32;
        unclear += u64_ + u32_;
    }
    assert!(clipped > 150, "{clipped}");
    assert!(pixels > 50 * 64 * 48, "{pixels}");
    assert!(unclear * 20 < pixels, "{unclear} of {pixels}");
}

#[test]
fn a_triangle_crossing_the_far_plane_is_clipped_there() {
    // The orthographic view's far plane is z = 10 (eye at z = -10, far 20).
    let view = ortho_view();
    let p = [
        DVec3::new(-10.0, 5.0, 0.0),
        DVec3::new(70.0, 10.0, 16.0),
        DVec3::new(20.0, 60.0, 8.0),
    ];
    for datapath in [Datapath::F32, Datapath::F64] {
        let (o, covered, _) = match datapath {
            Datapath::F32 => clip_against_rays::<f32>(&[p], &view),
            Datapath::F64 => clip_against_rays::<f64>(&[p], &view),
        };
        assert!(
            o[0].depth && !o[0].guard_band && o[0].cull.is_none(),
            "{o:?}"
        );
        assert!(covered > 500, "{covered}");
    }
}

#[test]
fn triangles_sharing_an_edge_across_the_near_plane_have_no_crack_and_no_double_hit() {
    // Orthographic (near plane z = -9): a shared edge through the pixel centres
    // (20.5 + 3k, 20.5 + k), from 1 unit nearer than the near plane to 1 beyond it, so
    // the plane cuts it at (20.5, 20.5); the third vertices on either side reach
    // nearer than the near plane too. The fill rule must give each centre on the edge
    // to one triangle.
    let view = ortho_view();
    let (p, q) = (DVec3::new(-9.5, 10.5, -10.0), DVec3::new(50.5, 30.5, -8.0));
    for (z1, z2) in [(-9.5, -8.5), (-12.0, -3.0), (-8.0, -9.9), (0.0, -20.0)] {
        let (r1, r2) = (DVec3::new(-30.0, 60.0, z1), DVec3::new(80.0, -20.0, z2));
        for tris in [[[p, q, r1], [q, p, r2]], [[q, r1, p], [r2, p, q]]] {
            let (o, covered, unclear) = clip_against_rays::<f64>(&tris, &view);
            assert!(o.iter().all(|o| o.depth), "{o:?}");
            assert!(covered > 300 && unclear < 200, "{covered} {unclear}");
            let (_, covered32, _) = clip_against_rays::<f32>(&tris, &view);
            assert!(covered32.abs_diff(covered) < 40, "{covered32} {covered}");
        }
    }
    // Perspective: random shared edges from behind the eye to ahead of it, through the
    // view; third vertices on either side, anywhere in depth.
    let view = perspective_view();
    let planes: Vec<DVec4> = depth_planes(&view)
        .into_iter()
        .chain(guard_band_planes(&view))
        .collect();
    let clip_all = |t: [DVec3; 3]| {
        let mut polygon = Polygon::new(&t, &[DVec3::Z; 3]);
        for &q in &planes {
            polygon = polygon.clip(q).unwrap();
        }
        polygon
    };
    let mut rng = SplitMix64::new(777);
    let mut rnd = || rng.unit();
    let mut pixels = 0;
    for case in 0..200 {
        let at = |x: f64, y: f64, z: f64| DVec3::new(x * z.abs(), y * z.abs(), z);
        let p = at(rnd() - 0.5, rnd() - 0.5, 0.05 + 2.0 * rnd());
        let q = at(0.5 * rnd() - 0.25, 0.4 * rnd() - 0.2, -0.15 - 5.0 * rnd());
        // A planar quadrilateral split along pq (two triangles folded along a shared
        // edge may overlap on screen legitimately; coplanar ones may not).
        let e = q - p;
        let side = e
            .cross(DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5))
            .normalize()
            * e.length();
        let along = |t: f64| p + e * t;
        let r1 = along(rnd()) + side * (0.05 + 2.0 * rnd());
        let r2 = along(rnd()) - side * (0.05 + 2.0 * rnd());
        let (a, b) = (clip_all([p, q, r1]), clip_all([q, p, r2]));
        if a.len > 0 && b.len > 0 {
            let shared = a
                .vertices()
                .iter()
                .filter(|u| b.vertices().iter().any(|v| v.p == u.p))
                .count();
            assert_eq!(shared, 2, "case {case}");
        }
        let (_, c64, _) = clip_against_rays::<f64>(&[[p, q, r1], [q, p, r2]], &view);
        let (_, c32, _) = clip_against_rays::<f32>(&[[p, q, r1], [q, p, r2]], &view);
        pixels += c64 + c32;
    }
    assert!(pixels > 100 * 64 * 48, "{pixels}");
}

#[test]
fn triangles_beyond_a_depth_plane_are_culled_and_clipped_ones_counted() {
    let view = perspective_view();
    let z = DVec3::Z;
    let mut out = Vec::new();
    let mut outcome = |p: [DVec3; 3]| setup::<f32>(0, &p, &[z; 3], [1.0; 3], &view, &mut out);
    let tri = |z0: f64, z1: f64, z2: f64| {
        [
            DVec3::new(-0.01, -0.01, z0),
            DVec3::new(0.01, -0.01, z1),
            DVec3::new(0.0, 0.01, z2),
        ]
    };
    // Between the eye and the near plane (z = -0.1), behind the eye, and both.
    for p in [
        tri(-0.05, -0.09, -0.02),
        tri(0.5, 1.0, 0.1),
        tri(0.5, -0.05, -0.09),
    ] {
        assert_eq!(outcome(p), SetupOutcome::culled(TriangleCull::BehindEye));
    }
    // Beyond the far plane (z = -100).
    assert_eq!(
        outcome(tri(-100.5, -120.0, -101.0)),
        SetupOutcome::culled(TriangleCull::Outside)
    );
    // Crossing the near plane, but wholly to the right of the view: rejected before any
    // clipping, whatever the sign of w.
    let right = [
        DVec3::new(1.0, 0.0, 0.5),
        DVec3::new(2.0, 0.0, -1.0),
        DVec3::new(3.0, 1.0, -1.0),
    ];
    assert_eq!(outcome(right), SetupOutcome::culled(TriangleCull::Outside));
    // Crossing near, far, both: clipped and drawn; counted once each.
    let mut counts = Counts::default();
    let big =
        |z0: f64, z1: f64, z2: f64| tri(z0, z1, z2).map(|p| p * DVec3::new(100.0, 100.0, 1.0));
    for p in [
        tri(0.5, -1.0, -1.0),
        big(-50.0, -150.0, -50.0),
        big(1.0, -200.0, -1.0),
    ] {
        let o = outcome(p);
        assert!(
            o.depth && !o.guard_band && o.fan >= 1 && o.cull.is_none(),
            "{o:?}"
        );
        o.count(&mut counts);
    }
    // Crossing the near plane and beyond the guard band: both clips.
    let wide = [
        DVec3::new(-1.0, -0.5, -2.0),
        DVec3::new(1e5, 0.0, -2.0),
        DVec3::new(0.0, 0.5, 1.0),
    ];
    let o = outcome(wide);
    assert!(o.depth && o.guard_band && o.cull.is_none(), "{o:?}");
    o.count(&mut counts);
    assert_eq!(
        (
            counts.triangles,
            counts.triangles_clipped_depth,
            counts.triangles_clipped
        ),
        (4, 4, 1)
    );
}

#[test]
fn setup_onto_appends_what_setup_gives_and_keeps_what_was_there() {
    let view = perspective_view();
    let n = [DVec3::Z; 3];
    let near = |x: f64| {
        [
            DVec3::new(x, -0.6, -1.5),
            DVec3::new(x + 0.5, -0.4, 0.5),
            DVec3::new(x, 1.2, -2.0),
        ]
    };
    let cases = [
        // Inside the guard band; far past it; through the near plane; wholly off screen;
        // a sliver through the near plane that covers no pixel centre, so every piece of
        // its fan is culled; wholly behind the eye.
        [
            DVec3::new(-1.0, -0.6, -1.5),
            DVec3::new(1.0, -0.4, -3.0),
            DVec3::new(-0.5, 1.2, -2.0),
        ],
        [
            DVec3::new(-1.0, -0.6, -1.5),
            DVec3::new(5000.0, -0.4, -3.0),
            DVec3::new(-0.5, 1.2, -2.0),
        ],
        near(0.0),
        near(-1.0e4),
        [
            DVec3::new(0.0, 0.0, -1.5),
            DVec3::new(0.0005, 0.0, 0.5),
            DVec3::new(0.0, 0.0005, -2.0),
        ],
        [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 2.0),
            DVec3::Y,
        ],
    ];
    let mut fanned_to_nothing = false;
    for p in cases {
        let mut alone = Vec::new();
        let want = setup::<f32>(3, &p, &n, [1.0; 3], &view, &mut alone);
        let earlier = setup_one::<f32>(9, &cases[0], &n, &view).unwrap();
        let mut onto = vec![earlier.clone()];
        let got = setup_onto::<f32>(3, &p, &n, [1.0; 3], &view, &mut onto);
        assert_eq!(got, want, "{p:?}");
        assert_eq!(onto[0], earlier, "what was there stays");
        assert_eq!(onto[1..], alone[..], "{p:?}");
        fanned_to_nothing |= want.fan > 0 && want.cull.is_some();
    }
    assert!(fanned_to_nothing, "a case fans into pieces all culled");
}
