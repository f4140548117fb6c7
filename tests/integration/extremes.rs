//! The extreme-case suite (issue 7, item 1): every scene in `traces/extremes/` renders
//! through both paths (lembo, and triangle at tessellation 2; discoid scenes through their
//! own passes) and both datapaths, in functional mode against the exact reference, and
//! once timed on the baseline architecture, without a panic and within [`TIME_LIMIT`], and
//! meets its entry in `traces/extremes/expect.json` (documented in
//! `traces/extremes/README.md`).

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::job::{render_reference, run_path, Mode, Model, PathRun, PrimitivePath, RenderJob};
use lembo_sim::reference::oracle::ReferenceImage;
use lembo_sim::scene::Scene;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use crate::support::render_job;

/// The longest one scene's runs may take, all of them together.
const TIME_LIMIT: Duration = Duration::from_secs(20);

/// The tessellation level of the triangle path.
const TESS: u32 = 2;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("traces/extremes")
}

fn expectations() -> serde_json::Map<String, Value> {
    let text = std::fs::read_to_string(dir().join("expect.json")).expect("expect.json reads");
    let v: Value = serde_json::from_str(&text).expect("expect.json parses");
    v.as_object().expect("expect.json is an object").clone()
}

fn job(path: PrimitivePath, datapath: Datapath, k: f64, mode: Mode) -> RenderJob {
    RenderJob {
        trace: Default::default(),
        mode,
        path,
        tess: (path == PrimitivePath::Triangle).then_some(TESS),
        ..render_job(k, datapath)
    }
}

fn num(bounds: &Value, key: &str) -> Option<f64> {
    bounds.get(key).map(|v| {
        v.as_f64()
            .unwrap_or_else(|| panic!("expect.json: {key} is a number"))
    })
}

/// Checks one functional run with its reference against the path's bounds.
fn check_bounds(what: &str, run: &PathRun, reference: &ReferenceImage, k: f64, bounds: &Value) {
    let a = run
        .report
        .accuracy
        .as_ref()
        .unwrap_or_else(|| panic!("{what}: accuracy measured"));
    let c = &run.report.counts;
    let covered = reference.hits.iter().filter(|h| h.is_some()).count().max(1) as f64;
    // Always 0, except where expect.json records a known defect (README.md there).
    let dp = if what.contains("f32") { "f32" } else { "f64" };
    let unpaired = num(bounds, &format!("unpaired_roots_{dp}")).unwrap_or(0.0) as u64;
    assert_eq!(c.unpaired_roots, unpaired, "{what}: unpaired roots {c:?}");
    if let Some(f) = num(bounds, "max_false_positive_frac") {
        let got = a.coverage_false_positive as f64 / covered;
        assert!(got <= f, "{what}: false positives {got} > {f} ({a:?})");
    }
    if let Some(f) = num(bounds, "max_false_negative_frac") {
        let got = a.coverage_false_negative as f64 / covered;
        assert!(got <= f, "{what}: false negatives {got} > {f} ({a:?})");
    }
    if let Some(px) = num(bounds, "max_false_positive_px") {
        assert!(
            a.coverage_false_positive as f64 <= px,
            "{what}: false positives {} > {px} px",
            a.coverage_false_positive
        );
    }
    let cracks = num(bounds, "max_crack_pixels").unwrap_or(0.0);
    assert!(a.crack_pixels as f64 <= cracks, "{what}: cracks {a:?}");
    let doubles = num(bounds, "max_double_hit_pixels").unwrap_or(0.0);
    assert!(
        a.double_hit_pixels as f64 <= doubles,
        "{what}: double hits {a:?}"
    );
    if let Some(p) = num(bounds, "min_psnr_db") {
        assert!(a.psnr_db >= p, "{what}: PSNR {} < {p} dB", a.psnr_db);
    }
    if let Some(n) = num(bounds, "max_segments") {
        assert!(
            c.segments as f64 <= n,
            "{what}: {} segments > {n}",
            c.segments
        );
    }
    if let Some(n) = num(bounds, "lembos_split") {
        assert_eq!(c.lembos_split as f64, n, "{what}: {c:?}");
    }
    if let Some(n) = num(bounds, "triangles_clipped") {
        assert_eq!(c.triangles_clipped as f64, n, "{what}: {c:?}");
    }
    match a.max_scanline_deviation_px {
        Some(dev) => {
            let key = format!("scanline_slack_{dp}");
            let slack = num(bounds, &key).unwrap_or_else(|| panic!("{what}: {key} given"));
            assert!(
                dev <= k + slack,
                "{what}: max |y - y_j| {dev} > k {k} + {slack}"
            );
        }
        None => assert!(what.contains("triangle"), "{what}: deviation measured"),
    }
}

/// Every run of one scene; panics on the first unmet expectation.
fn run_scene(file: &str, expect: &Value) {
    let k = num(expect, "k").expect("k given");
    let loaded = Scene::load(&dir().join(file));
    if let Some(needle) = expect.get("refused").and_then(Value::as_str) {
        let err = match loaded {
            Ok(scene) => {
                let view = View::new(&scene.camera, scene.viewport);
                let j = job(PrimitivePath::Lembo, Datapath::F32, k, Mode::Functional);
                match run_path(&j, &scene, &view, Model::Functional, None) {
                    Ok(_) => panic!("{file}: rendered, expected a refusal with {needle:?}"),
                    Err(e) => e.to_string(),
                }
            }
            Err(e) => e.to_string(),
        };
        assert!(err.contains(needle), "{file}: {err:?} lacks {needle:?}");
        return;
    }
    let scene = loaded.unwrap_or_else(|e| panic!("{file}: {e}"));
    let view = View::new(&scene.camera, scene.viewport);
    let baseline = ArchConfig::baseline();

    if scene.discoid_count() > 0 {
        let d = &expect["discoid"];
        for datapath in [Datapath::F32, Datapath::F64] {
            for (blend, key) in [
                (BlendMode::Rgba8, "saturations_rgba8_min"),
                (BlendMode::F32, "saturations_f32_max"),
            ] {
                let mut j = job(PrimitivePath::Lembo, datapath, k, Mode::Functional);
                j.blend = blend;
                let run = run_path(&j, &scene, &view, Model::Functional, None)
                    .unwrap_or_else(|e| panic!("{file}: {e}"));
                let b = &run.report.blend.as_ref().expect("blend section").blend;
                let bound = num(d, key).unwrap_or_else(|| panic!("{file}: {key}")) as u64;
                match blend {
                    BlendMode::Rgba8 => assert!(b.saturations >= bound, "{file}: {b:?}"),
                    _ => assert!(b.saturations <= bound, "{file}: {b:?}"),
                }
                if let Some(m) = num(d, "max_error") {
                    assert!(b.error_max <= m, "{file} {blend:?}: {b:?}");
                }
            }
        }
        let j = job(PrimitivePath::Lembo, Datapath::F32, k, Mode::Timed);
        let run = run_path(&j, &scene, &view, Model::Timed(&baseline), None)
            .unwrap_or_else(|e| panic!("{file} timed: {e}"));
        assert!(run.report.cycles.is_some(), "{file}: timed run has cycles");
        return;
    }

    let (reference, wall) = render_reference(&scene, &view, 1, lembo_sim::camera::Samples::ONE);
    for (path, key) in [
        (PrimitivePath::Lembo, "lembo"),
        (PrimitivePath::Triangle, "triangle"),
    ] {
        let bounds = expect
            .get(key)
            .unwrap_or_else(|| panic!("{file}: {key} bounds"));
        for datapath in [Datapath::F32, Datapath::F64] {
            let what = format!("{file} {key} {}", datapath.name());
            let j = job(path, datapath, k, Mode::Functional);
            let run = run_path(
                &j,
                &scene,
                &view,
                Model::Functional,
                Some((&reference, wall)),
            )
            .unwrap_or_else(|e| panic!("{what}: {e}"));
            check_bounds(&what, &run, &reference, k, bounds);
        }
        // Timed on the baseline: run_path also checks the timed image against the
        // functional one bit for bit.
        let what = format!("{file} {key} f32 timed");
        let j = job(path, Datapath::F32, k, Mode::Timed);
        let run = run_path(
            &j,
            &scene,
            &view,
            Model::Timed(&baseline),
            Some((&reference, wall)),
        )
        .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(run.report.cycles.is_some(), "{what}: cycles");
        check_bounds(&what, &run, &reference, k, bounds);
    }
}

/// Runs a scene on its own thread and fails if it panics or takes longer than
/// [`TIME_LIMIT`] (a hang must fail the test, not stall the suite).
fn check(file: &str) {
    let expect = expectations()
        .get(file)
        .unwrap_or_else(|| panic!("expect.json has no entry for {file}"))
        .clone();
    let (tx, rx) = mpsc::channel();
    let name = file.to_string();
    let worker = std::thread::spawn(move || {
        run_scene(&name, &expect);
        let _ = tx.send(());
    });
    match rx.recv_timeout(TIME_LIMIT) {
        Ok(()) => worker.join().expect("scene thread"),
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            // The thread ended without reporting: it panicked; rethrow its message.
            if let Err(p) = worker.join() {
                std::panic::resume_unwind(p);
            }
        }
        Err(mpsc::RecvTimeoutError::Timeout) => {
            panic!("{file}: not finished within {TIME_LIMIT:?}")
        }
    }
}

#[test]
fn every_scene_has_an_expectation_and_every_expectation_a_scene() {
    let mut scenes: Vec<String> = std::fs::read_dir(dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json") && n != "expect.json")
        .collect();
    scenes.sort();
    let mut expected: Vec<String> = expectations().keys().cloned().collect();
    expected.sort();
    assert_eq!(scenes, expected);
    // And every scene has its test below.
    let source = include_str!("extremes.rs");
    for s in &scenes {
        assert!(
            source.contains(&format!("=> \"{s}\"")),
            "{s} has no #[test]"
        );
    }
}

/// DESIGN.md §8: a patch that would need more segments than the cap on one interval is refused
/// with a message naming the lembo and the scanline, as bad input (exit status 2). No
/// scene reaches the default cap since Setup splits lembos far larger than the view, so a
/// small cap stands in for it.
#[test]
fn segment_cap_is_refused_by_lembo_and_scanline() {
    use lembo_sim::raster::{render_lembos, Counts};
    use lembo_sim::rop::{FrameBuffer, RopSink};
    let scene = Scene::load(&dir().join("huge_curved.json")).unwrap();
    let view = View::new(&scene.camera, scene.viewport);
    let mut fb = FrameBuffer::new(view.viewport.width, view.viewport.height, [0; 3], false);
    let mut rop = RopSink::<f64>::new(&mut fb, &scene.light, &view);
    let err = render_lembos::<f64, _>(&scene, &view, 1e-4, 4, &mut rop, &mut Counts::default())
        .expect_err("more than 4 segments on some interval");
    let msg = err.to_string();
    assert!(
        msg.contains("lembo 0 needs more than 4 segments on scanline"),
        "{msg}"
    );
    assert_eq!(err.exit_code(), 2);
}

macro_rules! scene_tests {
    ($($test:ident => $file:literal,)*) => {
        $(
            #[test]
            fn $test() {
                check($file);
            }
        )*
    };
}

scene_tests! {
    subpixel => "subpixel.json",
    huge => "huge.json",
    huge_curved => "huge_curved.json",
    close_up => "close_up.json",
    edge_on => "edge_on.json",
    degenerate_coincident => "degenerate_coincident.json",
    degenerate_collinear => "degenerate_collinear.json",
    degenerate_zero_area => "degenerate_zero_area.json",
    degenerate_zero_normals => "degenerate_zero_normals.json",
    saddle_on_scanline => "saddle_on_scanline.json",
    extremum_on_scanline => "extremum_on_scanline.json",
    linear_edges => "linear_edges.json",
    nearly_linear_edges => "nearly_linear_edges.json",
    k_min => "k_min.json",
    k_max => "k_max.json",
    coords_1e7 => "coords_1e7.json",
    discoids_64_one_pixel => "discoids_64_one_pixel.json",
}
