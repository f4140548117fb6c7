//! Model only what a scene requires (DESIGN.md §3, issue 7): primitives off-screen cost their
//! cull test and nothing downstream, and each path instantiates only its own units and
//! buffers, as report.json's `units` and `memory` say.

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::discoid::run_discoid_timed;
use lembo_sim::pipeline::SimOptions;
use lembo_sim::pipeline::{run_timed, Source, TimedFrame, UnitKind};
use lembo_sim::scene::Scene;
use std::path::Path;

use crate::support::scenes;

/// A timed frame on the default architecture: the lembo path, or the triangle path at
/// tessellation `tess`.
fn timed(s: &Scene, tess: Option<u32>) -> TimedFrame {
    let view = View::new(&s.camera, s.viewport);
    let t = tess.map(|n| Tessellation::new(s.lembo_sets(), n));
    let a = ArchConfig::default();
    let source = t.as_ref().map_or(Source::Lembos, |t| Source::Triangles(t));
    run_timed(
        s,
        &view,
        0.5,
        Datapath::F32,
        &a,
        source,
        &SimOptions::default(),
    )
    .unwrap()
}

#[test]
fn off_screen_primitives_cost_only_their_fetch_and_cull_test() {
    let visible = scenes::with_offscreen_copies(0, 128);
    let mostly_off = scenes::with_offscreen_copies(9, 128); // 216 of 240 lembos, 90 %, off-screen
    for (name, a, b) in [
        ("lembo", timed(&visible, None), timed(&mostly_off, None)),
        (
            "triangle",
            timed(&visible, Some(2)),
            timed(&mostly_off, Some(2)),
        ),
    ] {
        assert!(
            a.framebuffer.color == b.framebuffer.color,
            "{name}: same image"
        );
        // The frame takes longer by at most what reading and culling the off-screen
        // primitives take.
        let front = |t: &TimedFrame| -> u64 {
            t.cycles
                .units
                .iter()
                .filter(|u| {
                    matches!(
                        u.kind,
                        UnitKind::GeometryFetch | UnitKind::Setup | UnitKind::TriangleSetup
                    )
                })
                .map(|u| u.busy.0)
                .sum()
        };
        assert!(
            b.cycles.total.0 <= a.cycles.total.0 + (front(&b) - front(&a)),
            "{name}: the frame's cycles {} against {}",
            b.cycles.total,
            a.cycles.total
        );
        assert_eq!(a.counts.fragments, b.counts.fragments, "{name}");
        // Everything after the cull sees only the visible primitives; the memory port
        // also reads them all for the fetch.
        let reads = |t: &TimedFrame| -> u64 {
            t.cycles
                .units
                .iter()
                .filter(|u| u.kind == UnitKind::GeometryFetch)
                .map(|u| u.busy.0)
                .sum()
        };
        for (ua, ub) in a.cycles.units.iter().zip(&b.cycles.units) {
            if ua.kind == UnitKind::FrameBuffer {
                assert_eq!(ua.items_in, ub.items_in, "{name}: {}", ua.name);
                assert_eq!(ua.busy.0 - reads(&a), ub.busy.0 - reads(&b), "{name}");
            } else if !matches!(
                ua.kind,
                UnitKind::GeometryFetch | UnitKind::Setup | UnitKind::TriangleSetup
            ) {
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
    let s = scenes::with_offscreen_copies(0, 128);
    let kinds = |t: &TimedFrame| -> Vec<UnitKind> { t.units.iter().map(|u| u.kind).collect() };
    let lembo = kinds(&timed(&s, None));
    for k in [
        UnitKind::TriangleSetup,
        UnitKind::TriangleRasterizer,
        UnitKind::BlendUnit,
    ] {
        assert!(!lembo.contains(&k), "lembo path has no {k:?}");
    }
    let tri = kinds(&timed(&s, Some(1)));
    for k in [
        UnitKind::Setup,
        UnitKind::Segmenter,
        UnitKind::FragmentRasterizer,
        UnitKind::BlendUnit,
    ] {
        assert!(!tri.contains(&k), "triangle path has no {k:?}");
    }
    // A scene without primitives instantiates nothing.
    let mut empty = scenes::with_offscreen_copies(0, 128);
    empty.objects.clear();
    assert!(timed(&empty, None).units.is_empty());
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

/// An architecture whose links all differ in depth (so a link counted at the wrong
/// boundary changes the total) and whose unit counts are not the baseline's.
const MEMORY_ARCH: &str = r#"{"name": "memory",
  "segmenter": {"count": 3}, "subsegmenter": {"count": 2}, "rasterizer": {"count": 5},
  "rop": {"count": 2}, "triangle_rasterizer": {"count": 3},
  "links": {"setup_to_minmax": {"fifo_depth": 3},
            "minmax_to_interval_manager": {"fifo_depth": 5},
            "interval_manager_to_segmenter": {"fifo_depth": 7},
            "segmenter_to_subsegmenter": {"fifo_depth": 11},
            "subsegmenter_to_rasterizer": {"fifo_depth": 13},
            "rasterizer_to_rop": {"fifo_depth": 17},
            "rop_to_framebuffer": {"fifo_depth": 19},
            "triangle_setup_to_rasterizer": {"fifo_depth": 23},
            "triangle_rasterizer_to_rop": {"fifo_depth": 29}}}"#;
/// The lembo path's links: Setup→MinMax 1×1×3, MinMax→IntervalManager 1×1×5,
/// IntervalManager→Segmenter 1×3×7, Segmenter→Subsegmenter 3×2×11,
/// Subsegmenter→FragmentRasterizer 2×5×13, FragmentRasterizer→Rop 5×2×17, Rop→FrameBuffer
/// 2×1×19, and GeometryFetch→Setup 1×1×4 (its default).
const LEMBO_FIFO_ENTRIES: u64 = 3 + 5 + 21 + 66 + 130 + 170 + 38 + 4;
/// The triangle path's: TriangleSetup→TriangleRasterizer 1×3×23, TriangleRasterizer→Rop
/// 3×2×29, Rop→FrameBuffer 2×1×19, and GeometryFetch→TriangleSetup 1×1×4 (its default).
const TRIANGLE_FIFO_ENTRIES: u64 = 69 + 174 + 38 + 4;

/// `render` with `args` on a scene of `traces/` at 96 x 64 px; its report.json.
fn report(trace: &str, args: &[&str]) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let arch = dir.path().join("memory.json");
    std::fs::write(&arch, MEMORY_ARCH).unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("traces")
        .join(trace);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_lembo-sim"))
        .arg("render")
        .arg(&scene)
        .args(["--viewport", "96x64", "--out"])
        .arg(dir.path().join("o"))
        .args(args)
        .args(if args.contains(&"functional") {
            vec![]
        } else {
            vec!["--arch".to_string(), arch.to_string_lossy().into_owned()]
        })
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap()).unwrap()
}

fn unit_kinds(r: &serde_json::Value) -> Vec<String> {
    r["units"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["kind"].as_str().unwrap().to_string())
        .collect()
}

const FRAMEBUFFER_BYTES: u64 = 96 * 64 * (3 + 4 + 4);

#[test]
fn a_lembo_only_scene_has_no_triangle_or_blend_units_and_no_accumulation_buffer() {
    let r = report("sphere24.json", &[]);
    let kinds = unit_kinds(&r);
    for absent in ["TriangleSetup", "TriangleRasterizer", "BlendUnit"] {
        assert!(!kinds.iter().any(|k| k == absent), "{absent} in {kinds:?}");
    }
    let m = &r["memory"];
    assert_eq!(m["accumulation_bytes"], 0);
    assert_eq!(m["framebuffer_bytes"], FRAMEBUFFER_BYTES);
    assert_eq!(m["primitive_bytes"], 24 * 144);
    assert_eq!(m["primitive_bytes"], r["primitives"]["bytes"]);
    assert_eq!(m["fifo_entries"], LEMBO_FIFO_ENTRIES);
    assert_eq!(m["total_bytes"], FRAMEBUFFER_BYTES + 24 * 144);
    assert!(r["blend"].is_null());
    // Functional mode instantiates no links; the buffers are the same.
    let f = report("sphere24.json", &["--mode", "functional"]);
    assert!(f["memory"]["fifo_entries"].is_null());
    assert_eq!(f["memory"]["framebuffer_bytes"], FRAMEBUFFER_BYTES);
    assert_eq!(f["memory"]["accumulation_bytes"], 0);
    if cfg!(target_os = "linux") {
        assert!(r["host"]["peak_rss_bytes"].as_u64().unwrap() > 1 << 20);
    }
}

#[test]
fn the_triangle_path_counts_only_its_own_links() {
    let r = report("sphere24.json", &["--path", "triangle", "--tess", "2"]);
    let m = &r["memory"];
    assert_eq!(m["fifo_entries"], TRIANGLE_FIFO_ENTRIES);
    assert_eq!(m["accumulation_bytes"], 0);
    assert_eq!(m["framebuffer_bytes"], FRAMEBUFFER_BYTES);
    assert_eq!(m["primitive_bytes"], r["primitives"]["bytes"]);
}

#[test]
fn a_discoid_scene_reports_its_accumulation_target() {
    // Half the bytes per fragment (a read and a write) per pixel: 4, 8, 16.
    for (mode, per_pixel) in [("rgba8", 4), ("f16", 8), ("f32", 16)] {
        let r = report("discoid_sphere20.json", &["--blend", mode]);
        let m = &r["memory"];
        let bytes_per_fragment = r["blend"]["bytes_per_fragment"].as_u64().unwrap();
        assert_eq!(bytes_per_fragment, 2 * per_pixel, "{mode}");
        assert_eq!(m["accumulation_bytes"], 96 * 64 * per_pixel, "{mode}");
        assert_eq!(
            m["accumulation_bytes"], r["blend"]["accumulation_buffer_bytes"],
            "{mode}"
        );
        assert_eq!(m["framebuffer_bytes"], FRAMEBUFFER_BYTES);
        // Curved discoids take the lembo path; blend units add no links.
        assert!(unit_kinds(&r).iter().any(|k| k == "BlendUnit"));
        assert_eq!(m["fifo_entries"], LEMBO_FIFO_ENTRIES, "{mode}");
    }
}
