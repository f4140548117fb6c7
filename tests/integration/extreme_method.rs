//! The extreme method against its guarantees (Martinelli 2006 section 5, DESIGN.md §2 and §6), end
//! to end through `render_functional`:
//! - random lembos: every fragment within k of its scanline and inside the domain, every
//!   edge root paired, and coverage equal to the exact reference outside a band of k + 1.5
//!   pixels around the reference silhouette (seeded property tests; a fragment of a sliver
//!   thinner than a pixel, which the reference's pixel centres miss, must be within k + 1
//!   of the true image instead);
//! - shared edges: neighbours compute bit-identical crossings, and render without cracks or
//!   double hits;
//! - closed meshes (the sphere of 24 lembos, the bunny): no cracks, no double hits.

use glam::DVec3;
use lembo_sim::camera::View;
use lembo_sim::datapath::{Datapath, Real};
use lembo_sim::frame::{render_functional, Frame};
use lembo_sim::job::{measure_frame, PrimitivePath};
use lembo_sim::lembo::construct::lembo_from_triangle;
use lembo_sim::lembo::Lembo;
use lembo_sim::raster::interval::{edge_crossings, ConicPoint};
use lembo_sim::raster::probe::shared_edges;
use lembo_sim::raster::setup::{setup, ScreenLembo};
use lembo_sim::raster::{minmax, render_lembos, Counts, DEFAULT_SEGMENT_CAP};
use lembo_sim::reference::metrics::Accuracy;
use lembo_sim::reference::oracle::{
    render_reference, ReferenceImage, ReferenceInput, DEFAULT_TILE,
};
use lembo_sim::rop::framebuffer::NO_PRIMITIVE;
use lembo_sim::scene::Scene;
use proptest::prelude::*;
use proptest::test_runner::{RngAlgorithm, TestRng, TestRunner};
use std::path::Path;

use crate::support::scenes::trace;
use crate::support::Hits;

/// Side of the test viewport [pixels].
const SIDE: usize = 128;

/// The property tests' fixed seed: the cases are the same on every run and machine.
const SEED: [u8; 32] = *b"lembo-sim extreme method tests!!";

fn runner(cases: u32) -> TestRunner {
    let config = ProptestConfig {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..ProptestConfig::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &SEED))
}

/// A scene of `lembos` in a 128 x 128 orthographic view down -z, 128 world units high, in
/// which world (X, Y) lands on screen (X + 64, 64 - Y).
fn ortho_scene(lembos: Vec<Lembo>) -> Scene {
    let text = r#"{"name": "extreme", "viewport": {"width": 128, "height": 128},
        "camera": {"eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0],
                   "projection": {"kind": "orthographic", "height": 128, "near": 0.1, "far": 100}},
        "objects": [{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0],[0,0.5,0],[0.5,0.5,0]],
                                 "normals": [[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1]]}]}]}"#;
    let mut scene = Scene::from_json(text, "extreme_method.rs", Path::new(".")).unwrap();
    scene.objects[0].lembos = lembos.into();
    scene
}

/// World point of screen position (x, y) [pixels] at depth coordinate z in [`ortho_scene`].
fn world(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x - 64.0, 64.0 - y, z)
}

fn view_of(scene: &Scene) -> View {
    View::new(&scene.camera, scene.viewport)
}

fn reference(scene: &Scene, view: &View) -> ReferenceImage {
    let held: Vec<(Lembo, [f64; 3])> = scene.lembos().collect();
    let lembos: Vec<(&Lembo, [f64; 3])> = held.iter().map(|(l, c)| (l, *c)).collect();
    render_reference(&ReferenceInput {
        lembos: &lembos,
        view,
        light: &scene.light,
        background: scene.background,
        supersample: 1,
        tile: DEFAULT_TILE,
    })
}

fn accuracy(scene: &Scene, frame: &Frame, reference: &ReferenceImage) -> Accuracy {
    assert!(frame.probe.is_some(), "rendered with analyse");
    measure_frame(
        scene,
        &view_of(scene),
        frame,
        reference,
        PrimitivePath::Lembo,
        1,
        Default::default(),
    )
}

fn covered(frame: &Frame) -> Vec<bool> {
    frame
        .framebuffer
        .primitive
        .iter()
        .map(|&p| p != NO_PRIMITIVE)
        .collect()
}

fn reference_covered(reference: &ReferenceImage) -> Vec<bool> {
    reference.hits.iter().map(|h| h.is_some()).collect()
}

/// The pixels (i, j) where render and reference disagree farther than `band` [pixels] from
/// the reference silhouette, measured from the pixel to the nearest pixel whose reference
/// coverage differs from its own.
fn disagreements_beyond(
    ours: &[bool],
    theirs: &[bool],
    w: usize,
    h: usize,
    band: f64,
) -> Vec<(usize, usize)> {
    let r = band.ceil() as isize;
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let k = j * w + i;
            if ours[k] == theirs[k] {
                continue;
            }
            let near = (-r..=r).any(|dj| {
                (-r..=r).any(|di| {
                    let (x, y) = (i as isize + di, j as isize + dj);
                    let inside = x >= 0 && y >= 0 && x < w as isize && y < h as isize;
                    inside
                        && ((di * di + dj * dj) as f64).sqrt() <= band
                        && theirs[y as usize * w + x as usize] != theirs[k]
                })
            });
            if !near {
                out.push((i, j));
            }
        }
    }
    out
}

/// The distance [pixels] from the centre of pixel (i, j) to the screen image of the single
/// lembo of `scene`, from a dense sample of its domain (finer than 0.2 px for the lembos of
/// these tests). For a sliver thinner than a pixel the reference covers no pixel centre at
/// all, so the pixel-sampled silhouette says nothing about how far a fragment is from it.
fn distance_to_image(scene: &Scene, i: usize, j: usize) -> f64 {
    let (lembo, color) = scene.lembos().next().unwrap();
    let l = setup::<f64>(0, &lembo, color, &view_of(scene)).unwrap();
    let n = 2048;
    let (cx, cy) = (i as f64 + 0.5, j as f64 + 0.5);
    let mut d2 = f64::INFINITY;
    for a in 0..=n {
        for b in 0..=n - a {
            let (u, v) = (a as f64 / n as f64, b as f64 / n as f64);
            d2 = d2.min((l.x.eval(u, v) - cx).powi(2) + (l.y.eval(u, v) - cy).powi(2));
        }
    }
    d2.sqrt()
}

/// Checks the paper's guarantees on one rendered frame of a single-object ortho scene.
fn check_guarantees<R: Real>(
    scene: &Scene,
    k: f64,
    reference: &ReferenceImage,
) -> Result<(), TestCaseError> {
    let datapath = if R::NAME == "f32" {
        Datapath::F32
    } else {
        Datapath::F64
    };
    let (rounding, domain) = if R::NAME == "f32" {
        (1e-3, 1e-5)
    } else {
        (1e-9, 1e-12)
    };
    let frame = render_functional(scene, &view_of(scene), k, datapath, true).unwrap();
    let probe = frame.probe.unwrap();
    prop_assert_eq!(frame.counts.unpaired_roots, 0, "{:?}", frame.counts);
    prop_assert!(
        probe.max_scanline_deviation_px <= k + rounding,
        "{} deviation {} > k {}",
        R::NAME,
        probe.max_scanline_deviation_px,
        k
    );
    prop_assert!(
        probe.max_domain_excess <= domain,
        "{} domain excess {}",
        R::NAME,
        probe.max_domain_excess
    );
    let (ours, theirs) = (covered(&frame), reference_covered(reference));
    for (i, j) in disagreements_beyond(&ours, &theirs, SIDE, SIDE, k + 1.5) {
        // A fragment where the reference has none is still fine within k + 1 of the image.
        let d = if ours[j * SIDE + i] {
            distance_to_image(scene, i, j)
        } else {
            f64::INFINITY
        };
        prop_assert!(
            d <= k + 1.0,
            "{} pixel ({}, {}) differs from the reference far from its silhouette (k {})",
            R::NAME,
            i,
            j,
            k
        );
    }
    Ok(())
}

/// Six points of a lembo: the corners `c` and the edge middles moved off the chords by
/// fractions `bend` of the edge lengths, at depths `z` (A, B, C, D, E, F order).
fn bent_lembo(
    c: [(f64, f64); 3],
    bend: [(f64, f64); 3],
    z: [f64; 6],
    normals: [(f64, f64, f64); 6],
) -> Lembo {
    // D, E, F are the middles of AB, AC, BC.
    let mids = [(0, 1), (0, 2), (1, 2)].map(|(p, q)| {
        let len = ((c[q].0 - c[p].0).powi(2) + (c[q].1 - c[p].1).powi(2)).sqrt();
        (0.5 * (c[p].0 + c[q].0), 0.5 * (c[p].1 + c[q].1), len)
    });
    let mut points = [DVec3::ZERO; 6];
    for n in 0..3 {
        points[n] = world(c[n].0, c[n].1, z[n]);
        let (x, y, len) = mids[n];
        points[3 + n] = world(x + bend[n].0 * len, y + bend[n].1 * len, z[3 + n]);
    }
    Lembo::new(points, normals.map(|(x, y, z)| DVec3::new(x, y, z)))
}

fn area(c: &[(f64, f64); 3]) -> f64 {
    0.5 * ((c[1].0 - c[0].0) * (c[2].1 - c[0].1) - (c[2].0 - c[0].0) * (c[1].1 - c[0].1))
}

#[test]
fn random_lembos_keep_the_paper_guarantees() {
    let corner = (10.0..118.0f64, 10.0..118.0f64);
    let strategy = (
        prop::array::uniform3(corner),
        prop::array::uniform3((-0.25..0.25f64, -0.25..0.25f64)),
        prop::array::uniform6(-3.0..3.0f64),
        prop::array::uniform6((-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)),
        0.1..2.0f64,
    )
        .prop_filter("a proper triangle", |(c, ..)| area(c).abs() > 50.0)
        .prop_map(|(c, bend, z, n, k)| (bent_lembo(c, bend, z, n), k));
    let result = runner(64).run(&strategy, |(lembo, k)| {
        let scene = ortho_scene(vec![lembo]);
        let reference = reference(&scene, &view_of(&scene));
        check_guarantees::<f32>(&scene, k, &reference)?;
        check_guarantees::<f64>(&scene, k, &reference)
    });
    if let Err(e) = result {
        panic!("{e}");
    }
}

/// Two lembos built from triangles (p0, p1, p2) and (p2, p1, p3), which share the edge
/// p1 p2 traversed in opposite directions, with vertex normals `n`.
fn pair(p: [DVec3; 4], n: [DVec3; 4]) -> Vec<Lembo> {
    vec![
        lembo_from_triangle([p[0], p[1], p[2]], [n[0], n[1], n[2]]),
        lembo_from_triangle([p[2], p[1], p[3]], [n[2], n[1], n[3]]),
    ]
}

/// Checks that the two lembos of `scene` find the same crossings on their shared edge, bit
/// for bit, on every scanline either covers; returns the number of crossings compared.
fn shared_crossings_agree<R: Real>(scene: &Scene) -> usize {
    let view = view_of(scene);
    let (e0, e1) = shared_edges(scene, 1)[&(0, 1)];
    let ls: Vec<ScreenLembo<R>> = scene
        .lembos()
        .enumerate()
        .map(|(id, (l, c))| setup::<R>(id as u32, &l, c, &view).unwrap())
        .collect();
    let (j0, j1) = ls
        .iter()
        .filter_map(|l| minmax::scanlines(l, SIDE as u32))
        .fold((u32::MAX, 0), |(a, b), (c, d)| (a.min(c), b.max(d)));
    let mut compared = 0;
    for j in j0..=j1 {
        let yj = R::of(j as f64 + 0.5);
        let mut sides = [(0, e0), (1, e1)].map(|(n, e)| {
            let mut roots: Vec<(ConicPoint<R>, bool)> = Vec::new();
            edge_crossings(&ls[n], e as usize, yj, |p, entry| roots.push((p, entry)));
            roots.sort_by(|a, b| a.0.x.partial_cmp(&b.0.x).unwrap());
            roots
        });
        let [a, b] = &mut sides;
        assert_eq!(a.len(), b.len(), "{} scanline {j}: {a:?} vs {b:?}", R::NAME);
        for (p, q) in a.iter().zip(b.iter()) {
            assert_eq!(
                p.0.x.f64().to_bits(),
                q.0.x.f64().to_bits(),
                "{} scanline {j}",
                R::NAME
            );
            // Entering one lembo across the shared edge is leaving the other.
            assert_ne!(p.1, q.1, "{} scanline {j}", R::NAME);
        }
        compared += a.len();
    }
    compared
}

/// The fixed pair: a curved quadrilateral split along a diagonal, its normals those of a
/// sphere around a centre behind and to the side, so that every edge bends on screen.
fn fixed_pair() -> Scene {
    let corners = [
        (20.0, 24.0, 0.5),
        (104.0, 30.0, -0.3),
        (36.0, 108.0, 0.2),
        (112.0, 100.0, -0.6),
    ];
    let p = corners.map(|(x, y, z)| world(x, y, z));
    let centre = DVec3::new(-10.0, 15.0, -120.0);
    ortho_scene(pair(p, p.map(|q| (q - centre).normalize())))
}

#[test]
fn shared_edge_crossings_are_bit_identical_from_both_sides() {
    let scene = fixed_pair();
    // The shared edge is curved on screen: its middle is off the chord.
    let (a, b) = (
        &scene.objects[0].lembos.get(0),
        &scene.objects[0].lembos.get(1),
    );
    let chord_mid = 0.5 * (a.points[1] + a.points[2]);
    assert_eq!(a.points[5], b.points[3]);
    assert!(
        (a.points[5] - chord_mid).truncate().length() > 0.5,
        "{:?}",
        a.points[5] - chord_mid
    );
    assert!(shared_crossings_agree::<f32>(&scene) > 60);
    assert!(shared_crossings_agree::<f64>(&scene) > 60);
}

fn check_pair_render<R: Real>(
    scene: &Scene,
    k: f64,
    reference: &ReferenceImage,
    exact_once: bool,
) -> Result<(), TestCaseError> {
    let datapath = if R::NAME == "f32" {
        Datapath::F32
    } else {
        Datapath::F64
    };
    let view = view_of(scene);
    let frame = render_functional(scene, &view, k, datapath, true).unwrap();
    let acc = accuracy(scene, &frame, reference);
    prop_assert_eq!(acc.double_hit_pixels, 0, "{}", R::NAME);
    prop_assert_eq!(acc.crack_pixels, 0, "{}", R::NAME);
    let far = disagreements_beyond(
        &covered(&frame),
        &reference_covered(reference),
        SIDE,
        SIDE,
        k + 1.5,
    );
    prop_assert!(
        far.is_empty(),
        "{} pixels far from the silhouette: {:?}",
        R::NAME,
        far
    );
    if exact_once {
        // No fold on screen: every pixel is hit by at most one fragment of the two lembos,
        // and each row's covered pixels are one run.
        let mut sink = Hits::new(SIDE as u32, SIDE as u32);
        let mut counts = Counts::default();
        render_lembos::<R, _>(scene, &view, k, DEFAULT_SEGMENT_CAP, &mut sink, &mut counts)
            .unwrap();
        for (j, row) in sink.count.chunks(SIDE).enumerate() {
            prop_assert!(
                row.iter().all(|&n| n <= 1),
                "{} row {}: {:?}",
                R::NAME,
                j,
                row
            );
            let hit: Vec<usize> = (0..SIDE).filter(|&i| row[i] > 0).collect();
            if let (Some(first), Some(last)) = (hit.first(), hit.last()) {
                prop_assert_eq!(
                    hit.len(),
                    last - first + 1,
                    "{} row {} is not one run",
                    R::NAME,
                    j
                );
            }
        }
    }
    Ok(())
}

#[test]
fn shared_edge_pair_renders_without_cracks_or_double_hits() {
    let scene = fixed_pair();
    let reference = reference(&scene, &view_of(&scene));
    for k in [0.1, 0.5, 1.0] {
        check_pair_render::<f32>(&scene, k, &reference, true).unwrap();
        check_pair_render::<f64>(&scene, k, &reference, true).unwrap();
    }
}

#[test]
fn random_shared_edge_pairs_agree_bit_for_bit_and_leave_no_cracks() {
    // Corners: p1, p2 on the shared diagonal, p0 and p3 on either side of it.
    let strategy = (
        (20.0..108.0f64, 10.0..40.0f64),
        (10.0..40.0f64, 20.0..108.0f64),
        (88.0..118.0f64, 20.0..108.0f64),
        (20.0..108.0f64, 88.0..118.0f64),
        prop::array::uniform4(-2.0..2.0f64),
        prop::array::uniform4((-0.5..0.5f64, -0.5..0.5f64)),
        0.1..1.0f64,
    )
        .prop_map(|(p0, p1, p2, p3, z, tilt, k)| {
            // Corners in the order p0 (top), p1 (left), p2 (right), p3 (bottom): the shared
            // edge is p1 p2, which separates p0 from p3.
            let c = [p0, p1, p2, p3];
            let p = [0, 1, 2, 3].map(|n| world(c[n].0, c[n].1, z[n]));
            let n = tilt.map(|(x, y)| DVec3::new(x, y, 1.0));
            (pair(p, n), k)
        });
    let result = runner(64).run(&strategy, |(lembos, k)| {
        let scene = ortho_scene(lembos);
        prop_assert!(shared_crossings_agree::<f32>(&scene) > 0);
        prop_assert!(shared_crossings_agree::<f64>(&scene) > 0);
        let reference = reference(&scene, &view_of(&scene));
        check_pair_render::<f32>(&scene, k, &reference, false)?;
        check_pair_render::<f64>(&scene, k, &reference, false)
    });
    if let Err(e) = result {
        panic!("{e}");
    }
}

/// Renders a closed mesh at its own viewport and checks it has neither double hits nor
/// holes; returns the accuracy for scene-specific checks.
fn check_closed_mesh(scene: &Scene, datapath: Datapath) -> Accuracy {
    let view = view_of(scene);
    let k = 0.5;
    let frame = render_functional(scene, &view, k, datapath, true).unwrap();
    let probe = frame.probe.unwrap();
    assert_eq!(
        frame.counts.unpaired_roots, 0,
        "{}: {:?}",
        scene.name, frame.counts
    );
    assert_eq!(probe.double_hit_pixels, 0, "{} {datapath:?}", scene.name);
    assert!(
        probe.max_scanline_deviation_px <= k + 1e-3,
        "{} {datapath:?}: {probe:?}",
        scene.name
    );
    let reference = reference(scene, &view);
    let (w, ours, theirs) = (
        scene.viewport.width as usize,
        covered(&frame),
        reference_covered(&reference),
    );
    assert_eq!(
        narrow_gaps(&ours, &theirs, w),
        Vec::<(usize, usize)>::new(),
        "{} {datapath:?}",
        scene.name
    );
    accuracy(scene, &frame, &reference)
}

/// Cracks as a seam fault makes them: runs of at most two pixels in a row that the render
/// leaves uncovered between two covered pixels while the reference covers them (as (i, j)
/// of the run's first pixel). The crack metric counts one-pixel gaps away from the
/// silhouette; this also sees two-pixel gaps and gaps next to the silhouette.
fn narrow_gaps(ours: &[bool], theirs: &[bool], w: usize) -> Vec<(usize, usize)> {
    let mut gaps = Vec::new();
    for (j, (row, want)) in ours.chunks(w).zip(theirs.chunks(w)).enumerate() {
        for i in 1..w {
            if row[i - 1] && !row[i] {
                let len = (i..w).take_while(|&n| !row[n]).count();
                if len <= 2 && i + len < w && (i..i + len).all(|n| want[n]) {
                    gaps.push((i, j));
                }
            }
        }
    }
    gaps
}

#[test]
fn closed_meshes_have_no_cracks_and_no_double_hits() {
    // The sphere of 24 lembos (embedded default and trace) and the bunny at their own
    // 512 x 512 perspective views, and the sphere in an orthographic view, where setup's
    // screen quadratics are exact.
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("traces/sphere24.json"))
            .unwrap();
    let perspective = r#""kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100"#;
    assert!(text.contains(perspective));
    let ortho = text.replace(
        perspective,
        r#""kind": "orthographic", "height": 2.9, "near": 0.1, "far": 100"#,
    );
    let scenes = [
        Scene::default_scene(),
        trace("sphere24.json", None),
        trace("bunny.json", None),
        Scene::from_json(&ortho, "sphere24 orthographic", Path::new(".")).unwrap(),
    ];
    for scene in &scenes {
        assert_eq!((scene.viewport.width, scene.viewport.height), (512, 512));
        for datapath in [Datapath::F32, Datapath::F64] {
            let acc = check_closed_mesh(scene, datapath);
            assert_eq!(acc.crack_pixels, 0, "{} {datapath:?}", scene.name);
            assert_eq!(acc.double_hit_pixels, 0, "{} {datapath:?}", scene.name);
        }
    }
}
