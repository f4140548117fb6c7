//! Model only what a scene requires (DESIGN §3, issue 7): primitives off-screen cost their
//! cull test and nothing downstream, and each path instantiates only its own units and
//! buffers.

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::actor::SimOptions;
use lembo_sim::pipeline::discoid::run_discoid_timed;
use lembo_sim::pipeline::{run_timed, TimedFrame, UnitKind};
use lembo_sim::scene::Scene;
use std::path::Path;

/// sphere24 in view, then `copies` more far to the side, out of the viewport.
fn scene_with_offscreen(copies: usize) -> Scene {
    let mut objects = vec![r#"{"builtin": "sphere24", "color": [0.8, 0.3, 0.2]}"#.to_string()];
    for c in 0..copies {
        objects.push(format!(
            r#"{{"builtin": "sphere24", "transform": {{"translate": [{}, 0, 0]}}}}"#,
            40.0 + 5.0 * c as f64
        ));
    }
    let json = format!(
        r#"{{"name": "offscreen", "viewport": {{"width": 128, "height": 128}},
            "camera": {{"eye": [0, 1.2, 3.8], "target": [0, 0, 0],
                        "projection": {{"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100}}}},
            "objects": [{}]}}"#,
        objects.join(", ")
    );
    Scene::from_json(&json, "offscreen", Path::new(".")).unwrap()
}

fn lembo_path(s: &Scene) -> TimedFrame {
    let view = View::new(&s.camera, s.viewport);
    let a = ArchConfig::default();
    run_timed(
        s,
        &view,
        0.5,
        Datapath::F32,
        &a,
        None,
        &SimOptions::default(),
    )
    .unwrap()
}

fn triangle_path(s: &Scene, n: u32) -> TimedFrame {
    let view = View::new(&s.camera, s.viewport);
    let t = Tessellation::new(s, n);
    let a = ArchConfig::default();
    run_timed(
        s,
        &view,
        0.5,
        Datapath::F32,
        &a,
        Some(&t),
        &SimOptions::default(),
    )
    .unwrap()
}

#[test]
fn off_screen_primitives_cost_their_cull_test_and_no_frame_cycles() {
    let visible = scene_with_offscreen(0);
    let mostly_off = scene_with_offscreen(9); // 216 of 240 lembos, 90 %, off-screen
    for (name, a, b) in [
        ("lembo", lembo_path(&visible), lembo_path(&mostly_off)),
        (
            "triangle",
            triangle_path(&visible, 2),
            triangle_path(&mostly_off, 2),
        ),
    ] {
        assert!(
            a.framebuffer.color == b.framebuffer.color,
            "{name}: same image"
        );
        assert_eq!(a.cycles.total, b.cycles.total, "{name}: the frame's cycles");
        assert_eq!(a.counts.fragments, b.counts.fragments, "{name}");
        // Everything after the cull sees only the visible primitives.
        for (ua, ub) in a.cycles.units.iter().zip(&b.cycles.units) {
            if !matches!(ua.kind, UnitKind::Setup | UnitKind::TriangleSetup) {
                assert_eq!(ua.items_in, ub.items_in, "{name}: {}", ua.name);
                assert_eq!(ua.busy, ub.busy, "{name}: {}", ua.name);
            }
        }
        let culled = b.counts.lembos_culled_outside + b.counts.triangles_culled_outside;
        assert!(culled > 0, "{name}: the off-screen primitives were culled");
    }
}

#[test]
fn each_path_instantiates_only_its_own_units_and_buffers() {
    let s = scene_with_offscreen(0);
    let kinds = |t: &TimedFrame| -> Vec<UnitKind> { t.units.iter().map(|u| u.kind).collect() };
    let lembo = kinds(&lembo_path(&s));
    for k in [
        UnitKind::TriangleSetup,
        UnitKind::TriangleRasterizer,
        UnitKind::BlendUnit,
    ] {
        assert!(!lembo.contains(&k), "lembo path has no {k:?}");
    }
    let tri = kinds(&triangle_path(&s, 1));
    for k in [
        UnitKind::Setup,
        UnitKind::Segmenter,
        UnitKind::FragmentRasterizer,
        UnitKind::BlendUnit,
    ] {
        assert!(!tri.contains(&k), "triangle path has no {k:?}");
    }
    // A scene without primitives instantiates nothing.
    let mut empty = scene_with_offscreen(0);
    empty.objects.clear();
    assert!(lembo_path(&empty).units.is_empty());
    // Blend units and their accumulation buffer exist with discoids only.
    let mut d =
        Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("traces/discoid_sphere20.json"))
            .unwrap();
    d.set_viewport(64, 64).unwrap();
    let view = View::new(&d.camera, d.viewport);
    let a = ArchConfig::default();
    let t = run_discoid_timed(
        &d,
        &view,
        0.5,
        Datapath::F32,
        &a,
        BlendMode::Rgba8,
        0.2,
        &SimOptions::default(),
    )
    .unwrap();
    let blenders = t
        .units
        .iter()
        .filter(|u| u.kind == UnitKind::BlendUnit)
        .count();
    assert_eq!(blenders, a.rop.count as usize);
    assert_eq!(t.blend.accumulation_buffer_bytes, 64 * 64 * 4);
}
