//! How a run's cost grows with the scene and the frame (RESULTS.md, "How cost grows"):
//! render time and peak memory against lembos (generated terrains of 5 000 to 5 000 000
//! lembos at 1024x1024) and against pixels (the bunny at 512x512 to 4096x4096), in both
//! modes, each point a fresh `lembo-sim render` process.
//!
//! ```text
//! cargo build --release && cargo run --release --example scaling [-- OUT_DIR] [--quick]
//! cargo run --release --example scaling -- --replot [OUT_DIR]
//! ```
//!
//! The first measures and writes `sim/scaling/` (committed; RESULTS.md, "How cost grows"): its
//! times and memory are measurements of the machine it runs on, so a run reproduces their
//! slopes, not their bytes. `--replot` measures nothing: it draws the four plots again from
//! `OUT_DIR/scaling.csv`, byte for byte the committed ones from the committed CSV.
//!
//! Writes `OUT_DIR` (default `sim/scaling/`): `scaling.csv` (one row a run: the sweep, x,
//! mode, lembos, pixels, the render's wall seconds as report.json gives them, the process's
//! wall seconds, its peak resident memory) and four log-log plots with each series' fitted
//! slope: `time_vs_lembos.svg`, `memory_vs_lembos.svg`, `time_vs_pixels.svg`,
//! `memory_vs_pixels.svg`. `--quick` stops at 500 000 lembos and 2048x2048 (a check that it
//! runs, not a measurement). It takes a few minutes on 2 cores; run it on an idle machine.

mod slope;

use lembo_sim::plot::loglog::loglog_svg;
use slope::slope_label;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// One measured run.
struct Run {
    sweep: &'static str,
    x: f64,
    mode: &'static str,
    lembos: u64,
    pixels: u64,
    render_s: f64,
    process_s: f64,
    peak_rss: f64,
}

/// Terrain sizes N (2N² lembos): about 5 k, 16 k, 50 k, 160 k, 500 k, 1.6 M and 5 M.
const TERRAINS: [u32; 7] = [50, 89, 158, 283, 500, 894, 1582];

/// Viewport sides for the pixel sweep.
const SIDES: [u32; 4] = [512, 1024, 2048, 4096];

const MODES: [&str; 2] = ["functional", "timed"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let out = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("sim/scaling"));
    if args.iter().any(|a| a == "--replot") {
        let csv = std::fs::read_to_string(out.join("scaling.csv")).expect("OUT_DIR/scaling.csv");
        plot(&out, &read_csv(&csv));
        return;
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let bin = root.join("target/release/lembo-sim");
    if !bin.is_file() {
        eprintln!(
            "scaling: {} is missing: run `cargo build --release` first",
            bin.display()
        );
        std::process::exit(2);
    }
    let scratch = std::env::temp_dir().join(format!("lembo-scaling-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).expect("a scratch directory");
    let template =
        std::fs::read_to_string(root.join("traces/terrain320.json")).expect("traces/terrain320");
    let mut runs = Vec::new();
    for n in TERRAINS {
        if quick && n > 500 {
            continue;
        }
        let scene = scratch.join(format!("terrain{n}.json"));
        std::fs::write(
            &scene,
            template.replace("terrain320", &format!("terrain{n}")),
        )
        .expect("a scene file");
        for mode in MODES {
            let lembos = 2 * n as u64 * n as u64;
            runs.push(measure(
                &bin,
                &scratch,
                &scene,
                1024,
                mode,
                "lembos",
                lembos as f64,
            ));
        }
    }
    let bunny = root.join("traces/bunny.json");
    for side in SIDES {
        if quick && side > 2048 {
            continue;
        }
        for mode in MODES {
            let pixels = side as f64 * side as f64;
            runs.push(measure(
                &bin, &scratch, &bunny, side, mode, "pixels", pixels,
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    write(&out, &runs);
}

/// One `render` of `scene` at `side`² pixels in `mode`, its figures read from its report.
fn measure(
    bin: &Path,
    scratch: &Path,
    scene: &Path,
    side: u32,
    mode: &'static str,
    sweep: &'static str,
    x: f64,
) -> Run {
    let dir = scratch.join("out");
    let viewport = format!("{side}x{side}");
    let t = Instant::now();
    let status = Command::new(bin)
        .arg("render")
        .arg(scene)
        .args(["--viewport", &viewport, "--mode", mode, "--out"])
        .arg(&dir)
        .stdout(std::process::Stdio::null())
        .status()
        .expect("lembo-sim runs");
    let process_s = t.elapsed().as_secs_f64();
    assert!(
        status.success(),
        "{} at {viewport}, {mode}",
        scene.display()
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("report.json")).expect("report.json"),
    )
    .expect("a report");
    let number = |path: &[&str]| {
        path.iter()
            .fold(&report, |v, k| &v[*k])
            .as_f64()
            .unwrap_or_else(|| panic!("report.json has no {path:?}"))
    };
    let run = Run {
        sweep,
        x,
        mode,
        lembos: number(&["scene", "lembos"]) as u64,
        pixels: side as u64 * side as u64,
        render_s: number(&["host", "wall_seconds"]),
        process_s,
        peak_rss: number(&["host", "peak_rss_bytes"]),
    };
    eprintln!(
        "{sweep:6} {:>9} lembos {viewport:>9} {mode:10} render {:8.3} s, process {:8.3} s, peak {:7.1} MB",
        run.lembos,
        run.render_s,
        run.process_s,
        run.peak_rss / 1e6
    );
    run
}

/// A plot's file name, its y axis and the figure it reads from a run.
type Figure = (&'static str, &'static str, fn(&Run) -> f64);

/// The CSV and the four plots into `out`.
fn write(out: &Path, runs: &[Run]) {
    std::fs::create_dir_all(out).expect("the output directory");
    let mut csv =
        String::from("sweep,x,mode,lembos,pixels,render_seconds,process_seconds,peak_rss_bytes\n");
    for r in runs {
        csv += &format!(
            "{},{},{},{},{},{:.6},{:.6},{}\n",
            r.sweep, r.x, r.mode, r.lembos, r.pixels, r.render_s, r.process_s, r.peak_rss
        );
    }
    std::fs::write(out.join("scaling.csv"), csv).expect("scaling.csv");
    plot(out, runs);
}

/// The runs of a `scaling.csv` this program wrote.
fn read_csv(csv: &str) -> Vec<Run> {
    let label = |v: &str, of: &[&'static str]| -> &'static str {
        of.iter()
            .find(|x| **x == v)
            .unwrap_or_else(|| panic!("scaling.csv: unknown {v:?}"))
    };
    csv.lines()
        .skip(1)
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), 8, "scaling.csv: {line:?}");
            let num = |i: usize| -> f64 {
                f[i].parse()
                    .unwrap_or_else(|e| panic!("scaling.csv: {line:?}: {e}"))
            };
            Run {
                sweep: label(f[0], &["lembos", "pixels"]),
                x: num(1),
                mode: label(f[2], &MODES),
                lembos: num(3) as u64,
                pixels: num(4) as u64,
                render_s: num(5),
                process_s: num(6),
                peak_rss: num(7),
            }
        })
        .collect()
}

/// The four plots into `out`.
fn plot(out: &Path, runs: &[Run]) {
    // The slope from 160 k lembos or 1024² pixels on: where the fixed costs (the binary,
    // the bunny's setup, the frame buffer of 1024²) no longer hide the growth.
    for (sweep, x_desc, tail) in [("lembos", "lembos", 1.6e5), ("pixels", "pixels", 1.0e6)] {
        let figures: [Figure; 2] = [
            ("time", "process wall time [s]", |r| r.process_s),
            ("memory", "peak resident memory [bytes]", |r| r.peak_rss),
        ];
        for (name, y_desc, y) in figures {
            let lines: Vec<(String, Vec<(f64, f64)>)> = MODES
                .iter()
                .map(|&mode| {
                    let points: Vec<(f64, f64)> = runs
                        .iter()
                        .filter(|r| r.sweep == sweep && r.mode == mode)
                        .map(|r| (r.x, y(r)))
                        .collect();
                    (slope_label(mode, &points, tail), points)
                })
                .collect();
            let svg = loglog_svg(x_desc, y_desc, &lines).expect("a plot");
            let file = out.join(format!("{name}_vs_{sweep}.svg"));
            std::fs::write(&file, svg).expect("a plot file");
            eprintln!("wrote {}", file.display());
        }
    }
}
