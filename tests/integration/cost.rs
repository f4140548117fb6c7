//! The cost model: counting changes no pixel, the counts are the ones a hand-worked lembo
//! gives and every shipped scene's are kept as a golden, and a timed report prices every
//! unit it instantiates.

use crate::support::binary::{files_in, run};
use crate::support::{golden, scenes};
use lembo_sim::camera::View;
use lembo_sim::cost::tech::DramKind;
use lembo_sim::cost::{lembo_ops, triangle_ops};
use lembo_sim::datapath::Datapath;
use lembo_sim::datapath::{Op, OPS};
use lembo_sim::graph::{UnitKind, KINDS};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::raster::{render_functional, render_functional_triangles};
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
            let tess = Tessellation::new(&scene, 2);
            let plain = render_functional_triangles(&scene, &view, &tess, dp, false);
            let (counted, ops) = triangle_ops(&scene, &view, &tess, dp);
            assert!(plain.framebuffer.color == counted.framebuffer.color);
            assert!(ops.get(UnitKind::TriangleRasterizer, Op::IntMul) > 0);
        }
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
                | UnitKind::BlendUnit
                | UnitKind::FrameBuffer
        );
        assert_eq!(total > 0, expected, "{kind:?}: {:?}", ops.of(kind));
        assert_eq!(ops.get(kind, Op::Other), 0);
        assert_eq!(ops.get(kind, Op::IntMul), 0);
    }
    assert_eq!(OPS.len(), 9);
}

/// Every kind's operation counts, as text: a line a kind that counts any.
fn digest(ops: &lembo_sim::cost::counted::OpTable) -> String {
    KINDS
        .iter()
        .filter(|&&k| ops.of(k).iter().any(|&n| n > 0))
        .map(|&k| format!("{k:?} {:?}\n", ops.of(k)))
        .collect()
}

/// The operation counts the cost model prices (every unit kind, every operation) on every
/// shipped surface scene at 128 x 128, the lembo path in both datapaths and the triangle
/// path (n = 2), kept as a golden: a change that moves an operation into or out of the
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
        if scene.discoid_count() > 0 {
            continue;
        }
        scene.set_viewport(128, 128).unwrap();
        let view = View::new(&scene.camera, scene.viewport);
        for dp in [Datapath::F32, Datapath::F64] {
            let ops = match lembo_ops(&scene, &view, 0.5, dp) {
                Ok((_, ops)) => digest(&ops),
                Err(e) => format!("error: {e}"),
            };
            got.insert(format!("{name} lembo {dp:?}"), ops);
        }
        let tess = Tessellation::new(&scene, 2);
        let (_, ops) = triangle_ops(&scene, &view, &tess, Datapath::F32);
        got.insert(format!("{name} triangle F32"), digest(&ops));
    }
    golden::check(
        &root.join("tests/golden/ops/shipped.json"),
        got,
        "operation tables",
        &golden::Expect {
            min_cases: 40,
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
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("f32.mul_pj"), "{err}");
    assert!(files_in(&out).is_empty());
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
