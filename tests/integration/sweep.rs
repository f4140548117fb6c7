//! `lembo-sim sweep` and `sweep-merge` as a user meets them: sim/sweeps/smoke.json end to
//! end, an interrupted sweep finished by a rerun, shards merged, and bad specs refused
//! before any run. Outputs are compared with host timing masked (`report.host` in the
//! records, `wall_seconds` in the table); everything else must be equal.

use crate::support::{binary, golden};
use lembo_sim::sweep::Plan;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

fn manifest() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn smoke() -> PathBuf {
    manifest().join("sim/sweeps/smoke.json")
}

fn sweep(args: &[&str], envs: &[(&str, &str)], cwd: &Path) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lembo-sim"));
    cmd.args(args)
        .current_dir(cwd)
        .env_remove("LEMBO_SWEEP_STOP_AFTER")
        .env_remove("LEMBO_MEMORY_AVAILABLE");
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.output().expect("the binary runs")
}

fn ok(out: &Output) {
    assert!(
        out.status.success(),
        "status {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
}

fn run_smoke(dir: &Path, extra: &[&str], envs: &[(&str, &str)]) -> Output {
    let spec = smoke();
    let out = dir.to_string_lossy().into_owned();
    let mut args = vec![
        "sweep",
        spec.to_str().unwrap(),
        "--out",
        &out,
        "--jobs",
        "2",
    ];
    args.extend_from_slice(extra);
    sweep(&args, envs, dir.parent().unwrap())
}

/// A sweep directory's results with host timing masked: the records, the table and the
/// spec copy.
#[derive(Debug, PartialEq)]
struct Masked {
    records: Vec<Value>,
    csv: Vec<Vec<String>>,
    spec: Vec<u8>,
}

fn masked(dir: &Path) -> Masked {
    let text = std::fs::read_to_string(dir.join("results.jsonl")).unwrap();
    let records = text
        .lines()
        .map(|l| {
            let mut r: Value = serde_json::from_str(l).unwrap();
            let host = r["report"]
                .as_object_mut()
                .unwrap()
                .remove("host")
                .expect("every record has host timing");
            assert!(host["wall_seconds"].is_number());
            r
        })
        .collect();
    let mut reader = csv::Reader::from_path(dir.join("results.csv")).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let wall = header.iter().position(|h| h == "wall_seconds").unwrap();
    let mut csv = vec![header];
    for row in reader.records() {
        let mut row: Vec<String> = row.unwrap().iter().map(String::from).collect();
        assert!(row[wall].parse::<f64>().is_ok(), "{row:?}");
        row[wall].clear();
        csv.push(row);
    }
    Masked {
        records,
        csv,
        spec: std::fs::read(dir.join("spec.json")).unwrap(),
    }
}

/// One uninterrupted, unsharded run of smoke.json, shared by the tests that compare
/// against it.
fn reference_run() -> &'static Masked {
    static RUN: OnceLock<Masked> = OnceLock::new();
    RUN.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("full");
        ok(&run_smoke(&dir, &[], &[]));
        masked(&dir)
    })
}

#[test]
fn smoke_runs_end_to_end() {
    let full = reference_run();
    let plan = Plan::load(&smoke()).unwrap();
    let runs = plan.spec.runs.len();
    assert!(runs >= 8, "smoke.json should have a few runs, has {runs}");
    assert_eq!(full.records.len(), runs);
    assert_eq!(full.csv.len(), runs + 1);
    assert_eq!(full.spec, std::fs::read(smoke()).unwrap());
    for (i, (r, run)) in full.records.iter().zip(&plan.spec.runs).enumerate() {
        assert_eq!(r["index"], i);
        assert_eq!(r["key"], run.key.as_str());
        assert_eq!(
            r["params"],
            serde_json::to_value(&plan.spec.points[run.point].params).unwrap()
        );
        assert_eq!(r["report"]["schema_version"], 9);
        // Timed with the reference: cycles, cost and accuracy in every record.
        assert!(r["report"]["cycles"]["total"].as_u64().unwrap() > 0);
        assert!(r["report"]["cost"]["area_mm2"].as_f64().unwrap() > 0.0);
        assert!(r["report"]["accuracy"]["psnr_db"].as_f64().unwrap() > 10.0);
        assert_eq!(
            r["report"]["scene"]["source"],
            plan.spec.scenes[run.scene].as_str()
        );
    }
    // A parameter takes effect: the f64 point's report says so, the 4-segmenter point has
    // four segmenters.
    let report_of = |param: &str| {
        &full
            .records
            .iter()
            .find(|r| r["params"].get(param).is_some())
            .unwrap()["report"]
    };
    assert_eq!(report_of("datapath")["settings"]["datapath"], "f64");
    assert_eq!(
        report_of("arch.segmenter.count")["arch"]["segmenter"]["count"],
        4
    );
    let header = &full.csv[0];
    for col in [
        "index",
        "scene",
        "k",
        "tess",
        "arch.segmenter.count",
        "cycles_total",
        "fps",
        "bottleneck",
        "util.Segmenter[3]",
        "acc.psnr_db",
        "primitives",
        "primitive_bytes",
        "fragments",
        "blend.error_mean",
        "blend.error_max",
        "wall_seconds",
    ] {
        assert!(
            header.iter().any(|h| h == col),
            "no column {col} in {header:?}"
        );
    }
}

#[test]
fn an_interrupted_sweep_finishes_on_rerun_as_if_uninterrupted() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("interrupted");
    let out = run_smoke(&dir, &[], &[("LEMBO_SWEEP_STOP_AFTER", "3")]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let partial = std::fs::read_to_string(dir.join("results.jsonl")).unwrap();
    assert_eq!(partial.lines().count(), 3);
    assert!(!dir.join("results.csv").exists());
    // A kill in the middle of a write leaves a truncated last line.
    let first = partial.lines().next().unwrap();
    let torn = format!("{partial}{}", &first[..first.len() / 2]);
    std::fs::write(dir.join("results.jsonl"), torn).unwrap();

    let out = run_smoke(&dir, &[], &[]);
    ok(&out);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("(3 already done)"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert_eq!(&masked(&dir), reference_run());
}

#[test]
fn merged_shards_equal_the_unsharded_sweep() {
    let tmp = tempfile::tempdir().unwrap();
    for n in [2, 3] {
        let mut dirs = Vec::new();
        for i in 0..n {
            let dir = tmp.path().join(format!("shard{i}of{n}"));
            ok(&run_smoke(&dir, &["--shard", &format!("{i}/{n}")], &[]));
            dirs.push(dir.to_string_lossy().into_owned());
        }
        let merged = tmp.path().join(format!("merged{n}"));
        let merged_s = merged.to_string_lossy().into_owned();
        let mut args = vec!["sweep-merge", "--out", &merged_s];
        args.extend(dirs.iter().map(String::as_str));
        ok(&sweep(&args, &[], tmp.path()));
        assert_eq!(&masked(&merged), reference_run(), "{n} shards");

        // Without one shard the merge is refused and writes nothing.
        let partial = tmp.path().join(format!("partial{n}"));
        let partial_s = partial.to_string_lossy().into_owned();
        let out = sweep(
            &["sweep-merge", "--out", &partial_s, &dirs[0]],
            &[],
            tmp.path(),
        );
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains("in no shard"));
        assert!(!partial.exists());
    }
}

/// A bad spec (or flag) is refused with status 2, an error naming `needle`, and no
/// results.jsonl.
fn assert_refused(spec: &str, extra: &[&str], needle: &str) {
    assert_refused_with(spec, extra, &[], needle);
}

/// As [`assert_refused`], with the environment variables `envs` set.
fn assert_refused_with(spec: &str, extra: &[&str], envs: &[(&str, &str)], needle: &str) {
    let tmp = tempfile::tempdir().unwrap();
    let spec_path = tmp.path().join("bad.json");
    std::fs::write(&spec_path, spec).unwrap();
    let out_dir = tmp.path().join("out");
    let out_s = out_dir.to_string_lossy().into_owned();
    let mut args = vec!["sweep", spec_path.to_str().unwrap(), "--out", &out_s];
    args.extend_from_slice(extra);
    let out = sweep(&args, envs, tmp.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{spec}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{spec}: expected `{needle}` in {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!out_dir.join("results.jsonl").exists(), "{spec}");
}

/// A spec of `rest` on the sphere at 32x32.
fn small_spec(rest: &str) -> String {
    let scene = manifest().join("traces/sphere24.json");
    format!(
        r#"{{"name": "bad", "scenes": [{:?}], "viewport": [32, 32], {rest}}}"#,
        scene.to_string_lossy()
    )
}

#[test]
fn bad_specs_are_refused_before_any_run() {
    for (rest, needle) in [
        (r#""grid": [{"k": [1]}], "colour": "red""#, "field `colour`"),
        (r#""grid": [{"k": []}]"#, "field `grid[0].k` = []"),
        (
            r#""points": [{"k": 0.5}, {"k": 100}]"#,
            "field `points[1].k` = 100",
        ),
        (r#""grid": [{"k": [0.5, 0]}]"#, "field `grid[0].k[1]` = 0"),
        (
            r#""points": [{"arch.segmenter.cnt": 4}]"#,
            "field `points[0].arch.segmenter.cnt`: unknown architecture field",
        ),
        (
            r#""grid": [{"k": [1]}, {"arch.rop.count": [2, 0]}]"#,
            "field `grid[1].arch.rop.count[1]` = 0",
        ),
        (
            r#""grid": [{"arch.interval_manager.count": [2, 65]}]"#,
            "field `grid[0].arch.interval_manager.count[1]` = 65",
        ),
        (
            r#""points": [{"arch.links.rasterizer_to_rop.fifo_depth": 0}]"#,
            "field `points[0].arch.links.rasterizer_to_rop.fifo_depth` = 0",
        ),
        (r#""points": [{"tess": 2}]"#, "field `points[0].tess`"),
        (
            r#""grid": [{"perspective_tol": [0.1, -1]}]"#,
            "field `grid[0].perspective_tol[1]` = -1",
        ),
        (
            r#""points": [{"perspective_tol": "on"}]"#,
            "field `points[0].perspective_tol`",
        ),
        (
            r#""points": [{"path": "triangle", "perspective_tol": "off"}]"#,
            "field `points[0].perspective_tol`",
        ),
        (r#""points": [{"blend": "f16"}]"#, "has no discoids"),
        (
            r#""grid": [{"samples": [1, 3]}]"#,
            "field `grid[0].samples[1]` = 3",
        ),
        (
            r#""points": [{"samples": "4"}]"#,
            "field `points[0].samples`",
        ),
        (
            r#""points": [{"tech.dram.pj_per_byte": -1}]"#,
            "field `points[0].tech.dram.pj_per_byte` = -1",
        ),
        (
            r#""grid": [{"tech.dram.pj_per_byte": [1, 0]}]"#,
            "field `grid[0].tech.dram.pj_per_byte[1]` = 0",
        ),
        (
            r#""points": [{"tech.sram.leakage": 1}]"#,
            "field `points[0].tech.sram.leakage`: unknown technology field",
        ),
        (
            r#""grid": [{"arch.framebuffer.access_cycles": [0.5, 0.3]}]"#,
            "field `grid[0].arch.framebuffer.access_cycles[1]` = 0.3",
        ),
        (
            r#""points": [{"arch.rop.fragments_per_cycle": 0}]"#,
            "field `points[0].arch.rop.fragments_per_cycle` = 0",
        ),
    ] {
        assert_refused(&small_spec(rest), &[], needle);
    }
    let good = small_spec(r#""grid": [{"k": [1]}]"#);
    for (flags, needle) in [
        (&["--shard", "2/2"][..], "--shard"),
        (&["--shard", "0/0"][..], "--shard"),
        (&["--shard", "1"][..], "--shard"),
        (&["--jobs", "0"][..], "--jobs"),
    ] {
        assert_refused(&good, flags, needle);
    }
}

#[test]
fn a_directory_of_another_spec_is_not_resumed() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out");
    let first = tmp.path().join("a.json");
    let spec = |k: &str| small_spec(&format!(r#""reference": false, "grid": [{{"k": [{k}]}}]"#));
    std::fs::write(&first, spec("1")).unwrap();
    let args = |d: &Path| {
        vec![
            "sweep".to_string(),
            first.to_string_lossy().into_owned(),
            "--out".into(),
            d.to_string_lossy().into_owned(),
        ]
    };
    let run = |a: Vec<String>| {
        sweep(
            &a.iter().map(String::as_str).collect::<Vec<_>>(),
            &[],
            tmp.path(),
        )
    };
    ok(&run(args(&dir)));
    std::fs::write(&first, spec("2")).unwrap();
    let out = run(args(&dir));
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("field `grid`") && stderr.contains("another spec"),
        "{stderr}"
    );
}

/// A discoid sweep over the blend modes is priced like any timed sweep: results.csv's area
/// and energy are filled for every mode, and the narrower modes cost less.
/// Writes a spec on the shipped `scene` with the rest of its fields `rest` into `tmp`, runs
/// it to completion and returns its output folder.
fn run_spec(tmp: &Path, scene: &str, rest: &str) -> PathBuf {
    let scene = manifest().join("traces").join(scene);
    let spec = tmp.join("spec.json");
    std::fs::write(
        &spec,
        format!(r#"{{"scenes": [{:?}], {rest}}}"#, scene.to_string_lossy()),
    )
    .unwrap();
    let dir = tmp.join("out");
    ok(&sweep(
        &[
            "sweep",
            spec.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ],
        &[],
        tmp,
    ));
    dir
}

#[test]
fn a_discoid_sweep_has_area_and_energy() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = run_spec(
        tmp.path(),
        "discoid_sphere20.json",
        r#""name": "blend", "viewport": [64, 64], "reference": false,
           "grid": [{"blend": ["rgba8", "f16", "f32"]}]"#,
    );
    let table = masked(&dir).csv;
    let column = |name: &str| table[0].iter().position(|h| h == name).unwrap();
    let (blend, area, energy) = (column("blend"), column("area_mm2"), column("energy_pj"));
    let mut by_mode: Vec<(String, f64, f64)> = table[1..]
        .iter()
        .map(|row| {
            let number = |k: usize| row[k].parse::<f64>().unwrap_or_else(|_| panic!("{row:?}"));
            (row[blend].clone(), number(area), number(energy))
        })
        .collect();
    by_mode.sort_by(|a, b| a.1.total_cmp(&b.1));
    let modes: Vec<&str> = by_mode.iter().map(|(m, _, _)| m.as_str()).collect();
    assert_eq!(modes, ["rgba8", "f16", "f32"], "smallest first");
    assert!(by_mode.windows(2).all(|w| w[0].2 < w[1].2), "{by_mode:?}");
}

/// `samples` on a sweep axis: every run is measured against the area-averaged colours
/// (one target for all sample counts), the records and the table carry the samples, 4
/// samples beat 1 at the same k against that target, and the tradeoff plot keeps each
/// sample count a series of its own.
#[test]
fn a_sweep_puts_samples_on_an_axis() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = run_spec(
        tmp.path(),
        "sphere24.json",
        r#""name": "aa", "viewport": [48, 48],
           "grid": [{"samples": [1, 4], "k": [0.25, 1]},
                    {"samples": [1, 4], "path": ["triangle"], "tess": [2, 8]}]"#,
    );
    let run = masked(&dir);
    assert_eq!(run.records.len(), 8);
    for r in &run.records {
        let samples = r["params"]["samples"].as_u64().unwrap();
        let settings = &r["report"]["settings"];
        assert_eq!(settings["samples"].as_u64(), Some(samples));
        // Every run of a scene whose runs mix sample counts is measured against the
        // area-averaged colours, 8x8 a pixel: one target for all.
        assert_eq!(r["report"]["accuracy"]["supersample"].as_u64(), Some(8));
        assert_eq!(settings["supersample"].as_u64(), Some(8));
        assert!(r["report"]["cycles"]["total"].as_u64().unwrap() > 0);
    }
    let error = |samples: u64, k: f64| {
        run.records
            .iter()
            .find(|r| r["params"]["samples"] == samples && r["params"]["k"] == k)
            .map(|r| r["report"]["accuracy"]["psnr_db"].as_f64().unwrap())
            .unwrap()
    };
    assert!(
        error(4, 0.25) > error(1, 0.25),
        "PSNR at 4 samples against 1"
    );
    let header = &run.csv[0];
    assert!(header.iter().any(|h| h == "samples"), "{header:?}");
    let svg = std::fs::read_to_string(dir.join("tradeoff_sphere24.svg")).unwrap();
    for series in [
        "lembo path, samples=1",
        "lembo path, samples=4",
        "triangle path, samples=4",
    ] {
        assert!(
            svg.contains(series),
            "no series `{series}` in the tradeoff plot"
        );
    }
}

#[test]
fn every_committed_spec_is_valid() {
    let dir = manifest().join("sim/sweeps");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let plan = Plan::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(path.file_stem().unwrap().to_string_lossy(), plan.spec.name);
            names.push(plan.spec.name);
        }
    }
    names.sort();
    assert_eq!(
        names,
        [
            "antialias",
            "bandwidth",
            "equal_area",
            "fair",
            "fair_ci",
            "fair_dram",
            "fair_large",
            "leaks",
            "perspective",
            "precision",
            "smoke",
            "tradeoff",
            "units"
        ]
    );
}

/// `--host-threads` partitions each timed run's units over host threads: the results are
/// the one-thread sweep's exactly (host timing aside), and 0 threads is refused.
#[test]
fn host_threads_leave_sweep_results_unchanged() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("threads");
    ok(&run_smoke(&dir, &["--host-threads", "3"], &[]));
    assert_eq!(&masked(&dir), reference_run());
    assert_refused(
        &small_spec(r#""grid": [{"k": [1]}]"#),
        &["--host-threads", "0"],
        "--host-threads",
    );
}

/// Every file in `dir` with its bytes, sorted by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| {
            let bytes = std::fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    files.sort();
    files
}

/// A second `sweep` or `sweep-merge` on a folder a live sweep writes is refused at once,
/// naming that process, and changes nothing; the lock a killed sweep leaves is taken over
/// by the next sweep, which finishes as if nothing had happened and releases it.
#[test]
fn a_folder_another_live_sweep_writes_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("locked");
    let dir_s = dir.to_string_lossy().into_owned();
    let lock = dir.join(lembo_sim::sweep::LOCK_FILE);
    // The first sweep takes the lock, then waits before its first rename.
    let mut first = Command::new(env!("CARGO_BIN_EXE_lembo-sim"))
        .args([
            "sweep",
            smoke().to_str().unwrap(),
            "--out",
            &dir_s,
            "--jobs",
            "1",
        ])
        .env("LEMBO_HOLD_BEFORE_RENAME_SECS", "60")
        .env_remove("LEMBO_SWEEP_STOP_AFTER")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while !lock.exists() {
        assert!(
            t0.elapsed().as_secs() < 60,
            "the first sweep never took its lock"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // Its temporaries are written before it holds: wait until they are there and still (a
    // snapshot taken between the lock and their writes would see them change).
    let before = loop {
        let a = snapshot(&dir);
        std::thread::sleep(std::time::Duration::from_millis(200));
        let written = a
            .iter()
            .any(|(name, bytes)| name.ends_with(".tmp") && !bytes.is_empty());
        if written && snapshot(&dir) == a {
            break a;
        }
        assert!(
            t0.elapsed().as_secs() < 60,
            "the first sweep never wrote its temporaries"
        );
    };
    let holder = format!("process {}", first.id());

    let out = run_smoke(&dir, &[], &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--out") && stderr.contains(&holder),
        "{stderr}"
    );
    let merged = tmp.path().join("merged").to_string_lossy().into_owned();
    let out = sweep(&["sweep-merge", "--out", &merged, &dir_s], &[], tmp.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("SHARD_DIR") && stderr.contains(&holder),
        "{stderr}"
    );
    let out = sweep(&["sweep-merge", "--out", &dir_s, &dir_s], &[], tmp.path());
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(snapshot(&dir), before, "a refused command changes nothing");

    first.kill().unwrap(); // SIGKILL: the lock and a temporary stay behind
    first.wait().unwrap();
    assert!(lock.exists());
    ok(&run_smoke(&dir, &[], &[]));
    assert_eq!(&masked(&dir), reference_run());
    assert!(!lock.exists(), "a finished sweep releases its lock");
    let hidden: Vec<String> = snapshot(&dir)
        .into_iter()
        .map(|(n, _)| n)
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
}

/// The cluster recipes of `sim/sweeps/README.md`, run for real in a folder laid out as the repository (the smoke
/// spec under the recipes' spec name): its GNU parallel line over 8 shards, and its Slurm
/// script as 3 array tasks followed by its merge line, each give exactly the unsharded
/// sweep. GNU parallel comes from the distribution's packages (`.ci/run` installs it).
#[test]
fn the_readme_cluster_recipes_give_the_unsharded_sweep() {
    let readme = std::fs::read_to_string(manifest().join("sim/sweeps/README.md")).unwrap();
    let parallel_line = readme
        .lines()
        .find(|l| l.starts_with("parallel -j"))
        .expect("sim/sweeps/README.md has a GNU parallel recipe");
    let start = readme
        .find("#!/bin/bash")
        .expect("sim/sweeps/README.md has a Slurm script");
    let end = start + readme[start..].find("```").unwrap();
    let slurm = readme[start..end].to_string();
    // The merge that follows the Slurm array.
    let merge_line = readme[end..]
        .lines()
        .find(|l| l.starts_with("lembo-sim sweep-merge"))
        .expect("sim/sweeps/README.md has the merge after the Slurm array");
    // The Slurm script names its shard from the array and writes where the merge reads.
    assert!(slurm.contains("--shard \"$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT\""));
    assert!(slurm.contains("--out \"out/sweeps/tradeoff-shards/$SLURM_ARRAY_TASK_ID\""));
    assert!(merge_line.ends_with("out/sweeps/tradeoff-shards/*"));

    let has_parallel = Command::new("parallel").arg("--version").output().is_ok();
    if !has_parallel {
        assert!(
            std::env::var_os("CI").is_none(),
            "GNU parallel is missing; .ci/run installs it"
        );
        eprintln!("skipped: GNU parallel is not installed (apt-get install parallel)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(tmp.path().join("sim/sweeps")).unwrap();
    std::fs::copy(smoke(), tmp.path().join("sim/sweeps/tradeoff.json")).unwrap();
    std::os::unix::fs::symlink(manifest().join("traces"), tmp.path().join("traces")).unwrap();
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_lembo-sim"))
        .parent()
        .unwrap()
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let bash = |script: &str, envs: &[(&str, String)]| {
        let mut cmd = Command::new("bash");
        cmd.arg("-c")
            .arg(script)
            .current_dir(tmp.path())
            .env("PATH", &path)
            .env_remove("LEMBO_SWEEP_STOP_AFTER");
        for (k, v) in envs {
            cmd.env(k, v);
        }
        let out = cmd.output().unwrap();
        ok(&out);
    };
    let merged = tmp.path().join("out/sweeps/tradeoff");

    bash(parallel_line, &[]);
    assert_eq!(&masked(&merged), reference_run(), "GNU parallel, 8 shards");

    std::fs::remove_dir_all(tmp.path().join("out")).unwrap();
    for task in 0..3 {
        bash(
            &slurm,
            &[
                ("SLURM_ARRAY_TASK_ID", task.to_string()),
                ("SLURM_ARRAY_TASK_COUNT", "3".into()),
                ("SLURM_CPUS_PER_TASK", "1".into()),
            ],
        );
    }
    bash(merge_line, &[]);
    assert_eq!(&masked(&merged), reference_run(), "Slurm, 3 array tasks");
}

/// Runs that together would need more memory than the machine has are refused before any
/// run, naming `--jobs` and the estimate; `--no-memory-check` is the way to insist. Two
/// 2048x2048 runs with their reference need about 1.8 GiB, one about 0.8 GiB: on a machine
/// set (`LEMBO_MEMORY_AVAILABLE`) to 1.25 GiB, `--jobs 2` is refused and `--jobs 1` passes
/// the check (`LEMBO_SWEEP_STOP_AFTER=0` then stops it before any run). On the machine's own
/// reading of /proc/meminfo, as many 16384x16384 runs at once (about 50 GiB each) as pass
/// what it has are refused too; only a machine without /proc/meminfo, or with more than
/// about 10 TiB, skips that part, and fails under CI.
#[test]
fn runs_at_once_larger_than_memory_are_refused_before_any_run() {
    let scene = manifest().join("traces/sphere24.json");
    // `runs` runs at `side` x `side` px: k from 1 down in steps of 1/512.
    let spec_of = |side: u32, runs: usize| {
        let ks: Vec<String> = (0..runs)
            .map(|n| (1.0 - n as f64 / 512.0).to_string())
            .collect();
        format!(
            r#"{{"name": "big", "scenes": [{:?}], "viewport": [{side}, {side}], "grid": [{{"k": [{}]}}]}}"#,
            scene.to_string_lossy(),
            ks.join(", ")
        )
    };
    let spec_at = |side: u32| spec_of(side, 2);
    let small_machine = ("LEMBO_MEMORY_AVAILABLE", "1342177280");
    for needle in [
        "field `--jobs` = 2",
        "2.2 GiB (estimate)",
        "--no-memory-check",
    ] {
        assert_refused_with(&spec_at(2048), &["--jobs", "2"], &[small_machine], needle);
    }
    // The control: one run at a time fits the same machine.
    let tmp = tempfile::tempdir().unwrap();
    let spec_path = tmp.path().join("big.json");
    std::fs::write(&spec_path, spec_at(2048)).unwrap();
    let out = sweep(
        &[
            "sweep",
            spec_path.to_str().unwrap(),
            "--out",
            "o",
            "--jobs",
            "1",
        ],
        &[small_machine, ("LEMBO_SWEEP_STOP_AFTER", "0")],
        tmp.path(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("after 0 runs"), "{stderr}");
    // On the machine's own reading of /proc/meminfo: enough 16384x16384 runs at once (about
    // 50 GiB each, counted as 40) to pass what it has, on machines of up to about 10 TiB
    // (--jobs takes at most 256).
    match binary::memory_available() {
        Some(bytes) if bytes < 200.0 * 50.0 * (1u64 << 30) as f64 => {
            let jobs_n = (bytes / (40.0 * (1u64 << 30) as f64)).ceil().max(2.0) as usize;
            let jobs = jobs_n.to_string();
            let field = format!("field `--jobs` = {jobs}");
            for needle in [field.as_str(), "GiB (estimate)", "--no-memory-check"] {
                assert_refused(&spec_of(16384, jobs_n), &["--jobs", &jobs], needle);
            }
            eprintln!("{:.1} GiB available", bytes / (1u64 << 30) as f64);
        }
        available => crate::support::skip_part(&format!(
            "the part on this machine's own memory: {available:?} bytes available"
        )),
    }
}

/// A results table as cases for [`golden::differences`]: each row under its index, scene
/// and point, as `column = value` lines, without the host's `wall_seconds`.
fn table_cases(csv: &str) -> BTreeMap<String, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    lines
        .map(|row| {
            let cells: Vec<&str> = row.split(',').collect();
            let text = header
                .iter()
                .zip(&cells)
                .filter(|(h, _)| **h != "wall_seconds")
                .map(|(h, c)| format!("{h} = {c}"))
                .collect::<Vec<_>>()
                .join("\n");
            (format!("row {}", cells.first().unwrap_or(&"?")), text)
        })
        .collect()
}

/// The committed results checked only with LEMBO_FULL_CHECKS=1.
const FULL_ONLY: [&str; 4] = ["fair", "fair_dram", "bandwidth", "fair_large"];

/// The committed sweep results README and RESULTS quote (`sim/sweeps/results/NAME/`, from
/// `sim/sweeps/NAME.json`) are what the code computes now: each spec is swept again and its
/// table (host time aside), the plots committed beside it and its `answer.md` (if
/// committed) must equal the committed ones. `LEMBO_BLESS=1`
/// rewrites the committed files instead, after printing what changed (then re-read the
/// quoted figures in README.md and RESULTS.md).
#[test]
fn committed_sweep_results_are_what_the_code_computes() {
    let results = manifest().join("sim/sweeps/results");
    let mut names: Vec<String> = std::fs::read_dir(&results)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 2, "committed results: {names:?}");
    let bless = golden::blessing();
    // The full answer takes too long for every test run (README.md, "Results", gives its
    // time): it is checked with LEMBO_FULL_CHECKS=1, and its reduced form `fair_ci`, the
    // same spec on three scenes at 160x160, on every run.
    let full = crate::support::full_checks();
    let mut failures = Vec::new();
    for name in names
        .iter()
        .filter(|n| full || !FULL_ONLY.contains(&n.as_str()))
    {
        let committed = results.join(name);
        let spec = manifest().join(format!("sim/sweeps/{name}.json"));
        assert!(
            spec.exists(),
            "{} has no spec {}",
            committed.display(),
            spec.display()
        );
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        ok(&sweep(
            &[
                "sweep",
                spec.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--jobs",
                "2",
            ],
            &[],
            dir.path(),
        ));
        // The table, row by row.
        let read = |d: &Path, f: &str| std::fs::read_to_string(d.join(f)).unwrap_or_default();
        let want = table_cases(&read(&committed, "results.csv"));
        let got = table_cases(&read(&out, "results.csv"));
        assert!(got.len() >= 10, "{name}: {} rows swept", got.len());
        let mut differ = golden::differences(&want, &got);
        // The plots committed (a chosen few of the sweep's), byte for byte.
        let svgs = |d: &Path| -> BTreeMap<String, Vec<u8>> {
            std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "svg"))
                .map(|p| {
                    let bytes = std::fs::read(&p).unwrap();
                    (p.file_name().unwrap().to_string_lossy().into_owned(), bytes)
                })
                .collect()
        };
        let (want_svg, got_svg) = (svgs(&committed), svgs(&out));
        assert!(!want_svg.is_empty(), "{name}: no plot committed");
        // The answer and the answer by value, when committed, word for word.
        let pages: Vec<String> = std::fs::read_dir(&committed)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f.ends_with(".md"))
            .collect();
        for page in &pages {
            if read(&committed, page) != read(&out, page) {
                differ.push(format!("{page} differs"));
            }
        }
        for (plot, bytes) in &want_svg {
            match got_svg.get(plot) {
                None => differ.push(format!("{plot}: no longer drawn")),
                Some(g) if g != bytes => differ.push(format!("{plot}: differs")),
                Some(_) => {}
            }
        }
        if bless {
            eprintln!(
                "{}: {} of {} rows and plots changed in {}",
                golden::BLESS,
                differ.len(),
                got.len() + want_svg.len(),
                committed.display()
            );
            for d in differ.iter().take(5) {
                eprintln!("  {d}");
            }
            std::fs::copy(out.join("results.csv"), committed.join("results.csv")).unwrap();
            for page in &pages {
                std::fs::copy(out.join(page), committed.join(page)).unwrap();
            }
            for plot in want_svg.keys() {
                match got_svg.contains_key(plot) {
                    true => std::fs::copy(out.join(plot), committed.join(plot)).map(drop),
                    false => std::fs::remove_file(committed.join(plot)),
                }
                .unwrap();
            }
        } else if !differ.is_empty() {
            failures.push(format!(
                "{}: {} of {} rows and plots differ from what the code computes (rerun with \
                 LEMBO_BLESS=1, then update the figures README.md and RESULTS.md quote):\n{}",
                committed.display(),
                differ.len(),
                want.len() + want_svg.len(),
                differ
                    .iter()
                    .take(8)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join("\n")
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// A spec that refines both paths' knobs on the sphere at 48x48 (about a second), with a
/// sensitivity study of two parameters; `rest` adds fields.
fn refine_spec(rest: &str) -> String {
    let scene = manifest().join("traces/sphere24.json");
    format!(
        r#"{{"name": "refine", "scenes": [{:?}], "viewport": [48, 48],
            "area_budget_mm2": 100,
            "refine": {{"margin_db": 0.5, "k_floor": 0.05, "tess_cap": 16}},
            "targets": {{"psnr_db": [30, 35]}},
            "sensitivity": {{"target": {{"psnr_db": 30}},
                "params": ["arch.framebuffer.bytes_per_cycle",
                           {{"param": "arch.interval_manager.count", "path": "lembo", "low": 1, "high": 4}}]}},
            "grid": [{{"path": ["lembo"], "k": [2, 1]}},
                     {{"path": ["triangle"], "tess": [1, 2]}},
                     {{"path": ["lembo"], "k": [2, 1], "arch.rop.count": [2]}}]{rest}}}"#,
        scene.to_string_lossy()
    )
}

fn run_refine(tmp: &Path, name: &str, spec: &str, envs: &[(&str, &str)]) -> (PathBuf, Output) {
    let path = tmp.join(format!("{name}.json"));
    std::fs::write(&path, spec).unwrap();
    let dir = tmp.join(name);
    let out = sweep(
        &[
            "sweep",
            path.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
            "--jobs",
            "2",
        ],
        envs,
        tmp,
    );
    (dir, out)
}

/// Refinement goes past the grid's last k and n until each series is bracketed or reaches
/// the floor or cap, says why each ended, and a sweep stopped inside a refinement round
/// finishes on rerun as if it had not been stopped.
#[test]
fn a_refined_sweep_brackets_each_knob_and_resumes_as_if_uninterrupted() {
    let tmp = tempfile::tempdir().unwrap();
    let (whole, out) = run_refine(tmp.path(), "whole", &refine_spec(""), &[]);
    ok(&out);
    let m = masked(&whole);
    let params: Vec<&Value> = m.records.iter().map(|r| &r["params"]).collect();
    // The grid's 6 points, the variants (2 x 4 lembo and triangle points + 2 x 2 lembo
    // ones), and refinement beyond k = 1 and n = 2.
    let finer_k = params
        .iter()
        .any(|p| p["k"].as_f64().is_some_and(|k| k < 1.0));
    let finer_n = params
        .iter()
        .any(|p| p["tess"].as_u64().is_some_and(|n| n > 2));
    assert!(finer_k && finer_n, "{params:?}");
    // No variant is refined.
    assert!(params
        .iter()
        .filter(|p| p.get("sensitivity").is_some())
        .all(|p| p["k"].as_f64().is_none_or(|k| k >= 1.0)
            && p["tess"].as_u64().is_none_or(|n| n <= 2)));
    let answer = std::fs::read_to_string(whole.join("answer.md")).unwrap();
    for part in [
        "## Bracketing",
        "## Speed-up against target error",
        "| sphere24 | 30.0 dB |",
        "## What flips it",
        "| arch.interval_manager.count | = 1 | = 4 |",
    ] {
        assert!(answer.contains(part), "no `{part}` in {answer}");
    }
    let bracket: Vec<&str> = answer
        .lines()
        .skip_while(|l| !l.starts_with("## Bracketing"))
        .take_while(|l| !l.starts_with("## Speed-up"))
        .filter(|l| l.starts_with("| sphere24 |"))
        .collect();
    assert_eq!(bracket.len(), 2, "{answer}");
    for row in &bracket {
        assert!(
            row.contains("bracketed: the last two refinements")
                || row.contains("stopped at the floor k = 0.05")
                || row.contains("stopped at the cap n = 16"),
            "{row}"
        );
    }
    for figure in [
        "speedup_psnr_db_sphere24.svg",
        "tornado_cycles_sphere24.svg",
        "tornado_energy_sphere24.svg",
    ] {
        assert!(whole.join(figure).exists(), "{figure}");
    }
    let html = std::fs::read_to_string(whole.join("report.html")).unwrap();
    assert!(html.contains("## Bracketing") && html.contains("speedup_psnr_db_sphere24.svg"));
    // The coarse side ended too, and said how: the lembo path's beyond the grid's k = 2
    // unless k = 2 already saved under the margin, the triangle path's at n = 1.
    for row in &bracket {
        assert!(
            row.ends_with("exists |")
                || row.contains("of the level finer than it, under the")
                || row.contains("stopped at the ceiling"),
            "{row}"
        );
    }
    reproduce_named_runs(tmp.path(), &answer, &m.records);

    // Stopped after the grid and its variants and part of the first round, then rerun.
    let grid_and_variants = m
        .records
        .iter()
        .filter(|r| {
            r["params"].get("sensitivity").is_some()
                || r["params"]["k"].as_f64().is_some_and(|k| k >= 1.0)
                || r["params"]["tess"].as_u64().is_some_and(|n| n <= 2)
        })
        .count();
    let stop = (grid_and_variants + 1).to_string();
    let (part, out) = run_refine(
        tmp.path(),
        "part",
        &refine_spec(""),
        &[("LEMBO_SWEEP_STOP_AFTER", &stop)],
    );
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (again, out) = run_refine(tmp.path(), "part", &refine_spec(""), &[]);
    ok(&out);
    assert_eq!(again, part);
    assert_eq!(masked(&part), m);
    assert_eq!(
        std::fs::read(part.join("answer.md")).unwrap(),
        answer.as_bytes()
    );

    // A refinement runs in one process: no shards.
    let (_, out) = run_refine(tmp.path(), "sharded", &refine_spec(""), &[]);
    ok(&out);
    let spec = tmp.path().join("sharded.json");
    let out = sweep(
        &[
            "sweep",
            spec.to_str().unwrap(),
            "--out",
            tmp.path().join("shard").to_str().unwrap(),
            "--shard",
            "0/2",
        ],
        &[],
        tmp.path(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--shard"));
}

/// Every run answer.md names has its command, and the command, pasted into a shell in the
/// spec's folder, draws what the sweep measured: the same cycles, area and PSNR (one run of
/// each path).
fn reproduce_named_runs(spec_dir: &Path, answer: &str, records: &[Value]) {
    let named: std::collections::BTreeSet<u64> = answer
        .split("run ")
        .skip(1)
        .filter_map(|rest| {
            rest.split(|c: char| !c.is_ascii_digit())
                .next()?
                .parse()
                .ok()
        })
        .collect();
    let commands: BTreeMap<u64, &str> = answer
        .lines()
        .filter_map(|l| {
            let rest = l.strip_prefix("- run ")?;
            let (index, command) = rest.split_once(": `")?;
            Some((index.parse().ok()?, command.strip_suffix('`')?))
        })
        .collect();
    assert!(!named.is_empty());
    for index in &named {
        assert!(commands.contains_key(index), "run {index} has no command");
    }
    let record = |index: u64| {
        records
            .iter()
            .find(|r| r["index"] == index)
            .unwrap_or_else(|| panic!("no record of run {index}"))
    };
    for path in ["lembo", "triangle"] {
        let (index, command) = commands
            .iter()
            .find(|(i, _)| record(**i)["params"]["path"] == path)
            .unwrap_or_else(|| panic!("no {path} run named"));
        let command = command.replacen("lembo-sim", env!("CARGO_BIN_EXE_lembo-sim"), 1);
        let out = Command::new("sh")
            .args(["-c", &command])
            .current_dir(spec_dir)
            .output()
            .unwrap();
        ok(&out);
        let report: Value = serde_json::from_str(
            &std::fs::read_to_string(spec_dir.join(format!("out/run{index}/report.json"))).unwrap(),
        )
        .unwrap();
        let record = &record(*index)["report"];
        for at in ["/cycles/total", "/cost/area_mm2", "/accuracy/psnr_db"] {
            assert_eq!(report.pointer(at), record.pointer(at), "run {index}: {at}");
        }
    }
}

/// Without `refine`, a grid that stops while the error still improves is flagged in
/// answer.md where it decides the answer.
#[test]
fn a_grid_that_stops_early_is_flagged_unbracketed() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = manifest().join("traces/sphere24.json");
    let spec = format!(
        r#"{{"name": "early", "scenes": [{:?}], "viewport": [48, 48], "area_budget_mm2": 100,
            "grid": [{{"path": ["lembo"], "k": [4, 2, 1]}}, {{"path": ["triangle"], "tess": [1, 2, 4]}}]}}"#,
        scene.to_string_lossy()
    );
    let (dir, out) = run_refine(tmp.path(), "early", &spec, &[]);
    ok(&out);
    let answer = std::fs::read_to_string(dir.join("answer.md")).unwrap();
    assert!(
        answer.contains("unbracketed: the grid stops at n = 4"),
        "{answer}"
    );
    // The most accurate triangle run at equal area is the grid's last n: flagged.
    let area = answer
        .lines()
        .skip_while(|l| !l.starts_with("## At equal area"))
        .find(|l| l.starts_with("| sphere24 |"))
        .unwrap();
    assert!(
        area.contains("tess=4") && area.contains("**unbracketed**"),
        "{area}"
    );
    // And it names no winner there: a finer n might change which path is more accurate.
    assert!(
        area.contains("no winner:") && !area.contains("more accurate"),
        "{area}"
    );
}

#[test]
fn bad_answer_settings_are_refused_naming_the_field() {
    let scene = manifest().join("traces/sphere24.json");
    let spec = |fields: &str| {
        format!(
            r#"{{"name": "bad", "scenes": [{:?}], "viewport": [32, 32], "area_budget_mm2": 10,
                "grid": [{{"path": ["lembo"], "k": [1]}}], {fields}}}"#,
            scene.to_string_lossy()
        )
    };
    for (fields, needle) in [
        (r#""refine": {"k_floor": 0}"#, "field `refine.k_floor` = 0"),
        (
            r#""refine": {"tess_cap": 4096}"#,
            "field `refine.tess_cap` = 4096",
        ),
        (
            r#""refine": {"margin_db": -1}"#,
            "field `refine.margin_db` = -1",
        ),
        (
            r#""refine": {"cycle_cap": 0}"#,
            "field `refine.cycle_cap` = 0",
        ),
        (r#""refine": {}, "reference": false"#, "field `refine`"),
        (
            r#""targets": {"psnr_db": []}"#,
            "field `targets.psnr_db` = []",
        ),
        (
            r#""targets": {"flip_mean": [0.5, 0]}"#,
            "field `targets.flip_mean[1]` = 0",
        ),
        (
            r#""sensitivity": {"target": {"psnr_db": 40}, "factors": [0, 2], "params": ["arch.rop.count"]}"#,
            "field `sensitivity.factors[0]` = 0",
        ),
        (
            r#""sensitivity": {"target": {"psnr_db": 40}, "factors": [0.5, -1], "params": ["arch.rop.count"]}"#,
            "field `sensitivity.factors[1]` = -1",
        ),
        (
            r#""sensitivity": {"target": {"psnr_db": 40}, "params": ["arch.rop.cnt"]}"#,
            "field `sensitivity.params[0]`",
        ),
        (
            r#""sensitivity": {"target": {"psnr_db": 40}, "params": [{"param": "arch.setup.count", "factors": [0.3, 2]}]}"#,
            "field of whole numbers",
        ),
    ] {
        assert_refused(&spec(fields), &[], needle);
    }
}

/// `tech.dram.pj_per_byte` on a sweep axis prices each run with the embedded technology
/// and that figure: energy moves by exactly the DRAM bytes times the change and nothing
/// else moves; the figure is a column of results.csv and is echoed in the report.
#[test]
fn a_sweep_sets_a_technology_figure() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = run_spec(
        tmp.path(),
        "sphere24.json",
        r#""name": "dram", "viewport": [32, 32], "reference": false,
           "points": [{}, {"tech.dram.pj_per_byte": 325},
                      {"path": "triangle", "tess": 2, "tech.dram.pj_per_byte": 162.5},
                      {"path": "triangle", "tess": 2, "tech.dram.pj_per_byte": 81.25}]"#,
    );
    let run = masked(&dir);
    assert_eq!(run.records.len(), 4);
    let column = run.csv[0]
        .iter()
        .position(|h| h == "tech.dram.pj_per_byte")
        .expect("a results.csv column");
    for pair in run.records.chunks(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let pj = |r: &serde_json::Value| {
            let used = r["report"]["cost"]["tech"]["dram_pj_per_byte"].as_f64();
            let given = r["params"].get("tech.dram.pj_per_byte");
            assert_eq!(given.map_or(Some(162.5), |g| g.as_f64()), used);
            used.unwrap()
        };
        let cost = |r: &serde_json::Value| r["report"]["cost"].clone();
        let (ca, cb) = (cost(a), cost(b));
        let bytes: u64 = ["framebuffer_bytes", "accumulation_bytes", "geometry_bytes"]
            .iter()
            .map(|k| ca[*k].as_u64().unwrap())
            .sum();
        assert!(ca["geometry_bytes"].as_u64().unwrap() > 0);
        let want = bytes as f64 * (pj(b) - pj(a));
        let got = cb["energy_pj"].as_f64().unwrap() - ca["energy_pj"].as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1e-9 * cb["energy_pj"].as_f64().unwrap(),
            "{got} against {want}"
        );
        assert_eq!(ca["area_mm2"], cb["area_mm2"]);
        for k in ["framebuffer_bytes", "accumulation_bytes", "geometry_bytes"] {
            assert_eq!(ca[k], cb[k], "{k}");
        }
        assert_eq!(a["report"]["cycles"], b["report"]["cycles"]);
        assert_eq!(a["report"]["counts"], b["report"]["counts"]);
    }
    // The first point left the figure at the embedded file's: its column says which.
    let cell = |row: usize| run.csv[row][column].parse::<f64>().unwrap();
    assert_eq!((cell(1), cell(2)), (162.5, 325.0));
}

/// The answer by value (issue: "does the answer change if I change X?"): the bunny swept
/// over four frame-buffer bandwidths with `--by` gives one answer.md per bandwidth and a
/// table of how the speed-up moves; the sweep ends with a summary on stdout, whose answer
/// rows are the answer's; a `--by` field the spec does not sweep is refused, naming it.
#[test]
fn an_answer_by_bandwidth_gives_one_answer_a_value_and_how_it_moves() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = manifest().join("traces/bunny.json");
    let spec = format!(
        r#"{{"name": "by", "scenes": [{:?}], "viewport": [64, 64], "area_budget_mm2": 100,
            "targets": {{"psnr_db": [30]}},
            "grid": [{{"path": ["lembo"], "k": [2, 1],
                       "arch.framebuffer.bytes_per_cycle": [8, 16, 32, 64]}},
                     {{"path": ["triangle"], "tess": [1, 2],
                       "arch.framebuffer.bytes_per_cycle": [8, 16, 32, 64]}}]}}"#,
        scene.to_string_lossy()
    );
    let path = tmp.path().join("by.json");
    std::fs::write(&path, &spec).unwrap();
    let dir = tmp.path().join("out");
    let field = "arch.framebuffer.bytes_per_cycle";
    let run = |by: &str| {
        sweep(
            &[
                "sweep",
                path.to_str().unwrap(),
                "--out",
                dir.to_str().unwrap(),
                "--jobs",
                "2",
                "--by",
                by,
            ],
            &[],
            tmp.path(),
        )
    };
    // Refused before any run, naming the flag and what the spec does sweep.
    let out = run("arch.rop.count");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--by") && stderr.contains(field),
        "{stderr}"
    );
    assert!(!dir.join("results.jsonl").exists());

    let out = run(field);
    ok(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stdout = stdout
        .split(' ')
        .filter(|w| !w.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    // The summary: runs, failures, time, the folder, the answer's row and the table.
    for needle in [
        "runs 16 (0 already done)",
        "failed 0",
        "time ",
        "report.html, answer.md, results.csv",
        "bunny: at equal area lembo run ",
        "speed-up at equal PSNR: 30.0 dB",
        "answer_by_arch_framebuffer_bytes_per_cycle.md",
    ] {
        assert!(stdout.contains(needle), "no `{needle}` in\n{stdout}");
    }
    let table =
        std::fs::read_to_string(dir.join("answer_by_arch_framebuffer_bytes_per_cycle.md")).unwrap();
    let records: Vec<Value> = std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let cycles = |i: u64| {
        records.iter().find(|r| r["index"] == i).unwrap()["report"]["cycles"]["total"]
            .as_u64()
            .unwrap()
    };
    for bw in [8, 16, 32, 64] {
        let answer = dir.join(format!(
            "by_arch_framebuffer_bytes_per_cycle/{bw}/answer.md"
        ));
        let answer = std::fs::read_to_string(&answer)
            .unwrap_or_else(|e| panic!("{}: {e}", answer.display()));
        // Each value's answer names only runs at that value.
        let named: Vec<u64> = answer
            .lines()
            .filter_map(|l| l.strip_prefix("- run "))
            .map(|l| l.split(':').next().unwrap().parse().unwrap())
            .collect();
        assert!(!named.is_empty(), "{bw}: no run named");
        for i in &named {
            let r = records.iter().find(|r| r["index"] == *i).unwrap();
            assert_eq!(r["params"][field], bw, "{bw}: run {i}");
        }
        // The table's equal-area row for the value: its runs, and their speed-up.
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("| {bw} | bunny | run ")))
            .unwrap_or_else(|| panic!("no row for {bw} in\n{table}"));
        let runs: Vec<u64> = row
            .split("run ")
            .skip(1)
            .map(|s| s.split(':').next().unwrap().parse().unwrap())
            .collect();
        let speedup = format!("{:.2}x", cycles(runs[1]) as f64 / cycles(runs[0]) as f64);
        assert!(row.contains(&speedup), "{row} lacks {speedup}");
        assert!(
            table.contains(&format!("| {bw} | bunny | 30.0 dB: ")),
            "{table}"
        );
    }
    // Plotted against the bandwidth too, each path holding what the plot says.
    let svg =
        std::fs::read_to_string(dir.join("vs_framebuffer_bytes_per_cycle_bunny.svg")).unwrap();
    assert!(svg.contains("against arch.framebuffer.bytes_per_cycle"));
    // report.html shows the answer and the table.
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("Answer by value") && html.contains("How the answer moves with"));
}

/// A spec over two viewports runs each scene at each, with a reference of its own, and
/// keeps them apart: each viewport its own plots and its own answer rows.
#[test]
fn a_sweep_over_two_viewports_keeps_them_apart() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = run_spec(
        tmp.path(),
        "sphere24.json",
        r#""name": "vp", "viewport": [[48, 48], "64x32"], "area_budget_mm2": 100,
           "grid": [{"path": ["lembo"], "k": [2, 1]}, {"path": ["triangle"], "tess": [1, 2]}]"#,
    );
    let run = masked(&dir);
    assert_eq!(run.records.len(), 8);
    for r in &run.records {
        let scene = &r["report"]["scene"];
        let shown = format!("{}x{}", scene["width"], scene["height"]);
        assert_eq!(r["params"]["viewport"], shown.as_str());
        assert!(r["report"]["accuracy"]["psnr_db"].as_f64().unwrap() > 10.0);
    }
    for stem in ["sphere24_48x48", "sphere24_64x32"] {
        assert!(
            dir.join(format!("tradeoff_{stem}.svg")).exists(),
            "no tradeoff_{stem}.svg"
        );
    }
    let answer = std::fs::read_to_string(dir.join("answer.md")).unwrap();
    for scene in [
        "| sphere24 48x48 | lembo |",
        "| sphere24 64x32 | triangle |",
    ] {
        assert!(answer.contains(scene), "no `{scene}` in\n{answer}");
    }
    // Each run's command reproduces its viewport.
    assert!(answer.contains("--viewport 64x32"), "{answer}");
}
