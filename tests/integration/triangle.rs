//! The triangle path against its contract (DESIGN.md §5, issue 4): the timed units draw the
//! functional model's image bit for bit on every architecture, the tessellation converges
//! to the surface as a GPU mesh would, a mesh at level 1 is drawn as given, and only the
//! triangle units are instantiated.

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::frame::{render_functional_triangles, Frame};
use lembo_sim::job::{measure_frame, render_reference, PrimitivePath};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::SimOptions;
use lembo_sim::pipeline::{run_timed, Source, TimedFrame, UnitKind};
use lembo_sim::scene::Scene;

use crate::support::{arch, fans, scenes};
use scenes::trace as scene;

fn timed(scene: &Scene, n: u32, arch: &ArchConfig, datapath: Datapath) -> TimedFrame {
    let view = View::new(&scene.camera, scene.viewport);
    let t = Tessellation::new(scene.lembo_sets(), n);
    run_timed(
        scene,
        &view,
        0.5,
        datapath,
        arch,
        Source::Triangles(&t),
        &SimOptions::default(),
    )
    .expect("timed run")
}

fn functional(scene: &Scene, n: u32, datapath: Datapath, analyse: bool) -> Frame {
    let view = View::new(&scene.camera, scene.viewport);
    let t = Tessellation::new(scene.lembo_sets(), n);
    render_functional_triangles(scene, &view, &t, datapath, analyse)
}

/// Triangle rasterizer counts 1..4, ROP counts 1..8, tiles of 3 (quad rows split across
/// tile rows) to 16 pixels, FIFO depths 1..64.
fn matrix() -> Vec<ArchConfig> {
    let mut odd = ArchConfig::default();
    odd.triangle_rasterizer.count = 3;
    odd.triangle_rasterizer.pixels_per_cycle = 5;
    odd.rop.count = 3;
    odd.rop.tile_px = 3;
    for c in odd.links.all_mut() {
        c.fifo_depth = 2;
    }
    let mut wide = arch("wide.json");
    wide.triangle_rasterizer.count = 4;
    wide.rop.count = 8;
    wide.rop.tile_px = 16;
    vec![
        arch("baseline.json"),
        arch("minimal.json"),
        arch("wide.json"),
        odd,
        wide,
    ]
}

#[test]
fn timed_triangle_path_is_bit_identical_to_its_functional_model() {
    for (name, side, levels) in [
        ("sphere24.json", 128, &[1u32, 3][..]),
        ("bunny.json", 160, &[1][..]),
    ] {
        let s = scene(name, Some(side));
        for &n in levels {
            for datapath in [Datapath::F32, Datapath::F64] {
                let f = functional(&s, n, datapath, false);
                assert!(
                    f.counts.fragments > 1000,
                    "{name}: the scene draws something"
                );
                for a in matrix() {
                    let t = timed(&s, n, &a, datapath);
                    let what = format!("{name} n={n} {datapath:?} arch {}", a.name);
                    assert!(t.framebuffer.color == f.framebuffer.color, "{what}: colour");
                    assert!(t.framebuffer.depth == f.framebuffer.depth, "{what}: depth");
                    assert_eq!(t.counts.triangles, f.counts.triangles, "{what}");
                    assert_eq!(t.counts.quads, f.counts.quads, "{what}");
                    assert_eq!(t.counts.fragments, f.counts.fragments, "{what}");
                    for u in &t.cycles.units {
                        assert_eq!(u.busy + u.starved + u.blocked, t.cycles.total, "{what}");
                    }
                }
            }
        }
    }
}

#[test]
fn clipped_triangles_are_drawn_the_same_timed_and_functional_and_cost_their_pieces() {
    // traces/extremes/huge.json: every triangle has a vertex up to 10^6 pixels away.
    let s = scene("extremes/huge.json", None);
    let view = View::new(&s.camera, s.viewport);
    for n in [1, 2] {
        for datapath in [Datapath::F32, Datapath::F64] {
            let fan = match datapath {
                Datapath::F32 => fans::<f32>(&s, n, &view),
                Datapath::F64 => fans::<f64>(&s, n, &view),
            };
            let f = functional(&s, n, datapath, true);
            // Every triangle has a vertex beyond the guard band: it is clipped, or culled
            // beside the viewport.
            let c = &f.counts;
            assert!(c.triangles_clipped >= 1, "n={n}: {c:?}");
            assert_eq!(
                c.triangles_clipped + c.triangles_culled_outside,
                c.triangles
            );
            assert_eq!(f.counts.pixels_covered, s.viewport.pixels() as u64, "n={n}");
            assert_eq!(f.probe.unwrap().double_hit_pixels, 0);
            for mut a in matrix() {
                for per_piece in [1, 3] {
                    a.triangle_setup.cycles_per_clipped_piece = per_piece;
                    let t = timed(&s, n, &a, datapath);
                    let what = format!("n={n} {datapath:?} arch {} per piece {per_piece}", a.name);
                    assert!(t.framebuffer.color == f.framebuffer.color, "{what}: colour");
                    assert!(t.framebuffer.depth == f.framebuffer.depth, "{what}: depth");
                    assert_eq!(t.counts.triangles_clipped, f.counts.triangles_clipped);
                    assert_eq!(t.counts.quads, f.counts.quads, "{what}");
                    assert_eq!(t.counts.fragments, f.counts.fragments, "{what}");
                    let setup = &t.cycles.units[1];
                    assert_eq!(setup.kind, UnitKind::TriangleSetup);
                    let per_triangle = a.triangle_setup.cycles_per_triangle;
                    assert_eq!(
                        setup.busy.0,
                        f.counts.triangles * per_triangle + fan * per_piece,
                        "{what}"
                    );
                }
            }
        }
    }
}

#[test]
fn triangle_path_instantiates_only_triangle_units_and_is_deterministic() {
    let s = scene("sphere24.json", Some(96));
    let a = ArchConfig::default();
    let first = timed(&s, 2, &a, Datapath::F32);
    let kinds: Vec<UnitKind> = first.units.iter().map(|u| u.kind).collect();
    assert_eq!(
        kinds,
        [
            UnitKind::GeometryFetch,
            UnitKind::TriangleSetup,
            UnitKind::TriangleRasterizer,
            UnitKind::Rop,
            UnitKind::Rop,
            UnitKind::Rop,
            UnitKind::Rop,
            UnitKind::FrameBuffer
        ]
    );
    for _ in 0..3 {
        let again = timed(&s, 2, &a, Datapath::F32);
        assert_eq!(again.cycles, first.cycles);
        assert_eq!(again.counts, first.counts);
    }
    // Two rasterizers never make the frame slower than one.
    let mut two = a.clone();
    two.triangle_rasterizer.count = 2;
    assert!(timed(&s, 2, &two, Datapath::F32).cycles.total <= first.cycles.total);
}

#[test]
fn silhouette_error_falls_roughly_as_one_over_n_squared() {
    // The sphere's chords: the sagitta of an edge shrinks as 1/n² (1/n would halve the
    // error per doubling; this asks for clearly more).
    let s = scene("sphere24.json", None);
    let view = View::new(&s.camera, s.viewport);
    let (reference, _) = render_reference(&s, &view, 1, lembo_sim::camera::Samples::ONE);
    let err: Vec<f64> = [1, 2, 4]
        .iter()
        .map(|&n| {
            let f = functional(&s, n, Datapath::F32, true);
            let a = measure_frame(
                &s,
                &view,
                &f,
                &reference,
                PrimitivePath::Triangle,
                n as u64 * n as u64,
                Default::default(),
            );
            assert_eq!(a.crack_pixels, 0, "n={n}: a watertight tessellation");
            a.silhouette_max_px
        })
        .collect();
    assert!(err[0] > 10.0, "{err:?}: 24 flat triangles are far off");
    assert!(err[0] / err[1] >= 2.5 && err[1] / err[2] >= 2.5, "{err:?}");
}

#[test]
fn a_mesh_at_level_one_is_drawn_as_its_own_triangles() {
    let s = scene("bunny.json", Some(256));
    let t = Tessellation::new(s.lembo_sets(), 1);
    let mesh = s.objects[0].mesh().unwrap();
    assert_eq!(t.len(), mesh.triangles.len() as u64);
    assert_eq!(t.vertex_count(), mesh.positions.len() as u64);
    let f = functional(&s, 1, Datapath::F32, true);
    assert_eq!(f.counts.triangles, 3674);
    assert_eq!(f.probe.unwrap().double_hit_pixels, 0);
}
