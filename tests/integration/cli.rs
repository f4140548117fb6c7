//! The `lembo-sim` binary as a user meets it: the default run, the golden default scene,
//! and bad input (exit status 2, an error naming the field, no file written).

use crate::support::binary::{bin, files_in, memory_available, run};
use crate::support::golden;
use std::path::{Path, PathBuf};

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs a failing command in a fresh directory and checks the contract of DESIGN.md §8.
fn assert_refused(args: &[&str], needle: &str) {
    assert_refused_with(args, &[], needle);
}

/// The binary run with `args` and the environment variables `env` in a fresh directory,
/// which is returned with what it printed (for the files it wrote).
fn run_in_empty_dir(
    args: &[&str],
    env: &[(&str, &str)],
) -> (std::process::Output, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .args(args)
        .envs(env.iter().copied())
        .current_dir(dir.path())
        .output()
        .expect("the binary runs");
    (out, dir)
}

/// As [`assert_refused`], with the environment variables `env` set.
fn assert_refused_with(args: &[&str], env: &[(&str, &str)], needle: &str) {
    let (out, dir) = run_in_empty_dir(args, env);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected `{needle}` in: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        files_in(dir.path()).is_empty(),
        "{args:?} wrote {:?}",
        files_in(dir.path())
    );
}

/// Runs `args` (writing into `o`) in `dir`, asserts that the run succeeded and returns the
/// report.json it wrote.
fn report_of_run(args: &[&str], dir: &Path) -> serde_json::Value {
    let out = run(args, dir);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&std::fs::read(dir.join("o/report.json")).unwrap()).unwrap()
}

/// Runs `args` in a fresh directory with the environment variables `env` set, and asserts
/// that the run succeeded.
fn assert_runs_with(args: &[&str], env: &[(&str, &str)]) {
    let (out, _dir) = run_in_empty_dir(args, env);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn scene_file(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

const GOOD: &str = r#"{"name": "t", "viewport": {"width": 32, "height": 32},
  "camera": {"eye": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0],
             "projection": {"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100}},
  "objects": [{"builtin": "sphere24"}]}"#;

#[test]
fn bare_command_renders_the_default_scene_into_out_default() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(&[], dir.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        files_in(&dir.path().join("out/default")),
        [
            "image.png",
            "manifest.json",
            "report.html",
            "report.json",
            "report.txt"
        ]
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/default/report.json")).unwrap())
            .unwrap();
    for key in [
        "schema_version",
        "scene",
        "settings",
        "arch",
        "units",
        "counts",
        "cycles",
        "accuracy",
        "memory",
        "host",
    ] {
        assert!(report.get(key).is_some(), "report.json lacks {key}");
    }
    // The default run is timed on the baseline architecture; accuracy needs --reference.
    assert_eq!(report["settings"]["mode"], "timed");
    assert_eq!(report["arch"]["name"], "baseline");
    assert!(report["cycles"]["total"].as_u64().unwrap() > 0);
    assert!(report["accuracy"].is_null());
    for key in [
        "scanlines",
        "intervals",
        "segments",
        "subsegments",
        "fragments",
        "fragments_passed_depth",
        "pixels_covered",
    ] {
        assert!(report["counts"][key].as_u64().unwrap() > 0, "counts.{key}");
    }
    for key in ["wall_seconds", "fragments_per_second"] {
        assert!(report["host"][key].is_number(), "host.{key}");
    }
}

#[test]
fn reference_run_writes_the_accuracy_names_and_images() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "s.json", GOOD);
    let out = run(&["render", &scene, "--reference", "--out", "o"], dir.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        files_in(&dir.path().join("o")),
        [
            "error.png",
            "flip.png",
            "image.png",
            "manifest.json",
            "reference.png",
            "report.html",
            "report.json",
            "report.txt"
        ]
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap()).unwrap();
    for key in ACCURACY_NAMES {
        assert!(
            report["accuracy"][key].is_number(),
            "accuracy.{key} missing"
        );
    }
    assert!(
        report["accuracy"]["max_scanline_deviation_px"]
            .as_f64()
            .unwrap()
            <= 0.5 + 1e-3
    );
}

/// The default scene's image, counts and cycle report (timed, baseline architecture),
/// compared exactly with tests/golden/default/ (Setup's default perspective tolerance, k/2)
/// and tests/golden/default_paper/ (`--perspective-tol off`: the paper's Setup).
/// Regenerate with `LEMBO_BLESS=1 cargo test --release --test integration cli::golden`
/// after an intended change; a blank image or an empty frame is refused either way.
#[test]
fn golden_default_scene() {
    check_golden(&["render", "--out", "o"], "default");
}

#[test]
fn golden_default_scene_with_the_papers_setup() {
    check_golden(
        &["render", "--out", "o", "--perspective-tol", "off"],
        "default_paper",
    );
}

/// The goldens were recorded before back-face culling was modelled: they run with it off
/// (`culling::` checks that it changes no image on the shipped closed meshes).
fn check_golden(args: &[&str], name: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("nocull.json"), crate::support::NO_CULLING).unwrap();
    let args = [args, &["--arch", "nocull.json"]].concat();
    let out = run(&args, dir.path());
    assert!(out.status.success());
    let golden = manifest().join("tests/golden").join(name);
    let image = std::fs::read(dir.path().join("o/image.png")).unwrap();
    let mut report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap()).unwrap();
    crate::support::strip_zero_culling(&mut report["counts"]);
    let counts = serde_json::to_string_pretty(&report["counts"]).unwrap() + "\n";
    let cycles = serde_json::to_string_pretty(&report["cycles"]).unwrap() + "\n";
    let got = image::load_from_memory(&image).unwrap().to_rgb8();
    // What no golden may be, blessed or compared: a blank image or an empty frame.
    let colours: std::collections::BTreeSet<[u8; 3]> = got.pixels().map(|p| p.0).collect();
    assert!(
        colours.len() > 16,
        "{name}: {} colours in the image",
        colours.len()
    );
    assert!(
        report["counts"]["pixels_covered"].as_u64() > Some(1000),
        "{name}: {counts}"
    );
    assert!(
        report["cycles"]["total"].as_u64() > Some(0),
        "{name}: {cycles}"
    );
    if golden::blessing() {
        let old = |f: &str| std::fs::read(golden.join(f)).unwrap_or_default();
        let changed: Vec<&str> = [
            ("image.png", image.as_slice()),
            ("counts.json", counts.as_bytes()),
            ("cycles.json", cycles.as_bytes()),
        ]
        .into_iter()
        .filter(|(f, new)| old(f) != *new)
        .map(|(f, _)| f)
        .collect();
        eprintln!("{}: {name} changed: {changed:?}", golden::BLESS);
        std::fs::create_dir_all(&golden).unwrap();
        std::fs::write(golden.join("image.png"), &image).unwrap();
        std::fs::write(golden.join("counts.json"), &counts).unwrap();
        std::fs::write(golden.join("cycles.json"), &cycles).unwrap();
    }
    let want = image::load_from_memory(&std::fs::read(golden.join("image.png")).unwrap())
        .unwrap()
        .to_rgb8();
    assert_eq!(want.dimensions(), got.dimensions());
    let differing = want
        .pixels()
        .zip(got.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(differing, 0, "pixels differing from the golden image");
    assert_eq!(
        std::fs::read_to_string(golden.join("counts.json")).unwrap(),
        counts
    );
    assert_eq!(
        std::fs::read_to_string(golden.join("cycles.json")).unwrap(),
        cycles
    );
}

/// An architecture file without a `"name"` is labelled by its file name, not as the
/// baseline it is not; one with a name keeps it.
#[test]
fn an_unnamed_architecture_file_is_labelled_by_its_file_name() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("two_rops.json"), r#"{"rop": {"count": 2}}"#).unwrap();
    std::fs::write(
        dir.path().join("named.json"),
        r#"{"name": "mine", "rop": {"count": 2}}"#,
    )
    .unwrap();
    for (file, name) in [("two_rops.json", "two_rops"), ("named.json", "mine")] {
        let out = run(
            &[
                "render",
                "--arch",
                file,
                "--viewport",
                "32x32",
                "--out",
                "o",
            ],
            dir.path(),
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap())
                .unwrap();
        assert_eq!(report["arch"]["name"], name, "{file}");
    }
}

#[test]
fn bad_architecture_field_is_refused_by_name() {
    for (arch, field) in [
        (
            r#"{"links": {"rop_to_framebuffer": {"fifo_depth": 0}}}"#,
            "links.rop_to_framebuffer.fifo_depth",
        ),
        (r#"{"segmenter": {"count": 0}}"#, "segmenter.count"),
        (r#"{"rop": {"count": 0}}"#, "rop.count"),
        (
            r#"{"triangle_setup": {"count": 0}}"#,
            "triangle_setup.count",
        ),
        (r#"{"setup": {"batch": 0}}"#, "setup.batch"),
        (
            r#"{"tessellation": {"source": "gpu"}}"#,
            "tessellation.source",
        ),
        (
            r#"{"tessellation": {"vertex_cache_entries": 0}}"#,
            "tessellation.vertex_cache_entries",
        ),
        (r#"{"tessellator": {"count": 0}}"#, "tessellator.count"),
        (r#"{"domain_eval": {"count": 65}}"#, "domain_eval.count"),
        (
            r#"{"triangle_setup": {"culled_per_cycle": 0}}"#,
            "triangle_setup.culled_per_cycle",
        ),
        (
            r#"{"framebuffer": {"access_cycles": 0.3}}"#,
            "framebuffer.access_cycles",
        ),
        (
            r#"{"rop": {"fragments_per_cycle": 0}}"#,
            "rop.fragments_per_cycle",
        ),
        (
            r#"{"tessellator": {"cycles_per_triangle": 0}}"#,
            "tessellator.cycles_per_triangle",
        ),
        (
            r#"{"domain_eval": {"cycles_per_vertex": 0.001}}"#,
            "domain_eval.cycles_per_vertex",
        ),
        (
            r#"{"fetch": {"bytes_per_lembo": 0}}"#,
            "fetch.bytes_per_lembo",
        ),
        (
            r#"{"fetch": {"bytes_per_vertex": 0}}"#,
            "fetch.bytes_per_vertex",
        ),
        (
            r#"{"fetch": {"index_bytes_per_triangle": 4097}}"#,
            "fetch.index_bytes_per_triangle",
        ),
        (
            r#"{"minmax": {"cull_backfaces": "sometimes"}}"#,
            "minmax.cull_backfaces",
        ),
        (
            r#"{"triangle_setup": {"cull_backfaces": true}}"#,
            "triangle_setup.cull_backfaces",
        ),
        (
            r#"{"minmax": {"cull_cycles_per_lembo": 1000000000000}}"#,
            "minmax.cull_cycles_per_lembo",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.json"), arch).unwrap();
        let out = run(&["render", "--arch", "a.json", "--out", "o"], dir.path());
        assert_eq!(out.status.code(), Some(2), "{arch}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(field), "stderr: {err}");
        assert!(!dir.path().join("o").exists(), "nothing written");
    }
}

#[test]
fn timed_run_reports_units_and_writes_a_timeline() {
    let dir = tempfile::tempdir().unwrap();
    let arch = manifest().join("sim/arch/wide.json");
    let report = report_of_run(
        &[
            "render",
            "--arch",
            arch.to_str().unwrap(),
            "--viewport",
            "128x128",
            "--trace-out",
            "t/trace.json",
            "--out",
            "o",
        ],
        dir.path(),
    );
    assert_eq!(report["settings"]["mode"], "timed");
    assert_eq!(report["arch"]["name"], "wide");
    assert_eq!(
        report["units"].as_array().unwrap().len(),
        1 + 3 + 4 + 4 + 8 + 4 + 1
    );
    let units = report["cycles"]["units"].as_array().unwrap();
    let total = report["cycles"]["total"].as_u64().unwrap();
    assert!(total > 0);
    for u in units {
        let sum = ["busy", "starved", "blocked"].map(|k| u[k].as_u64().unwrap());
        assert_eq!(sum.iter().sum::<u64>(), total, "{}", u["name"]);
    }
    assert!(
        report["host"]["simulated_cycles_per_second"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    let text = std::fs::read_to_string(dir.path().join("o/report.txt")).unwrap();
    assert!(text.contains("bottleneck") && text.contains("Rasterizer[7]"));
    let trace: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("t/trace.json")).unwrap()).unwrap();
    assert!(trace["traceEvents"].as_array().unwrap().len() > 10);
}

#[test]
fn functional_mode_refuses_timed_only_flags() {
    assert_refused(
        &["render", "--mode", "functional", "--arch", "x.json"],
        "--arch",
    );
    assert_refused(
        &["render", "--mode", "functional", "--host-threads", "2"],
        "--host-threads",
    );
}

/// `--threads` draws a functional frame; 0, more than the cap, or a timed run (whose units
/// take `--host-threads`) are refused by name; any count writes the same image and counts.
/// Renders scene file `scene` with `args` into `dir/out`, which must succeed; its
/// report.json and image.png.
fn render_into(dir: &Path, scene: &str, out: &str, args: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let out_dir = dir.join(out);
    let mut all = vec!["render", scene, "--out", out_dir.to_str().unwrap()];
    all.extend_from_slice(args);
    let run = run(&all, dir);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report = std::fs::read(out_dir.join("report.json")).unwrap();
    let image = std::fs::read(out_dir.join("image.png")).unwrap();
    (serde_json::from_slice(&report).unwrap(), image)
}

#[test]
fn threads_draw_the_same_functional_frame() {
    assert_refused(
        &["render", "--mode", "functional", "--threads", "0"],
        "field `--threads` = 0",
    );
    assert_refused(
        &["render", "--mode", "functional", "--threads", "257"],
        "field `--threads` = 257",
    );
    assert_refused(
        &["render", "--threads", "2"],
        "only meaningful with --mode functional",
    );
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(dir.path(), "s.json", GOOD);
    let mut seen = Vec::new();
    for threads in ["1", "2", "5"] {
        let args = ["--mode", "functional", "--threads", threads];
        let (r, image) = render_into(dir.path(), &s, &format!("t{threads}"), &args);
        seen.push((image, r["counts"].clone()));
    }
    assert!(seen.windows(2).all(|w| w[0] == w[1]));
}

/// `--host-threads` 0 and more threads than units are refused by name; any valid count
/// gives the same report (cycles, counts) and image, and report.json says how many ran.
#[test]
fn host_threads_change_nothing_simulated() {
    assert_refused(&["render", "--host-threads", "0"], "--host-threads");
    // The baseline's lembo path has 17 units.
    assert_refused(&["render", "--host-threads", "18"], "17 units");
    // compare needs a unit per thread on both paths: the baseline's triangle path has 8.
    assert_refused(&["compare", "--host-threads", "9"], "8 units");
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(dir.path(), "s.json", GOOD);
    let mut reports = Vec::new();
    for threads in ["1", "3", "16"] {
        let args = ["--host-threads", threads];
        let (r, image) = render_into(dir.path(), &s, &format!("out{threads}"), &args);
        assert_eq!(r["host"]["host_threads"], threads.parse::<u32>().unwrap());
        reports.push((r["cycles"].clone(), r["counts"].clone(), image));
    }
    assert!(reports.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn malformed_json_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(dir.path(), "bad.json", "{\"name\": \"t\", ");
    assert_refused(&["render", &s], "bad.json");
}

#[test]
fn unknown_field_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(dir.path(), "u.json", &GOOD.replace("\"up\"", "\"upp\""));
    assert_refused(&["render", &s], "upp");
}

#[test]
fn infinite_coordinate_is_refused_by_field() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(
        dir.path(),
        "inf.json",
        &GOOD.replace("\"eye\": [0, 0, 4]", "\"eye\": [0, 1e999, 4]"),
    );
    assert_refused(&["render", &s], "camera.eye");
}

#[test]
fn nan_in_a_mesh_is_refused_by_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n",
    )
    .unwrap();
    let s = scene_file(
        dir.path(),
        "nan.json",
        &GOOD.replace("{\"builtin\": \"sphere24\"}", "{\"mesh\": \"m.obj\"}"),
    );
    assert_refused(&["render", &s], "objects[0].mesh");
}

#[test]
fn mesh_triangle_whose_corners_weld_is_refused_by_file_and_index() {
    // Triangle 1 (0-based) has two corners 1e-12 apart: welded, it would be a sliver.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("sliver.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1e-12 0\nf 1 2 3\nf 2 4 3\n",
    )
    .unwrap();
    let s = scene_file(
        dir.path(),
        "sliver.json",
        &GOOD.replace("{\"builtin\": \"sphere24\"}", "{\"mesh\": \"sliver.obj\"}"),
    );
    for needle in [
        "sliver.json",
        "objects[0].mesh",
        "sliver.obj",
        "triangle 1 ",
    ] {
        assert_refused(&["render", &s], needle);
    }
}

#[test]
fn crease_angle_out_of_range_is_refused_by_field() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = manifest().join("traces/meshes/bevel_cube.obj");
    let s = scene_file(
        dir.path(),
        "crease.json",
        &GOOD.replace(
            "{\"builtin\": \"sphere24\"}",
            &format!(
                "{{\"mesh\": {:?}, \"crease_angle_deg\": 190}}",
                mesh.to_string_lossy()
            ),
        ),
    );
    assert_refused(&["render", &s], "objects[0].crease_angle_deg");
}

#[test]
fn k_out_of_range_is_refused() {
    for k in ["0", "-1", "64.5", "NaN", "inf"] {
        assert_refused(&["render", "--k", k], "--k");
    }
}

/// FLIP's observer: a positive finite number of pixels per degree, up to the bound, and
/// only with a reference to compare with.
#[test]
fn bad_flip_pixels_per_degree_is_refused() {
    for ppd in ["0", "-1", "NaN", "inf", "1e9", "far"] {
        assert_refused(&["render", "--reference", "--flip-ppd", ppd], "--flip-ppd");
        assert_refused(&["compare", "--flip-ppd", ppd], "--flip-ppd");
    }
    assert_refused(&["render", "--flip-ppd", "30"], "--flip-ppd");
}

/// `--samples`: 1, 2, 4 or 8; not on a discoid scene (the blend units do not multisample),
/// not past 16384 sample rows, and not against a reference of fewer than 4x4 sub-samples.
#[test]
fn bad_samples_are_refused() {
    for n in ["0", "3", "16", "four"] {
        assert_refused(&["render", "--samples", n], "--samples");
        assert_refused(&["compare", "--samples", n], "--samples");
    }
    let discoids = manifest().join("traces/discoid_sphere20.json");
    assert_refused(
        &["render", discoids.to_str().unwrap(), "--samples", "4"],
        "do not multisample",
    );
    assert_refused(
        &["render", "--samples", "8", "--viewport", "64x4096"],
        "32768 rows",
    );
    assert_refused(
        &["compare", "--samples", "8", "--viewport", "64x4096"],
        "32768 rows",
    );
    assert_refused(
        &[
            "render",
            "--samples",
            "4",
            "--reference",
            "--supersample",
            "2",
        ],
        "--supersample",
    );
}

/// The observer given is the one FLIP is computed for: echoed, and changing the figure.
#[test]
fn flip_pixels_per_degree_is_used_and_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let flip = |ppd: &str| {
        let report = report_of_run(
            &[
                "render",
                "--mode",
                "functional",
                "--reference",
                "--flip-ppd",
                ppd,
                "--out",
                "o",
            ],
            dir.path(),
        );
        let a = &report["accuracy"];
        assert_eq!(
            a["flip_pixels_per_degree"].as_f64(),
            Some(ppd.parse().unwrap())
        );
        a["flip_mean"].as_f64().unwrap()
    };
    let (near, far) = (flip("10"), flip("200"));
    assert!(near > 0.0 && far > 0.0 && near != far, "{near} {far}");
}

#[test]
fn bad_perspective_tolerance_is_refused() {
    for tol in ["0", "-0.1", "NaN", "inf", "-inf", "fine"] {
        for cmd in ["render", "compare"] {
            assert_refused(&[cmd, "--perspective-tol", tol], "--perspective-tol");
        }
    }
    assert_refused(
        &["render", "--path", "triangle", "--perspective-tol", "0.1"],
        "--perspective-tol",
    );
}

/// report.json echoes Setup's perspective tolerance: k/2 by default, the given pixels, or
/// "off"; null on the triangle path.
#[test]
fn perspective_tolerance_is_echoed_in_the_report() {
    let dir = tempfile::tempdir().unwrap();
    for (args, want) in [
        (&["--k", "0.25"][..], serde_json::json!(0.125)),
        (&["--perspective-tol", "0.3"][..], serde_json::json!(0.3)),
        (&["--perspective-tol", "off"][..], serde_json::json!("off")),
        (
            &["--path", "triangle", "--tess", "2"][..],
            serde_json::Value::Null,
        ),
    ] {
        let mut all = vec!["render", "--mode", "functional", "--out", "o"];
        all.extend_from_slice(args);
        let out = run(&all, dir.path());
        assert!(out.status.success(), "{args:?}");
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap())
                .unwrap();
        assert_eq!(report["settings"]["perspective_tol"], want, "{args:?}");
    }
}

#[test]
fn viewport_out_of_range_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (w, field) in [("0", "viewport.width"), ("16385", "viewport.width")] {
        let s = scene_file(
            dir.path(),
            "v.json",
            &GOOD.replace("\"width\": 32", &format!("\"width\": {w}")),
        );
        assert_refused(&["render", &s], field);
    }
    assert_refused(&["render", "--viewport", "0x10"], "--viewport width");
    assert_refused(&["render", "--viewport", "16385x10"], "--viewport width");
}

#[test]
fn missing_obj_file_is_refused_by_field() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(
        dir.path(),
        "m.json",
        &GOOD.replace("{\"builtin\": \"sphere24\"}", "{\"mesh\": \"nowhere.obj\"}"),
    );
    assert_refused(&["render", &s], "objects[0].mesh");
}

#[test]
fn missing_scene_file_is_refused() {
    assert_refused(&["render", "no-such-scene.json"], "no-such-scene.json");
}

#[test]
fn a_failed_run_keeps_an_earlier_output() {
    let dir = tempfile::tempdir().unwrap();
    assert!(run(&["render", "--out", "o"], dir.path()).status.success());
    let before = std::fs::read(dir.path().join("o/report.json")).unwrap();
    let out = run(&["render", "--out", "o", "--k", "100"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read(dir.path().join("o/report.json")).unwrap(),
        before
    );
}

#[test]
fn help_explains_the_render_flags() {
    let out = bin().args(["render", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--out",
        "--k",
        "--datapath",
        "--reference",
        "--mode",
        "--arch",
        "--trace-out",
        "--supersample",
        "--viewport",
        "--path",
        "--tess",
    ] {
        assert!(text.contains(flag), "--help lacks {flag}");
    }
    let out = bin().args(["compare", "--help"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--k",
        "--tess",
        "auto",
        "--match",
        "psnr",
        "flip",
        "--match-path",
        "--out",
        "--arch",
        "--viewport",
    ] {
        assert!(text.contains(flag), "compare --help lacks {flag}");
    }
}

/// The accuracy names of `render --reference` (DESIGN.md §6).
const ACCURACY_NAMES: [&str; 17] = [
    "coverage_false_positive",
    "coverage_false_negative",
    "silhouette_max_px",
    "silhouette_mean_px",
    "silhouette_resolution_px",
    "depth_max_abs",
    "normal_max_deg",
    "normal_mean_deg",
    "psnr_db",
    "max_abs_error",
    "flip_mean",
    "flip_pixels_per_degree",
    "crack_pixels",
    "double_hit_pixels",
    "see_through_px",
    "leak_px",
    "max_scanline_deviation_px",
];

#[test]
fn compare_writes_every_file_and_both_reports() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = manifest().join("traces/sphere24.json");
    let out = run(
        &[
            "compare",
            sphere.to_str().unwrap(),
            "--viewport",
            "160x160",
            "--out",
            "c",
        ],
        dir.path(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        files_in(&dir.path().join("c")),
        [
            "compare.json",
            "compare.txt",
            "lembo.png",
            "lembo_error.png",
            "lembo_flip.png",
            "manifest.json",
            "montage.png",
            "reference.png",
            "report.html",
            "triangle.png",
            "triangle_error.png",
            "triangle_flip.png"
        ]
    );
    for row in [
        "primitives",
        "vertices",
        "primitive bytes fetched",
        "primitive bytes stored",
        "cycles",
        "energy uJ/frame",
        "of it on chip uJ",
        "of it DRAM uJ",
        "fragments",
    ] {
        assert!(stdout.contains(row), "table row {row}: {stdout}");
    }
    let c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("c/compare.json")).unwrap()).unwrap();
    assert_eq!(c["schema_version"], 3);
    for path in ["lembo", "triangle"] {
        let r = &c[path];
        assert_eq!(r["settings"]["path"], path);
        for key in ACCURACY_NAMES {
            assert!(r["accuracy"].get(key).is_some(), "{path}: accuracy.{key}");
        }
        assert!(r["cycles"]["total"].as_u64().unwrap() > 0, "{path}");
        assert!(r["primitives"]["bytes"].as_u64().unwrap() > 0, "{path}");
    }
    // Auto chose the smallest level it tried that meets the lembo path's silhouette error.
    let target = c["lembo"]["accuracy"]["silhouette_max_px"]
        .as_f64()
        .unwrap();
    let level = c["tess"]["level"].as_u64().unwrap();
    let tried = c["tess"]["tried"].as_array().unwrap();
    assert!(c["tess"]["reached"].as_bool().unwrap());
    for step in tried {
        let (n, err) = (
            step["tess"].as_u64().unwrap(),
            step["silhouette_max_px"].as_f64().unwrap(),
        );
        assert_eq!(
            err <= target,
            n >= level,
            "n={n} error {err} target {target}"
        );
    }
    assert!(
        c["triangle"]["accuracy"]["silhouette_max_px"]
            .as_f64()
            .unwrap()
            <= target
    );
    assert!(c["triangle"]["accuracy"]["max_scanline_deviation_px"].is_null());
    // The default match is the silhouette's, of the triangle path's n.
    let m = &c["match"];
    assert_eq!(m["metric"], "silhouette");
    assert_eq!(m["searched_path"], "triangle");
    assert_eq!(m["target"].as_f64().unwrap(), target);
    assert_eq!(m["level"].as_u64().unwrap(), level);
    assert_eq!(m["tried"].as_array().unwrap().len(), tried.len());
    // Primitive bytes: the row gives what the fetch read, the ratio both.
    for path in ["lembo", "triangle"] {
        let fetched = c[path]["fetch"]["bytes"].as_u64().unwrap();
        assert_eq!(fetched, c[path]["cost"]["geometry_bytes"].as_u64().unwrap());
        assert!(stdout.contains(&fetched.to_string()), "{path}: {stdout}");
    }
    assert!(
        c["ratios"]["triangle_over_lembo_bytes_fetched"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert!(
        c["ratios"]["lembo_over_triangle_cycles_per_primitive"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert!(
        c["ratios"]["lembo_cycles_per_covered_pixel"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    let montage = image::open(dir.path().join("c/montage.png")).unwrap();
    assert!(montage.width() >= 5 * 160 && montage.height() > 160);
}

/// `compare --match psnr` (issue 49): the triangle path's n is the smallest whose PSNR is at
/// least the lembo run's; the output says what was matched, every level tried and how
/// close the chosen one came: within 1 dB, or the level below it missed.
#[test]
fn compare_match_psnr_picks_the_smallest_n_at_the_lembo_runs_psnr() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = manifest().join("traces/bunny.json");
    let out = run(
        &[
            "compare",
            bunny.to_str().unwrap(),
            "--viewport",
            "256x192",
            "--match",
            "psnr",
            "--out",
            "c",
        ],
        dir.path(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("c/compare.json")).unwrap()).unwrap();
    let psnr = |path: &str| c[path]["accuracy"]["psnr_db"].as_f64().unwrap();
    let m = &c["match"];
    assert_eq!(m["metric"], "psnr");
    assert_eq!(m["field"], "psnr_db");
    assert_eq!(m["searched_path"], "triangle");
    assert_eq!(m["target"].as_f64().unwrap(), psnr("lembo"));
    let n = c["tess"]["level"].as_u64().unwrap();
    assert_eq!(m["level"].as_u64().unwrap(), n);
    assert_eq!(c["triangle"]["settings"]["tess"].as_u64().unwrap(), n);
    assert_eq!(m["value"].as_f64().unwrap(), psnr("triangle"));
    assert!(psnr("triangle") >= psnr("lembo"), "{stdout}");
    // Every level tried is listed with its PSNR, meeting the target exactly from n on.
    let tried = m["tried"].as_array().unwrap();
    for step in tried {
        let (level, value) = (
            step["level"].as_u64().unwrap(),
            step["value"].as_f64().unwrap(),
        );
        assert_eq!(step["meets"].as_bool().unwrap(), value >= psnr("lembo"));
        assert_eq!(
            value >= psnr("lembo"),
            level >= n,
            "n = {level}: {value} dB"
        );
    }
    assert_eq!(c["tess"]["tried"].as_array().unwrap().len(), tried.len());
    // Within 1 dB, or the output says why not: n - 1 was tried and fell short.
    let gap = psnr("triangle") - psnr("lembo");
    if gap > 1.0 {
        let miss = &m["nearest_miss"];
        assert_eq!(miss["level"].as_u64().unwrap(), n - 1, "{m}");
        assert!(miss["value"].as_f64().unwrap() < psnr("lembo"));
        assert!(stdout.contains(&format!("n = {} (", n - 1)), "{stdout}");
    }
    for part in [
        "smallest n with psnr_db >=",
        "tried (functional model) n = 1 ",
        &format!(
            "matched: PSNR {:.2} dB at n = {n} against the lembo run's",
            psnr("triangle")
        ),
        &format!("within {gap:.2} dB"),
    ] {
        assert!(stdout.contains(part), "{part}: {stdout}");
    }
    let page = std::fs::read_to_string(dir.path().join("c/report.html")).unwrap();
    assert!(
        page.contains("matched: PSNR"),
        "report.html lacks the match"
    );
}

/// `compare --match-path lembo`: the triangle run keeps its n and the lembo path's k is
/// the largest that matches it, bisected to within 5 % of a k that did not.
#[test]
fn compare_match_path_lembo_searches_k_against_the_triangle_run() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = manifest().join("traces/bunny.json");
    let out = run(
        &[
            "compare",
            bunny.to_str().unwrap(),
            "--viewport",
            "256x192",
            "--match-path",
            "lembo",
            "--tess",
            "2",
            "--out",
            "c",
        ],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let c: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("c/compare.json")).unwrap()).unwrap();
    let m = &c["match"];
    assert_eq!(m["metric"], "silhouette");
    assert_eq!(m["searched_path"], "lembo");
    assert_eq!(c["tess"]["level"], 2);
    assert!(!c["tess"]["auto"].as_bool().unwrap());
    let k = m["level"].as_f64().unwrap();
    assert_eq!(c["lembo"]["settings"]["k_px"].as_f64().unwrap(), k);
    let silhouette = |path: &str| c[path]["accuracy"]["silhouette_max_px"].as_f64().unwrap();
    assert_eq!(m["target"].as_f64().unwrap(), silhouette("triangle"));
    assert!(silhouette("lembo") <= silhouette("triangle"));
    // The lembo run's 0.5 px misses the triangles' silhouette on the bunny: k is smaller,
    // with a larger k that missed within 5 % of it.
    assert!(k < 0.5, "{m}");
    let miss = m["nearest_miss"]["level"].as_f64().unwrap();
    assert!(miss > k && miss - k <= 0.05 * k, "{m}");
    assert_eq!(m["start"].as_f64().unwrap(), 0.5);
    assert_eq!(m["cap"].as_f64().unwrap(), 1e-4);
}

/// A match target the knob's cap cannot reach is refused rather than pretended (issue 49,
/// DESIGN.md §8): at k = 0.001 px the lembos' PSNR on the bunny is above what n = 64 gives.
/// Exit status 2, the error names `--match`, the target, the cap and the closest run, and
/// nothing is written.
#[test]
fn compare_refuses_a_match_target_the_cap_cannot_reach() {
    let bunny = manifest().join("traces/bunny.json");
    let args = [
        "compare",
        bunny.to_str().unwrap(),
        "--viewport",
        "256x192",
        "--k",
        "0.001",
        "--match",
        "psnr",
        "--out",
        "o",
    ];
    let (out, dir) = run_in_empty_dir(&args, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    for part in [
        "`--match` = psnr",
        "the lembo run's PSNR",
        "n = 64 (the cap of --tess auto)",
        "the closest run, n = 64, measured PSNR",
    ] {
        assert!(stderr.contains(part), "{part}: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}

#[test]
fn triangle_render_reports_quads_and_triangle_units() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(
        &[
            "render",
            "--path",
            "triangle",
            "--tess",
            "3",
            "--viewport",
            "96x96",
            "--out",
            "o",
        ],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap()).unwrap();
    assert_eq!(r["settings"]["tess"], 3);
    assert!(r["settings"]["k_px"].is_null());
    assert_eq!(r["primitives"]["count"], 24 * 9);
    let q = r["primitives"]["quad_efficiency"].as_f64().unwrap();
    assert!(q > 0.25 && q <= 1.0, "{q}");
    let names: Vec<&str> = r["units"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "GeometryFetch",
            "TriangleSetup",
            "TriangleRasterizer[0]",
            "Rop[0]",
            "Rop[1]",
            "Rop[2]",
            "Rop[3]",
            "FrameBuffer"
        ]
    );
}

#[test]
fn bad_tessellation_flags_are_refused() {
    assert_refused(&["render", "--tess", "2", "--out", "o"], "--path triangle");
    assert_refused(
        &["render", "--path", "triangle", "--tess", "0", "--out", "o"],
        "--tess",
    );
    assert_refused(&["compare", "--tess", "many", "--out", "o"], "--tess");
    assert_refused(&["compare", "--tess", "0", "--out", "o"], "--tess");
    // A match where nothing is searched, or searched without its fixed level.
    assert_refused(
        &["compare", "--match", "psnr", "--tess", "3", "--out", "o"],
        "--match",
    );
    assert_refused(
        &[
            "compare",
            "--match-path",
            "triangle",
            "--tess",
            "3",
            "--out",
            "o",
        ],
        "--match-path",
    );
    assert_refused(
        &["compare", "--match-path", "lembo", "--out", "o"],
        "--tess",
    );
    assert_refused(&["compare", "--match", "ssim", "--out", "o"], "--match");
    let bunny = manifest().join("traces/bunny.json");
    // 3674 lembos x 1024² triangles: refused before any work.
    assert_refused(
        &[
            "render",
            bunny.to_str().unwrap(),
            "--path",
            "triangle",
            "--tess",
            "1024",
            "--out",
            "o",
        ],
        "triangles",
    );
}

#[test]
fn discoid_render_reports_the_blend_section() {
    let dir = tempfile::tempdir().unwrap();
    let scene = manifest().join("traces/surfels_bunny.json");
    let out = run(
        &[
            "render",
            scene.to_str().unwrap(),
            "--blend",
            "f16",
            "--viewport",
            "96x96",
            "--out",
            "o",
        ],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap()).unwrap();
    let b = &r["blend"];
    assert_eq!(b["mode"], "f16");
    assert_eq!(b["bytes_per_fragment"], 16);
    for key in [
        "fragments_accumulated",
        "discarded_threshold",
        "discarded_beta_zero",
        "culled_backface",
        "saturations",
        "holes",
    ] {
        assert!(b[key].is_u64(), "blend.{key}: {b}");
    }
    for key in ["error_max", "error_mean"] {
        assert!(b[key].is_f64(), "blend.{key}: {b}");
    }
    assert!(b["fragments_accumulated"].as_u64().unwrap() > 0);
    assert_eq!(r["settings"]["path"], "discoid");
    assert_eq!(r["primitives"]["kind"], "discoid");
    assert!(r["cycles"]["total"].as_u64().unwrap() > 0);
    // A scene without discoids has no blend section.
    let out = run(&["render", "--viewport", "32x32", "--out", "p"], dir.path());
    assert!(out.status.success());
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("p/report.json")).unwrap()).unwrap();
    assert!(r["blend"].is_null());
}

#[test]
fn bad_discoid_flags_are_refused() {
    let scene = manifest().join("traces/discoid_sphere20.json");
    let s = scene.to_str().unwrap();
    assert_refused(
        &["render", s, "--threshold", "0", "--out", "o"],
        "--threshold",
    );
    assert_refused(
        &["render", s, "--threshold", "nan", "--out", "o"],
        "--threshold",
    );
    assert_refused(&["render", s, "--blend", "f8", "--out", "o"], "--blend");
    // The reference of a discoid scene is the surface it stands for: inline discoids
    // without a `surface` have none.
    let sheets = manifest().join("traces/discoid_threshold.json");
    let args = [
        "render",
        sheets.to_str().unwrap(),
        "--reference",
        "--out",
        "o",
    ];
    assert_refused(&args, "field `--reference`");
    assert_refused(&args, "does not say what surface its discoids stand for");
    // compare draws both surface paths; a discoid scene has neither.
    assert_refused(
        &["compare", s, "--out", "o"],
        "field `objects` = 1280 discoids",
    );
}

/// One rule for settings that do not apply (DESIGN.md §8): refused naming the flag and
/// why, exit 2, nothing written; as a sweep refuses such a parameter.
#[test]
fn flags_that_do_not_apply_are_refused_naming_why() {
    let path = |name: &str| manifest().join("traces").join(name);
    let (bunny, planar, curved) = (
        path("bunny.json"),
        path("bunny_discoids.json"),
        path("discoid_sphere20.json"),
    );
    let (b, p, c) = (
        bunny.to_str().unwrap(),
        planar.to_str().unwrap(),
        curved.to_str().unwrap(),
    );
    for (args, flag, why) in [
        (
            vec![b, "--blend", "f16"],
            "--blend",
            "which has no discoids",
        ),
        (
            vec![b, "--threshold", "0.1"],
            "--threshold",
            "which has no discoids",
        ),
        (vec![p, "--path", "triangle"], "--path", "planar discoids"),
        (vec![p, "--path", "lembo"], "--path", "planar discoids"),
        (
            vec![c, "--path", "triangle", "--tess", "2"],
            "--path",
            "curved discoids",
        ),
        (vec![p, "--k", "0.3"], "--k", "planar discoids"),
        (
            vec![b, "--path", "triangle", "--k", "0.3"],
            "--k",
            "triangle path",
        ),
        (
            vec![b, "--path", "triangle", "--perspective-tol", "off"],
            "--perspective-tol",
            "triangle path",
        ),
    ] {
        let mut full = vec!["render"];
        full.extend(args);
        full.extend(["--out", "o"]);
        assert_refused(&full, &format!("field `{flag}`"));
        assert_refused(&full, why);
    }
    // Where they apply they are taken: k on curved discoids, the path on a surface scene.
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec![
            "render",
            c,
            "--k",
            "0.3",
            "--mode",
            "functional",
            "--out",
            "o1",
        ],
        vec![
            "render",
            b,
            "--path",
            "lembo",
            "--mode",
            "functional",
            "--out",
            "o2",
        ],
    ] {
        let out = run(&args, dir.path());
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[cfg(unix)]
#[test]
fn endless_input_files_are_refused_not_read_forever() {
    // /dev/zero never ends: reading it whole would run out of memory.
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(
        dir.path(),
        "z.json",
        r#"{"name": "z", "camera": {"eye": [0, 0, 4], "target": [0, 0, 0],
            "projection": {"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 10}},
            "objects": [{"mesh": "/dev/zero"}]}"#,
    );
    assert_refused(&["render", &scene, "--out", "o"], "larger than");
    assert_refused(&["render", "/dev/zero", "--out", "o"], "larger than");
    assert_refused(
        &["render", "--arch", "/dev/zero", "--out", "o"],
        "larger than",
    );
}

/// A render estimated to need more memory than the machine has is refused before it starts,
/// naming `--viewport` and the estimate (a 4096x4096 frame with its reference needs about
/// 3 GiB); below that, the run goes ahead. The machine's size is set with
/// `LEMBO_MEMORY_AVAILABLE`, so the refusal is tested on any machine; where the machine
/// itself has less than 40 GB, a 16384x16384 run (about 50 GiB, the largest frame the
/// command takes) is refused on its own reading of /proc/meminfo too. A larger machine
/// skips that part, saying so, and fails under CI, whose machines are smaller.
#[test]
fn a_run_larger_than_memory_is_refused_before_it_starts() {
    let bunny = manifest().join("traces/bunny.json");
    let bunny = bunny.to_str().unwrap();
    let at = |size: &'static str| {
        [
            "render",
            bunny,
            "--viewport",
            size,
            "--reference",
            "--out",
            "o",
        ]
    };
    let one_gib = [("LEMBO_MEMORY_AVAILABLE", "1073741824")];
    for needle in [
        "field `--viewport` = 4096x4096",
        "GiB (estimate)",
        "1.0 GiB of memory available",
        "--no-memory-check",
    ] {
        assert_refused_with(&at("4096x4096"), &one_gib, needle);
    }
    // The control: the same machine runs a small frame.
    assert_runs_with(&at("64x64"), &one_gib);
    for bad in ["lots", "0", "-5", ""] {
        assert_refused_with(
            &at("64x64"),
            &[("LEMBO_MEMORY_AVAILABLE", bad)],
            "LEMBO_MEMORY_AVAILABLE",
        );
    }
    match memory_available() {
        Some(bytes) if bytes < 40e9 => {
            for needle in [
                "field `--viewport` = 16384x16384",
                "GiB (estimate)",
                "--no-memory-check",
            ] {
                assert_refused(&at("16384x16384"), needle);
            }
        }
        available => crate::support::skip_part(&format!(
            "the part on this machine's own memory: {available:?} bytes available, and the \
             largest run the command takes needs about 50 GiB; the refusal was tested at a set size"
        )),
    }
}

/// A scene whose lembos weigh more than its pixels is refused naming the scene: a run
/// measured against the exact reference is estimated at about 160 bytes a lembo more, so
/// terrain320's 204 800 lembos with a reference need about 33 MB more at 64x64 than
/// without (about 150 MB in all); nothing is written.
#[test]
fn a_scene_too_large_for_memory_is_refused_by_its_lembos() {
    let terrain = manifest().join("traces/terrain320.json");
    let terrain = terrain.to_str().unwrap();
    let args = |reference: bool| {
        let mut a = vec!["render", terrain, "--viewport", "64x64", "--out", "o"];
        if reference {
            a.push("--reference");
        }
        a
    };
    let small = [("LEMBO_MEMORY_AVAILABLE", "140000000")];
    for needle in [
        "field `SCENE` =",
        "204800 lembos at 64x64 px",
        "without --reference",
        "--no-memory-check",
    ] {
        assert_refused_with(&args(true), &small, needle);
    }
    let mut functional = args(false);
    functional.extend(["--mode", "functional"]);
    assert_runs_with(&functional, &small);
}

/// One run, one set (DESIGN.md §7): a folder holds exactly the files of the last run that
/// wrote it, listed in its manifest.json; a run that writes fewer files removes the ones
/// of the set it replaces, and leaves files no run wrote.
#[test]
fn an_output_folder_holds_one_runs_files() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = manifest().join("traces/sphere24.json");
    let s = sphere.to_str().unwrap();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", s, "--viewport", "64x64", "--out", "o"];
        args.extend(extra);
        let out = run(&args, dir.path());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let o = dir.path().join("o");
    render(&["--reference"]);
    std::fs::write(o.join("notes.txt"), "mine").unwrap();
    let with_reference = [
        "error.png",
        "flip.png",
        "image.png",
        "manifest.json",
        "notes.txt",
        "reference.png",
        "report.html",
        "report.json",
        "report.txt",
    ];
    assert_eq!(files_in(&o), with_reference);
    render(&["--mode", "functional"]);
    assert_eq!(
        files_in(&o),
        [
            "image.png",
            "manifest.json",
            "notes.txt",
            "report.html",
            "report.json",
            "report.txt"
        ]
    );
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["command"], "render");
    assert_eq!(
        m["files"],
        serde_json::json!([
            "image.png",
            "report.json",
            "report.txt",
            "report.html",
            "manifest.json"
        ])
    );
    // A trace written into the folder under a name of the replaced set is this run's: kept.
    render(&["--reference"]);
    render(&["--trace-out", "o/reference.png"]);
    let trace = std::fs::read_to_string(o.join("reference.png")).unwrap();
    assert!(
        trace.contains("traceEvents"),
        "the trace, not the old image"
    );
    assert!(!o.join("error.png").exists() && !o.join("flip.png").exists());
}

/// Output paths that cannot be written are usage errors, refused before any work (exit
/// 2), naming the flag: a folder flag naming a file, a file flag naming a folder.
#[test]
fn output_paths_of_the_wrong_kind_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("file"), "x").unwrap();
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    let smoke = manifest().join("sim/sweeps/smoke.json");
    for (args, flag) in [
        (vec!["render", "--out", "file"], "--out"),
        (
            vec!["render", "--out", "o", "--trace-out", "folder"],
            "--trace-out",
        ),
        (vec!["compare", "--out", "file"], "--out"),
        (
            vec!["sweep", smoke.to_str().unwrap(), "--out", "file"],
            "--out",
        ),
        (vec!["sweep-merge", "--out", "file", "folder"], "--out"),
    ] {
        let out = run(&args, dir.path());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(&format!("field `{flag}`")),
            "{args:?}: {stderr}"
        );
        assert_eq!(files_in(dir.path()), ["file", "folder"], "{args:?}");
        assert!(files_in(&dir.path().join("folder")).is_empty());
    }
}

/// `--set FIELD=VALUE` sets architecture fields on top of `--arch`, as a sweep's `arch.`
/// parameters do: the run is the one a sweep point with those values gives (the answer's
/// rows are reproduced this way); a field that does not exist, a value it does not take,
/// or the flag in functional mode is refused by name.
#[test]
fn set_overrides_architecture_fields_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = manifest().join("sim/arch/gpu.json");
    let report = report_of_run(
        &[
            "render",
            "--viewport",
            "64x64",
            "--arch",
            gpu.to_str().unwrap(),
            "--set",
            "rasterizer.count=8",
            "--set",
            "tessellation.source=memory",
            "--out",
            "o",
        ],
        dir.path(),
    );
    assert_eq!(report["arch"]["rasterizer"]["count"], 8);
    assert_eq!(report["arch"]["tessellation"]["source"], "memory");
    // Everything else is the file's.
    assert_eq!(report["arch"]["interval_manager"]["count"], 4);
    let rasterizers = report["cycles"]["units"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|u| u["kind"] == "FragmentRasterizer")
        .count();
    assert_eq!(rasterizers, 8);
    for (args, needle) in [
        (
            &["render", "--set", "rasterizer.cnt=8"][..],
            "--set rasterizer.cnt",
        ),
        (
            &["render", "--set", "rasterizer.count=0"][..],
            "rasterizer.count",
        ),
        (
            &["render", "--set", "rasterizer.count=x"][..],
            "--set rasterizer.count",
        ),
        (&["render", "--set", "rasterizer"][..], "FIELD=VALUE"),
        (
            &["render", "--mode", "functional", "--set", "rop.count=2"][..],
            "--set",
        ),
        (&["compare", "--set", "rop.count=0"][..], "rop.count"),
    ] {
        assert_refused(args, needle);
    }
}

/// The reference's tile side and threads are refused out of range or without
/// `--reference`, by name; within range they change no pixel and no metric (the reference
/// traces the same lembos in the same order at any tile side and thread count).
#[test]
fn reference_tile_and_threads_change_nothing_measured() {
    for (flag, bad) in [
        ("--reference-tile", "3"),
        ("--reference-tile", "1025"),
        ("--reference-threads", "0"),
        ("--reference-threads", "257"),
    ] {
        assert_refused(
            &["render", "--reference", flag, bad],
            &format!("field `{flag}` = {bad}"),
        );
        assert_refused(&["compare", flag, bad], &format!("field `{flag}` = {bad}"));
    }
    assert_refused(
        &["render", "--reference-tile", "8"],
        "only meaningful with --reference",
    );
    assert_refused(
        &["render", "--reference-threads", "1"],
        "only meaningful with --reference",
    );
    let dir = tempfile::tempdir().unwrap();
    let s = scene_file(dir.path(), "s.json", GOOD);
    let mut seen = Vec::new();
    for (tile, threads) in [("16", "2"), ("4", "1"), ("7", "3"), ("1024", "2")] {
        let args = [
            "--mode",
            "functional",
            "--reference",
            "--reference-tile",
            tile,
            "--reference-threads",
            threads,
        ];
        let (r, _) = render_into(dir.path(), &s, &format!("t{tile}"), &args);
        // The report says what it was measured with.
        let host = &r["host"];
        assert_eq!(host["reference_tile_px"].to_string(), tile, "{host}");
        assert_eq!(host["reference_threads"].to_string(), threads, "{host}");
        let text = std::fs::read_to_string(dir.path().join(format!("t{tile}/report.txt"))).unwrap();
        assert!(
            text.contains(&format!(", {tile} px tiles, {threads} reference threads")),
            "{text}"
        );
        let reference = std::fs::read(dir.path().join(format!("t{tile}/reference.png"))).unwrap();
        seen.push((reference, r["accuracy"].clone()));
    }
    assert!(seen[0].1["psnr_db"].as_f64().unwrap() > 20.0);
    assert!(seen.windows(2).all(|w| w[0] == w[1]));
    // Without the reference, nothing to echo.
    let (r, _) = render_into(dir.path(), &s, "none", &["--mode", "functional"]);
    assert!(r["host"]["reference_tile_px"].is_null());
    assert!(r["host"]["reference_threads"].is_null());
}

/// The memory guard's estimate of a run measured against the exact reference holds the
/// run's measured peak, on both paths, and is not so far above it that it would refuse
/// scenes the reference handles (at most 3x: the estimate's fixed 96 MB dominates here).
#[test]
fn the_memory_estimate_of_a_measured_run_holds_its_peak() {
    use lembo_sim::datapath::Datapath;
    use lembo_sim::job::{load_scene, memory_estimate, PrimitivePath, RenderJob};
    let dir = tempfile::tempdir().unwrap();
    let terrain = manifest().join("traces/terrain320.json");
    for (path, tess) in [
        (PrimitivePath::Lembo, None),
        (PrimitivePath::Triangle, Some(2)),
    ] {
        let job = RenderJob {
            scene: Some(terrain.clone()),
            reference: true,
            viewport: Some((256, 256)),
            path,
            tess,
            ..crate::support::render_job(0.5, Datapath::F32)
        };
        let estimate = memory_estimate(&job, &load_scene(&job).unwrap(), 0.0);
        let mut args = vec![
            "render",
            terrain.to_str().unwrap(),
            "--viewport",
            "256x256",
            "--mode",
            "functional",
            "--reference",
            "--out",
            "o",
        ];
        if tess.is_some() {
            args.extend(["--path", "triangle", "--tess", "2"]);
        }
        let report = report_of_run(&args, dir.path());
        let peak = report["host"]["peak_rss_bytes"].as_f64().unwrap();
        eprintln!(
            "{path:?}: peak {:.0} MB, estimate {:.0} MB",
            peak / 1e6,
            estimate / 1e6
        );
        assert!(
            peak <= estimate,
            "{path:?}: peak {peak} above the estimate {estimate}"
        );
        assert!(
            estimate <= 3.0 * peak,
            "{path:?}: estimate {estimate} over 3x the peak {peak}"
        );
    }
}
