//! The cost model: counting changes no pixel, the counts are the ones a hand-worked lembo
//! gives and every shipped scene's are kept as a golden, and a timed report prices every
//! unit it instantiates, a discoid scene's blend units per precision mode included.

use crate::support::binary::{files_in, run};
use crate::support::{golden, scenes};
use lembo_sim::camera::View;
use lembo_sim::config::{ArchConfig, Reciprocal};
use lembo_sim::cost::built::as_built;
use lembo_sim::cost::tech::{DramKind, Tech};
use lembo_sim::cost::{discoid_ops, lembo_ops, triangle_ops};
use lembo_sim::datapath::Datapath;
use lembo_sim::datapath::{Op, EVENTS, OPS};
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::frame::discoid::render_discoids_functional;
use lembo_sim::frame::{render_functional, render_functional_triangles};
use lembo_sim::graph::{UnitKind, KINDS};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::discoid::run_discoid_timed;
use lembo_sim::pipeline::SimOptions;
use lembo_sim::scene::Scene;

fn scenes() -> Vec<Scene> {
    [
        "traces/sphere24.json",
        "traces/bunny.json",
        "traces/near_camera.json",
    ]
    .iter()
    .map(|p| Scene::load(std::path::Path::new(p)).expect(p))
    .collect()
}

/// The counting datapath does the same IEEE operations: every pixel, depth and winner of
/// both paths, in both precisions, equals the plain run's.
#[test]
fn counting_changes_no_pixel() {
    for scene in scenes() {
        let view = View::new(&scene.camera, scene.viewport);
        for dp in [Datapath::F32, Datapath::F64] {
            let plain = render_functional(&scene, &view, 0.5, dp, false).unwrap();
            let (counted, ops) = lembo_ops(&scene, &view, 0.5, dp).unwrap();
            assert!(
                plain.framebuffer.color == counted.framebuffer.color,
                "{}",
                scene.name
            );
            assert!(plain.framebuffer.depth == counted.framebuffer.depth);
            assert_eq!(plain.counts, counted.counts);
            assert!(ops.get(UnitKind::Segmenter, Op::Mul) > 0);
            assert_eq!(ops.get(UnitKind::Setup, Op::Other), 0);
            let tess = Tessellation::new(scene.lembo_sets(), 2);
            let plain = render_functional_triangles(&scene, &view, &tess, dp, false);
            let (counted, ops) = triangle_ops(&scene, &view, &tess, dp);
            assert!(plain.framebuffer.color == counted.framebuffer.color);
            assert!(ops.get(UnitKind::TriangleRasterizer, Op::IntMul) > 0);
        }
    }
}

/// Counting changes no pixel of a discoid scene either, curved (the lembo path) or planar
/// (the triangle path), in any blend mode or datapath; the blend units are charged what
/// the blend does, the ROP the passes' fragments and the resolve, and nothing is charged
/// to a kind the scene does not instantiate.
#[test]
fn counting_changes_no_discoid_pixel() {
    for (name, path) in [
        ("discoid_sphere20.json", UnitKind::FragmentRasterizer),
        ("surfels_bunny.json", UnitKind::TriangleRasterizer),
    ] {
        let scene = scenes::trace(name, Some(96));
        let view = View::new(&scene.camera, scene.viewport);
        let t = scene.discoid_threshold;
        for dp in [Datapath::F32, Datapath::F64] {
            for mode in BlendMode::ALL {
                let what = format!("{name} {dp:?} {mode:?}");
                let plain = render_discoids_functional(&scene, &view, 0.5, dp, mode, t).unwrap();
                let (counted, ops) = discoid_ops(&scene, &view, 0.5, dp, (mode, t)).unwrap();
                assert!(
                    plain.framebuffer.color == counted.framebuffer.color,
                    "{what}"
                );
                assert_eq!(plain.blend, counted.blend, "{what}");
                assert!(plain.blend.fragments_accumulated > 100, "{what}");
                for kind in KINDS {
                    let total: u64 = ops.of(kind).iter().sum();
                    let on_path = match path {
                        UnitKind::FragmentRasterizer => !matches!(
                            kind,
                            UnitKind::TriangleSetup
                                | UnitKind::TriangleRasterizer
                                | UnitKind::Tessellator
                                | UnitKind::DomainEval
                        ),
                        _ => matches!(
                            kind,
                            UnitKind::TriangleSetup
                                | UnitKind::TriangleRasterizer
                                | UnitKind::Rop
                                | UnitKind::BlendUnit
                        ),
                    };
                    let charged =
                        on_path && !matches!(kind, UnitKind::FrameBuffer | UnitKind::GeometryFetch);
                    assert_eq!(total > 0, charged, "{what} {kind:?}: {:?}", ops.of(kind));
                    assert_eq!(ops.get(kind, Op::Other), 0, "{what} {kind:?}");
                }
                let blend = ops.of(UnitKind::BlendUnit);
                assert!(blend[Op::Mul as usize] > 0 && blend[Op::Div as usize] > 0);
                // rgba8's nibble sums are the blend unit's integer adds; the float modes
                // have none.
                assert_eq!(
                    blend[Op::IntAdd as usize] > 0,
                    mode == BlendMode::Rgba8,
                    "{what}"
                );
            }
        }
    }
}

/// The bytes a discoid frame is priced for are the bytes its passes moved through the
/// frame-buffer port: at one byte a cycle, the port is busy exactly as many cycles. And
/// the counting run draws the timed image.
#[test]
fn discoid_port_bytes_are_the_ports_traffic() {
    let mut arch = ArchConfig::default();
    arch.framebuffer.bytes_per_cycle = 1;
    for name in ["discoid_sphere20.json", "surfels_bunny.json"] {
        let scene = scenes::trace(name, Some(96));
        let view = View::new(&scene.camera, scene.viewport);
        let t = scene.discoid_threshold;
        for mode in BlendMode::ALL {
            let timed = run_discoid_timed(
                &scene,
                &view,
                0.5,
                Datapath::F32,
                &arch,
                mode,
                t,
                &SimOptions::default(),
            )
            .unwrap();
            let port = timed
                .cycles
                .units
                .iter()
                .find(|u| u.kind == UnitKind::FrameBuffer)
                .unwrap();
            let bytes = timed.port_bytes;
            // One memory port: the ROPs' traffic and the geometry fetch's reads.
            assert_eq!(
                port.busy.0,
                bytes.framebuffer + bytes.accumulation + bytes.geometry,
                "{name} {mode:?}"
            );
            assert!(bytes.geometry > 0);
            let pixels = 96 * 96;
            assert_eq!(
                bytes.accumulation,
                timed.blend.fragments_accumulated * 2 * mode.bytes_per_pixel()
                    + pixels * mode.bytes_per_pixel(),
                "{name} {mode:?}"
            );
            // Each blend unit is busy at its mode's rate for the fragments its ROP kept.
            let blended: u64 = timed.blend_units.iter().map(|u| u.items_in).sum();
            assert_eq!(blended, timed.blend.fragments_accumulated);
            assert_eq!(timed.blend_units.len(), arch.rop.count as usize);
            for u in &timed.blend_units {
                let rate = match mode {
                    BlendMode::Rgba8 => arch.blend.cycles_per_fragment_rgba8,
                    BlendMode::F16 => arch.blend.cycles_per_fragment_f16,
                    BlendMode::F32 => arch.blend.cycles_per_fragment_f32,
                };
                assert_eq!(u.busy.0, u.items_in * rate);
                assert_eq!(u.busy + u.starved + u.blocked, timed.cycles.total);
            }
            let (counted, _) = discoid_ops(&scene, &view, 0.5, Datapath::F32, (mode, t)).unwrap();
            assert!(counted.framebuffer.color == timed.framebuffer.color);
        }
    }
}

/// A discoid scene's timed report has a cost like every timed run, in every blend mode:
/// blend units with area and energy, priced at the width of the words the mode stores,
/// and the accumulation target's bytes at the DRAM figure beside the frame buffer's. The
/// paper's trade holds: rgba8's blend units are smaller and spend less per fragment than
/// f16's, and those than f32's, and so do their accumulation bytes.
#[test]
fn a_discoid_timed_report_prices_its_blend_units_per_mode() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut blend = Vec::new();
    for mode in ["rgba8", "f16", "f32"] {
        let out = temp_dir(&format!("blend-{mode}"));
        let o = run(
            &[
                "render",
                "traces/discoid_sphere20.json",
                "--viewport",
                "128x128",
                "--blend",
                mode,
                "--out",
                out.to_str().unwrap(),
            ],
            root,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = report(&out);
        let cost = &r["cost"];
        let units = cost["units"].as_array().unwrap();
        // Every listed instance is priced, the blend units among them.
        let names: Vec<&str> = r["units"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u["name"].as_str().unwrap())
            .collect();
        let priced: Vec<&str> = units.iter().map(|u| u["name"].as_str().unwrap()).collect();
        assert_eq!(names, priced, "{mode}");
        let blend_units: Vec<_> = units
            .iter()
            .filter(|u| u["name"].as_str().unwrap().starts_with("BlendUnit["))
            .collect();
        assert_eq!(blend_units.len(), 4, "{mode}");
        for u in &blend_units {
            assert!(u["area_mm2"].as_f64().unwrap() > 0.0, "{mode}: {u}");
            assert!(u["energy_pj"].as_f64().unwrap() > 0.0, "{mode}: {u}");
            assert_eq!(
                u["fifo_area_mm2"], 0.0,
                "inside its ROP: no FIFO of its own"
            );
        }
        let area: f64 = units.iter().map(|u| u["area_mm2"].as_f64().unwrap()).sum();
        let energy: f64 = units.iter().map(|u| u["energy_pj"].as_f64().unwrap()).sum();
        assert!((area - cost["area_mm2"].as_f64().unwrap()).abs() < 1e-9);
        assert!((energy - cost["energy_pj"].as_f64().unwrap()).abs() < 1e-6 * energy);
        let b = &cost["blend"];
        assert_eq!(b["mode"], mode);
        let (priced_as, bpp) = match mode {
            "rgba8" => ("int8", 4),
            "f16" => ("f16", 8),
            _ => ("f32", 16),
        };
        assert_eq!(b["priced_as"], priced_as);
        assert_eq!(b["accumulation_bytes_per_pixel"], bpp);
        let kept = r["blend"]["fragments_accumulated"].as_u64().unwrap();
        assert_eq!(b["fragments"], kept);
        assert_eq!(
            cost["accumulation_bytes"].as_u64().unwrap(),
            kept * 2 * bpp + 128 * 128 * bpp,
            "{mode}: a read and a write per fragment, the resolve's read per pixel"
        );
        let fb = units.iter().find(|u| u["name"] == "FrameBuffer").unwrap();
        let dram = (cost["framebuffer_bytes"].as_f64().unwrap()
            + cost["accumulation_bytes"].as_f64().unwrap())
            * cost["tech"]["dram_pj_per_byte"].as_f64().unwrap();
        let fifo = fb["fifo_energy_pj"].as_f64().unwrap() + fb["fifo_leakage_pj"].as_f64().unwrap();
        assert!((fb["energy_pj"].as_f64().unwrap() - fifo - dram).abs() < 1e-6 * dram);
        let text = std::fs::read_to_string(out.join("report.txt")).unwrap();
        assert!(
            text.contains(&format!("blend units {mode} (priced as {priced_as})")),
            "{text}"
        );
        blend.push(b.clone());
        let _ = std::fs::remove_dir_all(&out);
    }
    let f = |b: &serde_json::Value, k: &str| b[k].as_f64().unwrap();
    for pair in blend.windows(2) {
        let (narrow, wide) = (&pair[0], &pair[1]);
        let what = format!("{} against {}", narrow["mode"], wide["mode"]);
        assert!(f(narrow, "area_mm2") < f(wide, "area_mm2"), "{what}");
        assert!(
            f(narrow, "energy_pj_per_fragment") < f(wide, "energy_pj_per_fragment"),
            "{what}"
        );
        assert!(
            f(narrow, "accumulation_energy_pj") < f(wide, "accumulation_energy_pj"),
            "{what}"
        );
    }
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lembo-cost-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn report(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

/// A timed report prices every unit it instantiates, and the parts add up: the total area
/// and energy are the units' sums, a FIFO's share is within its unit's, every FIFO bit
/// leaks 100 mW per MB over the frame, and the frame buffer's energy is its bytes at the
/// DDR4 figure, its FIFO's traffic and its FIFO's leakage.
#[test]
fn a_timed_report_prices_every_unit() {
    let root = env!("CARGO_MANIFEST_DIR");
    for path in ["lembo", "triangle"] {
        let out = temp_dir(path);
        let o = run(
            &[
                "render",
                "traces/sphere24.json",
                "--path",
                path,
                "--out",
                out.to_str().unwrap(),
            ],
            std::path::Path::new(root),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = report(&out);
        let cost = &r["cost"];
        let units = cost["units"].as_array().unwrap();
        assert_eq!(units.len(), r["cycles"]["units"].as_array().unwrap().len());
        let area: f64 = units.iter().map(|u| u["area_mm2"].as_f64().unwrap()).sum();
        let energy: f64 = units.iter().map(|u| u["energy_pj"].as_f64().unwrap()).sum();
        assert!((area - cost["area_mm2"].as_f64().unwrap()).abs() < 1e-9);
        assert!((energy - cost["energy_pj"].as_f64().unwrap()).abs() < 1e-6 * energy);
        for u in units {
            assert!(u["fifo_area_mm2"].as_f64().unwrap() <= u["area_mm2"].as_f64().unwrap());
            assert!(u["energy_pj"].as_f64().unwrap() > 0.0, "{u}");
        }
        let tech = &cost["tech"];
        assert_eq!(tech["name"], "45nm");
        assert_eq!(tech["dram_kind"], "ddr4");
        assert_eq!(tech["dram_pj_per_byte"], 162.5);
        // µs of the frame, and each unit's FIFO bits from their area (0.69 µm² a bit).
        let cycles = &r["cycles"];
        let frame_us = cycles["total"].as_f64().unwrap() / cycles["clock_mhz"].as_f64().unwrap();
        let mut leakage = 0.0;
        for u in units {
            let bits = u["fifo_area_mm2"].as_f64().unwrap() * 1e6 / 0.69;
            let expected = 100.0 * bits / (8.0 * 1048576.0) * frame_us * 1e3;
            let got = u["fifo_leakage_pj"].as_f64().unwrap();
            assert!((got - expected).abs() <= 1e-9 * expected, "{u}");
            leakage += got;
        }
        assert!(leakage > 0.0);
        assert!((cost["sram_leakage_pj"].as_f64().unwrap() - leakage).abs() < 1e-9 * leakage);
        assert_eq!(cost["logic_leakage_pj"], 0.0);
        let fb = units.iter().find(|u| u["name"] == "FrameBuffer").unwrap();
        let dram = cost["framebuffer_bytes"].as_f64().unwrap() * 162.5;
        let fifo = fb["fifo_energy_pj"].as_f64().unwrap() + fb["fifo_leakage_pj"].as_f64().unwrap();
        assert!((fb["energy_pj"].as_f64().unwrap() - fifo - dram).abs() < 1e-6 * dram);
        let text = std::fs::read_to_string(out.join("report.txt")).unwrap();
        assert!(text.contains("\ncost      "), "{text}");
        assert!(
            text.contains("as ddr4 DRAM at 162.5 pJ/B; SRAM leakage "),
            "{text}"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
}

/// Every kind of the lembo path is charged something, and nothing is charged to kinds the
/// path does not have.
#[test]
fn operations_are_charged_to_the_kinds_that_do_them() {
    let scene = Scene::load(std::path::Path::new("traces/bunny.json")).unwrap();
    let view = View::new(&scene.camera, scene.viewport);
    let (_, ops) = lembo_ops(&scene, &view, 0.5, Datapath::F32).unwrap();
    for kind in KINDS {
        let total: u64 = ops.of(kind).iter().sum();
        let expected = !matches!(
            kind,
            UnitKind::TriangleSetup
                | UnitKind::TriangleRasterizer
                | UnitKind::Tessellator
                | UnitKind::DomainEval
                | UnitKind::BlendUnit
                | UnitKind::FrameBuffer
                | UnitKind::GeometryFetch
        );
        assert_eq!(total > 0, expected, "{kind:?}: {:?}", ops.of(kind));
        assert_eq!(ops.get(kind, Op::Other), 0);
        assert_eq!(ops.get(kind, Op::IntMul), 0);
    }
    assert_eq!(OPS.len(), 9);
}

/// Every kind's operation counts as priced (the units built differently from the model as
/// built, at the default reciprocal per quad), as text: a line a kind that counts any, and
/// a line of the triangle rasterizer's walk events when it walked any.
fn digest(ops: &lembo_sim::cost::counted::OpTable) -> String {
    // No vertex reuse: the counting run's own account.
    let priced = as_built(ops, Reciprocal::Quad, 0);
    let mut text: String = KINDS
        .iter()
        .filter(|&&k| priced.of(k).iter().any(|&n| n > 0))
        .map(|&k| format!("{k:?} {:?}\n", priced.of(k)))
        .collect();
    let events = EVENTS.map(|e| ops.events(e));
    if events.iter().any(|&n| n > 0) {
        text += &format!("events {events:?}\n");
    }
    text
}

/// The operation counts the cost model prices (every unit kind, every operation) on every
/// shipped surface scene at 128 x 128, the lembo path in both datapaths and the triangle
/// path (n = 2), and every shipped discoid scene's passes in each blend mode, kept as a
/// golden: a change that moves an operation into or out of the
/// counted datapath, or to another kind, changes the energy and area of every report, and
/// must be explained. Regenerate with
/// `LEMBO_BLESS=1 cargo test --release --test integration cost::` only after an intended
/// change of what the hardware computes.
#[test]
fn shipped_scenes_keep_their_operation_counts() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut got = std::collections::BTreeMap::new();
    for (name, path) in &scenes::shipped_files() {
        let mut scene = Scene::load(path).unwrap();
        scene.set_viewport(128, 128).unwrap();
        let view = View::new(&scene.camera, scene.viewport);
        if scene.discoid_count() > 0 {
            // Both passes, the blend in each mode and the resolve.
            for mode in BlendMode::ALL {
                let blend = (mode, scene.discoid_threshold);
                let ops = match discoid_ops(&scene, &view, 0.5, Datapath::F32, blend) {
                    Ok((_, ops)) => digest(&ops),
                    Err(e) => format!("error: {e}"),
                };
                got.insert(format!("{name} discoid {} F32", mode.name()), ops);
            }
            continue;
        }
        for dp in [Datapath::F32, Datapath::F64] {
            let ops = match lembo_ops(&scene, &view, 0.5, dp) {
                Ok((_, ops)) => digest(&ops),
                Err(e) => format!("error: {e}"),
            };
            got.insert(format!("{name} lembo {dp:?}"), ops);
        }
        let tess = Tessellation::new(scene.lembo_sets(), 2);
        let (_, ops) = triangle_ops(&scene, &view, &tess, Datapath::F32);
        got.insert(format!("{name} triangle F32"), digest(&ops));
    }
    golden::check(
        &root.join("tests/golden/ops/shipped.json"),
        got,
        "operation tables",
        &golden::Expect {
            min_cases: 99,
            expected_errors: &[],
            valid: &golden::some_operations,
        },
    );
}

/// Every shipped technology file is valid, and a newer node costs less area and energy
/// for the same frame.
#[test]
fn every_shipped_technology_file_loads() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut names = Vec::new();
    for entry in std::fs::read_dir(root.join("sim/tech")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let t = lembo_sim::cost::tech::Tech::load(&path).unwrap();
            names.push(t.name);
        }
    }
    names.sort();
    assert_eq!(names, ["45nm", "7nm"]);
    let t45 = lembo_sim::cost::tech::Tech::default_45nm();
    let t7 = lembo_sim::cost::tech::Tech::load(&root.join("sim/tech/7nm.json")).unwrap();
    for op in OPS {
        let (e45, a45) = t45.op(Datapath::F32, op);
        let (e7, a7) = t7.op(Datapath::F32, op);
        assert!(e7 < e45 && a7 < a45, "{op:?}");
    }
    // Jouppi et al. 2021, Table 2: an 8 KB SRAM access of 64 bits, HBM2's range.
    assert_eq!(t7.sram.access_pj_per_64_bits, 7.5);
    assert_eq!(t7.dram.kind, DramKind::Hbm2);
    assert!((250.0..=450.0).contains(&(t7.dram.pj_per_byte * 8.0)));
    assert!(t7.sram.leakage_mw_per_mb < t45.sram.leakage_mw_per_mb);
}

/// A 7 nm frame says which technology and which DRAM priced it, in report.json's
/// `cost.tech` and in report.txt.
#[test]
fn a_report_names_its_technology_and_dram_kind() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = temp_dir("7nm");
    let o = run(
        &[
            "render",
            "traces/sphere24.json",
            "--tech",
            "sim/tech/7nm.json",
            "--out",
            out.to_str().unwrap(),
        ],
        root,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let tech = &report(&out)["cost"]["tech"];
    assert_eq!(tech["name"], "7nm");
    assert_eq!(tech["node_nm"], 7.0);
    assert_eq!(tech["dram_kind"], "hbm2");
    assert_eq!(tech["dram_pj_per_byte"], 43.75);
    let text = std::fs::read_to_string(out.join("report.txt")).unwrap();
    assert!(text.contains("(technology 7nm; "), "{text}");
    assert!(text.contains("as hbm2 DRAM at 43.75 pJ/B"), "{text}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("cost (7nm, hbm2 DRAM)"));
    let _ = std::fs::remove_dir_all(&out);
}

/// A change made to a technology file's JSON.
type Edit = fn(&mut serde_json::Value);

/// A technology file without one of the fields issue 35 added (or with a DRAM kind the
/// simulator does not know) is refused naming the field, exit 2, before any work: nothing
/// is written.
#[test]
fn a_technology_file_without_a_new_field_is_refused_naming_it() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = temp_dir("new-fields");
    let text = std::fs::read_to_string(root.join("sim/tech/45nm.json")).unwrap();
    let edits: [(&str, Edit); 4] = [
        ("leakage_mw_per_mb", |v| {
            v["sram"]
                .as_object_mut()
                .unwrap()
                .remove("leakage_mw_per_mb");
        }),
        ("missing field `kind`", |v| {
            v["dram"].as_object_mut().unwrap().remove("kind");
        }),
        ("`dram.kind`", |v| v["dram"]["kind"] = "gddr6".into()),
        ("logic_leakage", |v| {
            v.as_object_mut().unwrap().remove("logic_leakage");
        }),
    ];
    for (i, (named, edit)) in edits.into_iter().enumerate() {
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        edit(&mut v);
        let bad = dir.join(format!("bad{i}.json"));
        std::fs::write(&bad, v.to_string()).unwrap();
        let out = dir.join(format!("out{i}"));
        let o = run(
            &[
                "render",
                "traces/sphere24.json",
                "--tech",
                bad.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            root,
        );
        assert_eq!(o.status.code(), Some(2), "{named}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(named), "{named}: {err}");
        assert!(files_in(&out).is_empty(), "{named}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A technology file with a bad figure is refused naming the field, exit 2, nothing
/// written; `--tech` in functional mode is refused as `--arch` is.
#[test]
fn a_bad_technology_file_is_refused_naming_the_field() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = temp_dir("bad");
    let text = std::fs::read_to_string(root.join("sim/tech/45nm.json")).unwrap();
    let bad = dir.join("bad.json");
    std::fs::write(&bad, text.replace("\"mul_pj\": 3.7", "\"mul_pj\": -3.7")).unwrap();
    let out = dir.join("out");
    // `render SCENE --tech bad.json` exits 2 naming `field`, and writes nothing.
    let refused = |scene: &str, field: &str| {
        let o = run(
            &[
                "render",
                scene,
                "--tech",
                bad.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            root,
        );
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(field), "{err}");
        assert!(files_in(&out).is_empty());
    };
    refused("traces/sphere24.json", "f32.mul_pj");
    // The blend units' groups are required too: a file from before them is refused,
    // naming the one missing, on a discoid scene as on any other.
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_object_mut().unwrap().remove("int8");
    std::fs::write(&bad, v.to_string()).unwrap();
    refused("traces/discoid_sphere20.json", "int8");
    let o = run(
        &[
            "render",
            "traces/sphere24.json",
            "--mode",
            "functional",
            "--tech",
            "sim/tech/45nm.json",
            "--out",
            out.to_str().unwrap(),
        ],
        root,
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--tech"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `render SCENE --path triangle` with `extra` arguments into a fresh folder: its report
/// and its image's bytes.
fn triangle_report(name: &str, scene: &str, extra: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = temp_dir(name);
    let mut args = vec!["render", scene, "--path", "triangle", "--out"];
    args.push(out.to_str().unwrap());
    args.extend_from_slice(extra);
    let o = run(&args, root);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&out);
    let image = std::fs::read(out.join("image.png")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    (r, image)
}

/// One kind's priced operations in a report, in [`OPS`] order.
fn kind_ops(r: &serde_json::Value, kind: &str) -> Vec<u64> {
    let k = r["cost"]["ops"]
        .as_array()
        .unwrap()
        .iter()
        .find(|k| k["kind"] == kind)
        .unwrap_or_else(|| panic!("{kind} priced"));
    OPS.iter()
        .map(|op| k[op.name()].as_u64().unwrap())
        .collect()
}

/// `triangle_rasterizer.reciprocal` prices the perspective divide per covered quad (the
/// default) or per covered pixel, and changes nothing else: not the image, not a cycle,
/// not the setup. Per pixel takes one divide a fragment; per quad one a covered quad,
/// and a Newton step (2 multiplies, an add) a fragment.
#[test]
fn the_reciprocal_per_quad_or_per_pixel_is_a_pricing_choice() {
    let dir = temp_dir("reciprocal");
    let arch = dir.join("pixel.json");
    std::fs::write(&arch, r#"{"triangle_rasterizer": {"reciprocal": "pixel"}}"#).unwrap();
    let (quad, quad_image) = triangle_report("recip-quad", "traces/sphere24.json", &[]);
    let (pixel, pixel_image) = triangle_report(
        "recip-pixel",
        "traces/sphere24.json",
        &["--arch", arch.to_str().unwrap()],
    );
    assert_eq!(quad["cycles"], pixel["cycles"]);
    assert_eq!(quad["counts"], pixel["counts"]);
    assert!(quad_image == pixel_image);
    let fragments = quad["counts"]["fragments"].as_u64().unwrap();
    let quads = quad["counts"]["quads"].as_u64().unwrap();
    let (q, p) = (
        kind_ops(&quad, "TriangleRasterizer"),
        kind_ops(&pixel, "TriangleRasterizer"),
    );
    let (add, mul, div) = (Op::Add as usize, Op::Mul as usize, Op::Div as usize);
    assert_eq!(p[div], fragments);
    assert_eq!(q[div], quads);
    assert_eq!(q[mul] - p[mul], 2 * fragments);
    assert_eq!(q[add] - p[add], fragments);
    assert_eq!(
        kind_ops(&quad, "TriangleSetup"),
        kind_ops(&pixel, "TriangleSetup")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// An unknown `triangle_rasterizer.reciprocal` is refused naming the field, exit 2, before
/// anything is written.
#[test]
fn an_unknown_reciprocal_is_refused_naming_the_field() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = temp_dir("bad-reciprocal");
    let arch = dir.join("bad.json");
    std::fs::write(&arch, r#"{"triangle_rasterizer": {"reciprocal": "tile"}}"#).unwrap();
    let out = dir.join("out");
    let o = run(
        &[
            "render",
            "traces/sphere24.json",
            "--arch",
            arch.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        root,
    );
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("triangle_rasterizer.reciprocal"), "{err}");
    assert!(err.contains("`quad` or `pixel`"), "{err}");
    assert!(files_in(&out).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Brunhaver, Fatahalian and Hanrahan (HPG 2010): 3 G micropolygons/s in 4.1 mm² at 2.9 W,
/// 45 nm: area per G micropolygons/s \[mm²\] and energy per micropolygon \[nJ\].
const BRUNHAVER: (f64, f64) = (4.1 / 3.0, 2.9 / 3.0);

/// Issue 35's calibration (RESULTS.md, "Sanity anchor"): the triangle path's setup and
/// rasterizer on a micropolygon frame, the bunny at n = 6 (about one fragment a
/// triangle), against Brunhaver et al., at the rate the two units sustain (triangles over
/// the busier one's busy cycles: the frame itself is bound by the memory port). Energy per
/// triangle stays within 2x of theirs. Area per throughput, sized at the design point
/// (issue 48) rather than for this frame, stays within 4x once the attribute planes are
/// taken out (their unit interpolates nothing: its micropolygons arrive shaded), and within
/// 5x with them.
#[test]
fn a_micropolygon_frame_is_priced_near_brunhaver_et_al() {
    // Calibrated with every triangle set up and rasterized: culling off.
    let nocull = temp_dir("micropolygons_arch").with_extension("json");
    std::fs::write(&nocull, crate::support::NO_CULLING).unwrap();
    let arch = ["--tess", "6", "--arch", nocull.to_str().unwrap()];
    let (r, _) = triangle_report("micropolygons", "traces/bunny.json", &arch);
    let _ = std::fs::remove_file(&nocull);
    let triangles = r["primitives"]["count"].as_f64().unwrap();
    let fragments = r["counts"]["fragments"].as_f64().unwrap();
    assert!(
        (0.8..1.25).contains(&(fragments / triangles)),
        "{fragments} fragments of {triangles} triangles: not micropolygons"
    );
    let cycles = &r["cycles"];
    let busy = cycles["units"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|u| u["kind"].as_str().unwrap().starts_with("Triangle"))
        .map(|u| u["busy"].as_f64().unwrap())
        .fold(0.0, f64::max);
    let seconds = busy / (cycles["clock_mhz"].as_f64().unwrap() * 1e6);
    let g_per_s = triangles / seconds * 1e-9;
    let (mut area, mut energy) = (0.0, 0.0);
    for u in r["cost"]["units"].as_array().unwrap() {
        if u["name"].as_str().unwrap().starts_with("Triangle") {
            area += u["area_mm2"].as_f64().unwrap();
            energy += u["energy_pj"].as_f64().unwrap();
        }
    }
    // The attribute planes' functional units in the one setup engine (one triangle a
    // busy cycle: a unit per operation of the planes' per-triangle account).
    let tech = Tech::default_45nm();
    let planes_um2: f64 = lembo_sim::cost::built::setup_per_triangle()
        .iter()
        .zip(OPS)
        .map(|(&n, op)| n as f64 * tech.op(Datapath::F32, op).1)
        .sum();
    let area_ratio = area / g_per_s / BRUNHAVER.0;
    let coverage_ratio = (area - planes_um2 * 1e-6) / g_per_s / BRUNHAVER.0;
    let energy_ratio = energy / triangles * 1e-3 / BRUNHAVER.1;
    assert!(
        (0.5..=2.0).contains(&energy_ratio),
        "energy a triangle {energy_ratio:.2}x Brunhaver et al."
    );
    // Since issue 48 a unit is sized for its architecture's design point, the most
    // operations a busy cycle over the calibration set (DESIGN.md §12), not for this frame:
    // the triangle setup's is set by n = 1 on chip, three new vertices a triangle, where
    // this frame shares them. Its area per throughput is therefore a worst-case design's,
    // 3.3x theirs without the planes (about 2x when it was this frame's): the bounds below
    // are that design's, and the energy's stays 2x.
    assert!(
        (0.5..=4.0).contains(&coverage_ratio),
        "area per G triangles/s without the planes {coverage_ratio:.2}x Brunhaver et al."
    );
    assert!(
        (0.5..=5.0).contains(&area_ratio),
        "area per G triangles/s {area_ratio:.2}x Brunhaver et al."
    );
    eprintln!(
        "micropolygons: {g_per_s:.3} G triangles/s, {area:.3} mm2, area {area_ratio:.2}x \
         ({coverage_ratio:.2}x without the planes), energy {energy_ratio:.2}x"
    );
}
