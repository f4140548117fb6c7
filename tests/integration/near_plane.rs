//! Near- and far-plane clipping of the triangle path (DESIGN.md §13, "How the triangle
//! path is made fair") on the scenes that need it: a ground plane running behind the camera
//! (`traces/walkthrough_ground.json`), a camera 0.05 in front of a sphere with the near
//! plane 0.2 away (`traces/near_camera.json`) and a camera inside a closed sphere
//! (`traces/inside_mesh.json`). Each is measured against the exact reference and, at coarse
//! tessellations, against the exact reference of its own flat facets (so that the faceting
//! error is told apart from a clipping error); fragments keep depths in [0, 1]; the timed
//! path draws the functional image and charges the clipped pieces.

use glam::DVec3;
use lembo_sim::camera::View;
use lembo_sim::datapath::{Datapath, Real};
use lembo_sim::frame::{render_functional_triangles, Frame};
use lembo_sim::job::{measure_frame, render_reference, PrimitivePath};
use lembo_sim::lembo::tessellate::{Tessellation, Triangle};
use lembo_sim::lembo::Lembo;
use lembo_sim::pipeline::SimOptions;
use lembo_sim::pipeline::{run_timed, Source, UnitKind};
use lembo_sim::raster::triangle::{
    render_triangles, ScreenTriangle, TriangleFragment, TriangleSink, TriangleSource,
};
use lembo_sim::raster::Counts;
use lembo_sim::reference::flip::flip_frame;
use lembo_sim::reference::metrics::{measure, Accuracy};
use lembo_sim::reference::oracle::{self, ReferenceInput, DEFAULT_TILE};
use lembo_sim::scene::Scene;

use crate::support::{arch, fans, scenes};
use scenes::trace as scene;

fn functional(s: &Scene, n: u32, datapath: Datapath) -> Frame {
    let view = View::new(&s.camera, s.viewport);
    render_functional_triangles(
        s,
        &view,
        &Tessellation::new(s.lembo_sets(), n),
        datapath,
        true,
    )
}

/// The triangle path at level `n` against the exact reference of the scene's lembos.
fn against_reference(s: &Scene, n: u32, datapath: Datapath) -> (Accuracy, Counts) {
    let view = View::new(&s.camera, s.viewport);
    let (reference, _) = render_reference(s, &view, 1, lembo_sim::camera::Samples::ONE);
    let f = functional(s, n, datapath);
    let a = measure_frame(
        s,
        &view,
        &f,
        &reference,
        PrimitivePath::Triangle,
        u64::from(n * n),
        Default::default(),
    );
    let c = &f.counts;
    eprintln!(
        "{} n={n} {datapath:?}: PSNR {:.2} dB, coverage +{} / -{}, cracks {}, depth {:.2e}; \
         {} triangles, {} clipped at near/far, {} to the guard band, {} culled near, {} outside",
        s.name,
        a.psnr_db,
        a.coverage_false_positive,
        a.coverage_false_negative,
        a.crack_pixels,
        a.depth_max_abs,
        c.triangles,
        c.triangles_clipped_depth,
        c.triangles_clipped,
        c.triangles_culled_behind_eye,
        c.triangles_culled_outside
    );
    (a, f.counts)
}

/// The triangle path at level `n` against the exact reference of the very triangles it
/// draws: each a flat lembo (edge midpoints, mid-normals the mean of the ends' normals, so
/// its normal function is the triangle's linear blend).
fn against_facets(s: &Scene, n: u32, datapath: Datapath) -> Accuracy {
    let view = View::new(&s.camera, s.viewport);
    let t = Tessellation::new(s.lembo_sets(), n);
    let mut facets: Vec<(Lembo, [f64; 3])> = Vec::new();
    let mut tris: Vec<Triangle> = Vec::new();
    for c in 0..t.chunks() {
        t.chunk(c, &mut tris);
        for tr in &tris {
            let (p, m) = (tr.positions, tr.normals);
            let mid = |a: usize, b: usize, v: &[DVec3; 3]| (v[a] + v[b]) * 0.5;
            let lembo = Lembo::new(
                [
                    p[0],
                    p[1],
                    p[2],
                    mid(0, 1, &p),
                    mid(0, 2, &p),
                    mid(1, 2, &p),
                ],
                [
                    m[0],
                    m[1],
                    m[2],
                    mid(0, 1, &m),
                    mid(0, 2, &m),
                    mid(1, 2, &m),
                ],
            );
            facets.push((lembo, tr.color));
        }
    }
    let lembos: Vec<(&Lembo, [f64; 3])> = facets.iter().map(|(l, c)| (l, *c)).collect();
    let reference = oracle::render_reference(&ReferenceInput {
        lembos: &lembos,
        view: &view,
        light: &s.light,
        background: s.background,
        supersample: 1,
        tile: DEFAULT_TILE,
    });
    let f = functional(s, n, datapath);
    let tracer = oracle::Tracer::of(facets.iter().map(|(l, _)| l), &view);
    let a = measure(
        &f.framebuffer,
        &reference,
        &tracer,
        f.probe.unwrap().double_hit_pixels,
        None,
        Default::default(),
        &flip_frame(&f.framebuffer, &reference, Default::default()),
    );
    eprintln!(
        "{} n={n} {datapath:?} against its facets: PSNR {:.2} dB, coverage +{} / -{}, depth {:.2e}",
        s.name, a.psnr_db, a.coverage_false_positive, a.coverage_false_negative, a.depth_max_abs
    );
    a
}

/// The range of the window depths of every fragment the triangle path generates (before
/// the depth test, which would discard those outside [0, 1]).
fn fragment_depths(s: &Scene, n: u32) -> [f64; 2] {
    struct Depths([f64; 2]);
    impl<R: Real> TriangleSink<R> for Depths {
        fn fragment(&mut self, _: &ScreenTriangle<R>, _: u32, _: u32, f: &TriangleFragment<R>) {
            let z = f.z.f64();
            self.0 = [self.0[0].min(z), self.0[1].max(z)];
        }
    }
    let view = View::new(&s.camera, s.viewport);
    let mut sink = Depths([f64::INFINITY, f64::NEG_INFINITY]);
    let mut counts = Counts::default();
    render_triangles::<f32, _>(
        &Tessellation::new(s.lembo_sets(), n),
        &view,
        &mut sink,
        &mut counts,
    );
    assert!(counts.fragments > 0);
    sink.0
}

fn assert_depths_in_range(s: &Scene, n: u32) {
    let [lo, hi] = fragment_depths(s, n);
    assert!(
        0.0 <= lo && hi <= 1.0,
        "{} n={n}: depths {lo} to {hi}",
        s.name
    );
}

fn assert_watertight(a: &Accuracy, what: &str) {
    assert_eq!(
        (a.crack_pixels, a.double_hit_pixels),
        (0, 0),
        "{what}: {a:?}"
    );
}

#[test]
fn a_ground_plane_running_behind_the_camera_is_drawn_up_to_the_near_plane() {
    // The ground alone is flat: the triangle path draws it as the reference does, at the
    // mesh's own level. Before near clipping the part of it near the camera was missing
    // (PSNR 21 dB with the sphere, coverage -79 000 px at level 1).
    let full = scene("walkthrough_ground.json", None);
    let mut ground = full.clone();
    ground.objects.truncate(1);
    for datapath in [Datapath::F32, Datapath::F64] {
        let (a, c) = against_reference(&ground, 1, datapath);
        assert!(c.triangles_clipped_depth >= 4, "{c:?}");
        assert!(a.psnr_db >= 60.0, "{a:?}");
        assert!(
            a.coverage_false_positive + a.coverage_false_negative <= 2,
            "{a:?}"
        );
        assert_watertight(&a, "ground");
    }
    assert_depths_in_range(&ground, 1);
    // With the sphere standing on it, at a level fine enough for the sphere: PSNR >= 35 dB,
    // and the only coverage errors are the sphere's silhouette, no more than the sphere
    // alone has against the background (its outline over the ground is covered both ways).
    let mut sphere = full.clone();
    sphere.objects.remove(0);
    for n in [4, 8] {
        let (a, c) = against_reference(&full, n, Datapath::F32);
        let (alone, _) = against_reference(&sphere, n, Datapath::F32);
        assert!(c.triangles_clipped_depth >= 1, "{c:?}");
        assert!(a.psnr_db >= 35.0, "n={n}: {a:?}");
        assert!(
            a.coverage_false_positive <= alone.coverage_false_positive
                && a.coverage_false_negative <= alone.coverage_false_negative,
            "n={n}: {a:?} against the sphere alone {alone:?}"
        );
        assert_watertight(&a, "ground and sphere");
        assert_depths_in_range(&full, n);
    }
}

#[test]
fn a_near_plane_slicing_a_sphere_leaves_only_the_faceting_error() {
    // The eye is 0.05 in front of the unit sphere, the near plane 0.2: the plane slices the
    // sphere and the view looks at the inside of its far side. Every pixel is covered.
    let s = scene("near_camera.json", None);
    for n in [1, 2] {
        let (a, c) = against_reference(&s, n, Datapath::F32);
        assert!(c.triangles_clipped_depth >= 1, "{c:?}");
        assert_eq!(
            (a.coverage_false_positive, a.coverage_false_negative),
            (0, 0),
            "n={n}: {a:?}"
        );
        assert_watertight(&a, "near camera");
        assert_depths_in_range(&s, n);
        if n == 2 {
            assert!(a.psnr_db >= 40.0, "{a:?}");
        }
        // At level 1 the sphere's 24 flat facets lie up to 0.25 inside it, so near the view
        // axis they are beyond the near plane where the sphere is not: the image shows
        // vertical bands of front facets (PSNR 15.8 dB against the sphere). They are the
        // facets' own: against the exact render of those facets the image agrees.
        let f = against_facets(&s, n, Datapath::F32);
        assert!(f.psnr_db >= 40.0, "n={n}: {f:?}");
        assert!(
            f.coverage_false_positive + f.coverage_false_negative <= 4,
            "n={n}: {f:?}"
        );
        assert!(f.depth_max_abs < 1e-3, "n={n}: {f:?}");
    }
}

#[test]
fn a_camera_inside_a_closed_mesh_sees_it_all_around() {
    // The eye at the centre of the sphere scaled by 3, looking along +z with 90 degrees:
    // every pixel sees a back face. Before near clipping level 1 missed 67 072 of the
    // 262 144 pixels (the facets reaching behind the eye).
    let s = scene("inside_mesh.json", None);
    for n in [1, 2] {
        let (a, c) = against_reference(&s, n, Datapath::F32);
        assert_eq!(
            (a.coverage_false_positive, a.coverage_false_negative),
            (0, 0),
            "n={n}: {a:?}"
        );
        assert!(a.psnr_db >= 60.0, "n={n}: {a:?}");
        assert_watertight(&a, "inside");
        assert_depths_in_range(&s, n);
        if n == 1 {
            assert!(c.triangles_clipped_depth >= 1, "{c:?}");
        }
    }
    let f = against_facets(&s, 1, Datapath::F32);
    assert!(f.psnr_db >= 60.0, "{f:?}");
    assert_eq!(
        (f.coverage_false_positive, f.coverage_false_negative),
        (0, 0)
    );
}

#[test]
fn timed_near_clipping_draws_the_functional_image_and_charges_its_pieces() {
    for name in [
        "walkthrough_ground.json",
        "near_camera.json",
        "inside_mesh.json",
    ] {
        let s = scene(name, Some(128));
        let view = View::new(&s.camera, s.viewport);
        let t = Tessellation::new(s.lembo_sets(), 1);
        let f = functional(&s, 1, Datapath::F32);
        assert!(
            f.counts.triangles_clipped_depth >= 1,
            "{name}: {:?}",
            f.counts
        );
        let fan = fans::<f32>(&s, 1, &view);
        for mut a in [arch("baseline.json"), arch("minimal.json")] {
            for per_piece in [1, 3] {
                a.triangle_setup.cycles_per_clipped_piece = per_piece;
                let timed = run_timed(
                    &s,
                    &view,
                    0.5,
                    Datapath::F32,
                    &a,
                    Source::Triangles(&t),
                    &SimOptions::default(),
                )
                .expect("timed run");
                let what = format!("{name} arch {} per piece {per_piece}", a.name);
                assert!(timed.framebuffer.color == f.framebuffer.color, "{what}");
                assert!(timed.framebuffer.depth == f.framebuffer.depth, "{what}");
                let (tc, fc) = (&timed.counts, &f.counts);
                assert_eq!(
                    tc.triangles_clipped_depth, fc.triangles_clipped_depth,
                    "{what}"
                );
                assert_eq!(tc.triangles_clipped, fc.triangles_clipped, "{what}");
                assert_eq!(tc.fragments, fc.fragments, "{what}");
                let setup = &timed.cycles.units[1];
                assert_eq!(setup.kind, UnitKind::TriangleSetup);
                assert_eq!(
                    setup.busy.0,
                    fc.triangles * a.triangle_setup.cycles_per_triangle + fan * per_piece,
                    "{what}"
                );
            }
        }
    }
}
