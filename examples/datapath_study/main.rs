//! The datapath study (issue 7, item 2): f32 against f64 over seeded random lembos.
//!
//! ```text
//! cargo run --release --example datapath_study -- [--lembos N] [--seed S] [--out DIR]
//! ```
//!
//! Its committed output is the two tables of RESULTS.md, "f32 against f64 over random
//! lembos": with no flag (200 cases per family, seed 1, k = 0.25 and 1 px) it prints them,
//! every figure but the host times (the last column) as committed.
//!
//! Prints a markdown table (one row per family and k) and writes into `--out`:
//! `datapath_study.json` (settings, wall time, the per-family summaries, the anomalies),
//! `datapath_study.csv` (one row per case, datapath and k) and, for every anomalous case (a
//! failure, an f64 slack above 1e-6 px (`F64_DEFECT_PX`), unpaired roots), its scene file in `cases/`, which
//! `lembo-sim render FILE --reference` reproduces. The cases and the measurements are
//! deterministic; the wall times are not. The generator and the measurement are the
//! module `study` beside this file, which `tests/integration/datapath.rs` runs in small.

mod study;

use clap::Parser;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use study::{Family, StudySettings, FAMILIES};

#[derive(Parser)]
#[command(
    about = "f32 against f64 datapath over seeded random lembos: the guarantee metric and coverage errors per family"
)]
struct Args {
    /// Random cases per family; each case is two lembos sharing a curved edge.
    #[arg(long, default_value_t = 200)]
    lembos: u32,
    /// The study seed: the same seed draws the same cases on every machine.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The segmenter's k values [pixels], comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.25,1")]
    k: Vec<f64>,
    /// Families to run, comma-separated (default all): ordinary, far_1e3, far_1e5, far_1e7,
    /// large, nearly_flat, nearly_degenerate, steep_perspective.
    #[arg(long, value_delimiter = ',')]
    families: Vec<String>,
    /// Output directory.
    #[arg(long, default_value = "out/datapath_study")]
    out: PathBuf,
    /// Print the scene file of one case, FAMILY:INDEX (with --seed), and run nothing: any
    /// row of the CSV as a file for `lembo-sim render FILE --reference`.
    #[arg(long, value_name = "FAMILY:INDEX")]
    scene: Option<String>,
}

#[derive(Serialize)]
struct Output<'a> {
    settings: &'a StudySettings,
    families: Vec<(&'static str, &'static str)>,
    /// Wall time of the whole study [seconds], and the threads it ran on.
    wall_seconds: f64,
    threads: usize,
    /// Sum of the references' wall times [seconds].
    reference_seconds: f64,
    summaries: Vec<study::Summary>,
    by_extent: Vec<study::ExtentSummary>,
    anomalies: Vec<&'a study::Measurement>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Some(which) = &args.scene {
        let parsed = which
            .split_once(':')
            .and_then(|(f, i)| Some((Family::parse(f)?, i.parse::<u32>().ok()?)));
        let Some((family, index)) = parsed else {
            eprintln!("error: --scene: expected FAMILY:INDEX, e.g. large:3, got {which:?}");
            return ExitCode::from(2);
        };
        println!("{}", study::case(family, args.seed, index).scene_json);
        return ExitCode::SUCCESS;
    }
    let mut families = Vec::new();
    for name in &args.families {
        match Family::parse(name) {
            Some(f) => families.push(f),
            None => {
                eprintln!("error: --families: unknown family {name:?}");
                return ExitCode::from(2);
            }
        }
    }
    if families.is_empty() {
        families = FAMILIES.to_vec();
    }
    if let Some(k) = args.k.iter().find(|k| !(1e-4..=64.0).contains(*k)) {
        eprintln!("error: --k: {k} is outside 1e-4..=64 px (the renderer's range)");
        return ExitCode::from(2);
    }
    let settings = StudySettings {
        cases_per_family: args.lembos,
        seed: args.seed,
        ks: args.k.clone(),
        families,
    };
    match run(&settings, &args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(settings: &StudySettings, args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let results = study::run(settings);
    let wall_seconds = t.elapsed().as_secs_f64();
    let summaries = study::summarise(settings, &results);
    let anomalies = study::anomalies(&results);
    let by_extent = study::by_extent(settings, &results);

    std::fs::create_dir_all(&args.out)?;
    let mut csv = csv::Writer::from_path(args.out.join("datapath_study.csv"))?;
    for m in results.iter().flat_map(|r| &r.measurements) {
        csv.serialize(m)?;
    }
    csv.flush()?;
    if !anomalies.is_empty() {
        let dir = args.out.join("cases");
        std::fs::create_dir_all(&dir)?;
        for m in &anomalies {
            let case = study::case(m.family, m.seed, m.index);
            let file = dir.join(format!("{}_{}.json", m.family.name(), m.index));
            std::fs::write(file, case.scene_json)?;
        }
    }
    let output = Output {
        settings,
        families: settings
            .families
            .iter()
            .map(|f| (f.name(), f.description()))
            .collect(),
        wall_seconds,
        threads: rayon::current_num_threads(),
        reference_seconds: results.iter().map(|r| r.reference_seconds).sum(),
        summaries: summaries.clone(),
        by_extent: by_extent.clone(),
        anomalies: anomalies.clone(),
    };
    std::fs::write(
        args.out.join("datapath_study.json"),
        serde_json::to_string_pretty(&output)? + "\n",
    )?;

    print!("{}", study::markdown(&summaries));
    println!();
    print!("{}", study::extent_markdown(&by_extent));
    println!();
    println!(
        "{} cases per family, seed {}, {} families, {:.1} s wall on {} threads; {} anomalies{}",
        settings.cases_per_family,
        settings.seed,
        settings.families.len(),
        wall_seconds,
        output.threads,
        anomalies.len(),
        if anomalies.is_empty() {
            String::new()
        } else {
            format!(" (scenes in {})", args.out.join("cases").display())
        }
    );
    for m in &anomalies {
        println!(
            "  {} {} {} k={}: {} (slack {:?}, unpaired roots {})",
            m.family.name(),
            m.index,
            m.datapath.name(),
            m.k_px,
            m.status,
            m.slack_px,
            m.unpaired_roots
        );
    }
    Ok(())
}
