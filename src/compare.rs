//! `lembo-sim compare`: the lembo path, the triangle path and the exact reference of the
//! same scene, side by side (DESIGN.md §5-§7).
//!
//! Both paths run on the timed pipeline of the same architecture (same ROPs, same
//! frame-buffer port) and are measured against one reference of the lembo surfaces. The
//! tessellation level is given, or `auto`: the smallest n whose accuracy on the `--match`
//! metric ([`MatchMetric`]: the silhouette error `silhouette_max_px` by default, or
//! `psnr_db`, or `flip_mean`) is at least as good as the lembo path's at the given k,
//! found by doubling n from 1 and then bisecting between the last level that missed and
//! the first that met it ([`smallest_level`]), up to [`MAX_AUTO_TESS`] or the triangle
//! budget. With `--match-path lembo` the triangle path keeps its given n and the lembo
//! path's k is searched instead ([`largest_k`]). The search (`compare/matching.rs`) draws each
//! level with the functional model and measures it against the reference; every level
//! tried is listed in compare.json. A target the knob's cap cannot reach is refused (exit
//! status 2) naming the closest run: the comparison would not be at equal accuracy.
//!
//! Outputs: `lembo.png`, `triangle.png`, `reference.png`, `lembo_error.png`,
//! `triangle_error.png`, `lembo_flip.png`, `triangle_flip.png` (each path's FLIP map),
//! `montage.png` (the three images and the two error maps, labelled),
//! `compare.json` (both reports, the tessellation search and the cost ratios) and
//! `compare.txt` (the table printed).

mod matching;

pub use matching::{
    largest_k, smallest_level, AutoStep, Level, MatchMetric, MatchPath, MatchReport, MatchStep,
    TessChoice, K_MATCH_WITHIN, MAX_AUTO_TESS,
};
use matching::{measured, search_k, search_tess};

use crate::camera::{Samples, View};
use crate::config::ArchConfig;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::job::{
    self, check_tess_range, check_triangle_budget, load_arch, render_reference, run_path, Given,
    Mode, Model, PathRun, PrimitivePath, RenderJob,
};
use crate::output::{check_out_dir, write_set};
use crate::reference::montage::{montage, Panel};
use crate::reference::oracle::ReferenceImage;
use crate::reference::PixelsPerDegree;
use crate::report::{html, png_bytes, Report};
use crate::tolerance::PerspectiveTol;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Version of the `compare.json` layout.
pub const COMPARE_SCHEMA_VERSION: u32 = 3;
/// How the tessellation level is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tess {
    /// This level n (n² triangles per lembo).
    Level(u32),
    /// The smallest level matching the lembo path's accuracy on the `--match` metric.
    Auto,
}

/// What a compare searches, decided from its flags before any work.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Search {
    /// Nothing: n is given and k is the given one.
    None(u32),
    /// n of the triangle path, against the lembo run (`--tess auto`).
    Tess(MatchMetric),
    /// k of the lembo path, against the triangle run at this n (`--match-path lembo`).
    K(MatchMetric, u32),
}

/// A validated compare request.
#[derive(Clone, Debug)]
pub struct CompareJob {
    /// Scene file, or None for the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output directory; None for `out/<scene name>/compare/`.
    pub out: Option<PathBuf>,
    /// Tolerance k of the lembo path \[pixels\].
    pub k: f64,
    /// Setup's perspective tolerance of the lembo path.
    pub perspective_tol: PerspectiveTol,
    /// The triangle path's tessellation level, or how to choose it.
    pub tess: Tess,
    /// Datapath precision of both paths.
    pub datapath: Datapath,
    /// Architecture file; None for the embedded baseline.
    pub arch: Option<PathBuf>,
    /// Architecture fields set on top of `arch` (`--set`).
    pub arch_set: Vec<(String, serde_json::Value)>,
    /// Technology file; None for the embedded `sim/tech/45nm.json`.
    pub tech: Option<PathBuf>,
    /// Run even when the memory estimate exceeds the memory available.
    pub no_memory_check: bool,
    /// Viewport override (width, height) \[pixels\].
    pub viewport: Option<(u32, u32)>,
    /// Reference samples per pixel side for reference.png (`--supersample`).
    pub supersample: u32,
    /// Whether `--supersample` was given.
    pub supersample_given: bool,
    /// Samples per pixel of both paths (`--samples`).
    pub samples: Samples,
    /// The observer FLIP is computed for.
    pub flip_ppd: PixelsPerDegree,
    /// Host threads of the timed runs (`--host-threads`).
    pub host_threads: u32,
    /// The metric the search matches (`--match`); None when not given: the silhouette.
    pub matching: Option<MatchMetric>,
    /// The path whose knob the search sets (`--match-path`); None when not given: the
    /// triangle path's n.
    pub match_path: Option<MatchPath>,
}

impl CompareJob {
    /// Which knob the run searches and on which metric; the match flags are refused where
    /// they do not apply (DESIGN.md §8), each naming itself.
    fn search(&self) -> Result<Search> {
        let metric = self.matching.unwrap_or_default();
        match (self.match_path.unwrap_or_default(), self.tess) {
            (MatchPath::Triangle, Tess::Auto) => Ok(Search::Tess(metric)),
            (MatchPath::Lembo, Tess::Level(n)) => Ok(Search::K(metric, n)),
            (MatchPath::Lembo, Tess::Auto) => Err(Error::invalid(
                COMMAND_LINE,
                "--tess",
                "auto",
                "--match-path lembo holds the triangle run's level and searches the lembo path's k against it: give the level, --tess N",
            )),
            (MatchPath::Triangle, Tess::Level(n)) => match (self.matching, self.match_path) {
                (Some(m), _) => Err(Error::invalid(
                    COMMAND_LINE,
                    "--match",
                    m.name(),
                    format!("matches the triangle path's n to the lembo run with --tess auto; with --tess {n} nothing is searched (add --match-path lembo to search the lembo path's k against the triangle run at n = {n})"),
                )),
                (None, Some(_)) => Err(Error::invalid(
                    COMMAND_LINE,
                    "--match-path",
                    "triangle",
                    format!("searches the triangle path's n with --tess auto; with --tess {n} nothing is searched"),
                )),
                (None, None) => Ok(Search::None(n)),
            },
        }
    }

    /// The render job of one path at tolerance `k` (validated like `render`'s flags).
    fn render_job(&self, path: PrimitivePath, tess: Option<u32>, k: f64) -> RenderJob {
        RenderJob {
            scene: self.scene.clone(),
            out: None,
            k,
            perspective_tol: match path {
                PrimitivePath::Lembo => self.perspective_tol,
                PrimitivePath::Triangle => PerspectiveTol::FollowK,
            },
            datapath: self.datapath,
            reference: true,
            supersample: self.supersample,
            samples: self.samples,
            flip_ppd: self.flip_ppd,
            viewport: self.viewport,
            mode: Mode::Timed,
            arch: self.arch.clone(),
            arch_set: self.arch_set.clone(),
            trace_out: None,
            tech: self.tech.clone().map(crate::job::TechSource::File),
            path,
            tess,
            blend: BlendMode::Rgba8,
            threshold: None,
            host_threads: self.host_threads,
            // Both paths are measured, so their functional frames are the analysed ones,
            // drawn on one thread.
            threads: None,
            given: Given {
                supersample: self.supersample_given,
                ..Given::default()
            },
            no_memory_check: self.no_memory_check,
        }
    }
}

/// Cost ratios of the two paths on this scene and architecture.
#[derive(Clone, Debug, Serialize)]
pub struct Ratios {
    /// The architecture both paths ran on.
    pub arch: String,
    /// Frame cycles per lembo \[cycles\].
    pub cycles_per_lembo: f64,
    /// Frame cycles per triangle \[cycles\].
    pub cycles_per_triangle: f64,
    /// cycles_per_lembo / cycles_per_triangle: a ratio per primitive. It is the paper's
    /// "a lembo costs 2-3 triangles" only at tessellation 1, where a triangle spans its
    /// lembo's corners; at level n a lembo's surface is n² triangles.
    pub lembo_over_triangle_cycles_per_primitive: f64,
    /// Frame cycles per covered pixel of the lembo path \[cycles\]; null when none is
    /// covered.
    pub lembo_cycles_per_covered_pixel: Option<f64>,
    /// Frame cycles per covered pixel of the triangle path \[cycles\].
    pub triangle_cycles_per_covered_pixel: Option<f64>,
    /// Triangle frame cycles over lembo frame cycles.
    pub triangle_over_lembo_cycles: f64,
    /// Triangle primitive bytes over lembo primitive bytes, as stored in memory
    /// (`primitives.bytes`).
    pub triangle_over_lembo_bytes: f64,
    /// Triangle primitive bytes over lembo primitive bytes, as the geometry fetch read them
    /// (`fetch.bytes`: a mesh's vertices once per vertex-cache miss).
    pub triangle_over_lembo_bytes_fetched: f64,
}

/// `compare.json`.
#[derive(Clone, Debug, Serialize)]
pub struct CompareReport {
    /// [`COMPARE_SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The triangle path's level and how it was chosen.
    pub tess: TessChoice,
    /// The search that matched the two paths' accuracy: its metric, target, levels tried,
    /// the level chosen and how close it came; null when both knobs were given.
    #[serde(rename = "match")]
    pub matched: Option<MatchReport>,
    /// Cycle and byte ratios of the two paths; null in functional mode or for an empty frame.
    pub ratios: Option<Ratios>,
    /// The lembo path's report, as `render --reference` writes it.
    pub lembo: Report,
    /// The triangle path's report, as `render --path triangle --reference` writes it.
    pub triangle: Report,
}

/// What a finished compare hands back for its summary.
pub struct CompareOutput {
    /// What `compare.json` holds.
    pub report: CompareReport,
    /// The table, as printed and written to compare.txt.
    pub table: String,
    /// The folder the files were written to.
    pub dir: PathBuf,
    /// The files written, by name.
    pub files: Vec<String>,
}

/// A path's image, error map and FLIP map kept until the end of a compare \[bytes per
/// pixel\].
const BYTES_PER_PIXEL_IMAGES: f64 = 9.0;

/// Runs a compare to completion: nothing is written unless everything succeeded.
pub fn run_compare(job: &CompareJob) -> Result<CompareOutput> {
    let lembo_job = job.render_job(PrimitivePath::Lembo, None, job.k);
    lembo_job.validate()?;
    if let Some(dir) = &job.out {
        check_out_dir("--out", dir)?;
    }
    if let Tess::Level(n) = job.tess {
        check_tess_range(n)?;
    }
    let search = job.search()?;
    let scene = job::load_scene(&lembo_job)?;
    if scene.discoid_count() > 0 {
        return Err(Error::invalid(
            scene.source_name(),
            "objects",
            format!("{} discoids", scene.discoid_count()),
            "compare draws a surface scene on the lembo and the triangle path; a discoid scene has neither (render it, with --reference to measure it against its surface)",
        ));
    }
    job::check_samples(job.samples, &scene, COMMAND_LINE, "--samples")?;
    // Both paths' images and error maps are kept beside the reference's.
    job::check_memory(&lembo_job, &scene, 2.0 * BYTES_PER_PIXEL_IMAGES)?;
    if let Tess::Level(n) = job.tess {
        check_triangle_budget(&scene, n)?;
    }
    let view = View::new(&scene.camera, scene.viewport);
    let arch = load_arch(&lembo_job)?;
    if let Some(a) = &arch {
        check_host_threads(job, a)?;
    }
    // Every run is measured against the one reference: both paths' accuracy, so every
    // metric `--match` names, is always there.
    let (reference, reference_wall) = render_reference(
        &scene,
        &view,
        lembo_job.reference_supersample(),
        job.samples,
    );
    let run = |path: PrimitivePath, tess: Option<u32>, k: f64| {
        run_path(
            &job.render_job(path, tess, k),
            &scene,
            &view,
            Model::new(arch.as_ref()),
            Some((&reference, reference_wall)),
        )
    };

    let (lembo, triangle, choice, found) = match search {
        Search::K(metric, n) => {
            // The triangle run at its given level sets the target; k is searched for it.
            let triangle = run(PrimitivePath::Triangle, Some(n), job.k)?;
            let target = measured(metric, &triangle);
            let (k, found) = search_k(&lembo_job, &scene, &view, &reference, metric, target)?;
            let lembo = run(PrimitivePath::Lembo, None, k)?;
            (lembo, triangle, TessChoice::given(n), Some(found))
        }
        Search::Tess(metric) => {
            let lembo = run(PrimitivePath::Lembo, None, job.k)?;
            let target = measured(metric, &lembo);
            let (choice, found) =
                search_tess(&lembo_job, &scene, &view, &reference, metric, target)?;
            let triangle = run(PrimitivePath::Triangle, Some(choice.level), job.k)?;
            (lembo, triangle, choice, Some(found))
        }
        Search::None(n) => {
            let lembo = run(PrimitivePath::Lembo, None, job.k)?;
            let triangle = run(PrimitivePath::Triangle, Some(n), job.k)?;
            (lembo, triangle, TessChoice::given(n), None)
        }
    };
    let matched = found.map(|f| {
        let chosen = match f.searched {
            PrimitivePath::Lembo => &lembo.report,
            PrimitivePath::Triangle => &triangle.report,
        };
        f.report(chosen)
    });

    let ratios = ratios(arch.as_ref(), &lembo.report, &triangle.report);
    let report = CompareReport {
        schema_version: COMPARE_SCHEMA_VERSION,
        tess: choice,
        matched,
        ratios,
        lembo: lembo.report.clone(),
        triangle: triangle.report.clone(),
    };
    let table = table(&report);

    let files = images(job, &report, &table, &reference, &lembo, &triangle);
    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name).join("compare"));
    write_set(&dir, "compare", &files, &[])?;
    Ok(CompareOutput {
        report,
        table,
        dir,
        files: files.iter().map(|(n, _)| n.to_string()).collect(),
    })
}

/// `--host-threads` is refused before any work when it exceeds the units of the smaller
/// path's pipeline: each host thread runs at least one unit.
fn check_host_threads(job: &CompareJob, arch: &ArchConfig) -> Result<()> {
    let units = [PrimitivePath::Lembo, PrimitivePath::Triangle]
        .map(|p| arch.instances(p).len())
        .into_iter()
        .min()
        .unwrap_or(1);
    if job.host_threads as usize > units {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--host-threads",
            job.host_threads,
            format!("more than the {units} units of the smaller path's pipeline (each host thread runs at least one)"),
        ));
    }
    Ok(())
}

/// The files of a compare: each path's image, error map and FLIP map, the reference, the
/// labelled montage of the images and error maps, `compare.json` and `compare.txt`.
fn images(
    job: &CompareJob,
    report: &CompareReport,
    table: &str,
    reference: &ReferenceImage,
    lembo: &PathRun,
    triangle: &PathRun,
) -> Vec<(&'static str, Vec<u8>)> {
    let reference_image = reference
        .to_image_supersampled()
        .unwrap_or_else(|| reference.to_image());
    let (lembo_image, triangle_image) = (
        lembo.framebuffer.to_image(),
        triangle.framebuffer.to_image(),
    );
    let (lembo_maps, triangle_maps) = (
        lembo.error_maps.as_ref().expect("measured"),
        triangle.error_maps.as_ref().expect("measured"),
    );
    let (lembo_error, triangle_error) = (&lembo_maps.colour, &triangle_maps.colour);
    let cycles = |r: &Report| {
        r.cycles
            .as_ref()
            .map(|c| format!("{} cycles", c.total))
            .unwrap_or_default()
    };
    let psnr = |r: &Report| {
        r.accuracy
            .as_ref()
            .map(|a| {
                format!(
                    "PSNR {:.1} dB, FLIP {:.4}\nsilhouette {:.2} px",
                    a.psnr_db, a.flip_mean, a.silhouette_max_px
                )
            })
            .unwrap_or_default()
    };
    let samples = match job.samples.get() {
        1 => String::new(),
        n => format!(", {n} samples"),
    };
    let labels = [
        format!(
            "lembo k={} px{samples}\n{} lembos\n{}",
            report.lembo.settings.k_px.unwrap_or(job.k),
            report.lembo.primitives.count,
            cycles(&report.lembo)
        ),
        format!(
            "triangle n={}{samples}\n{} triangles\n{}",
            report.tess.level,
            report.triangle.primitives.count,
            cycles(&report.triangle)
        ),
        "reference\nexact, f64\n".to_string(),
        format!("lembo error\n{}", psnr(&report.lembo)),
        format!("triangle error\n{}", psnr(&report.triangle)),
    ];
    let images = [
        &lembo_image,
        &triangle_image,
        &reference_image,
        lembo_error,
        triangle_error,
    ];
    let panels: Vec<Panel> = labels
        .iter()
        .zip(images)
        .map(|(label, image)| Panel { label, image })
        .collect();
    let montage_image = montage(&panels);

    vec![
        ("lembo.png", png_bytes(&lembo_image)),
        ("triangle.png", png_bytes(&triangle_image)),
        ("reference.png", png_bytes(&reference_image)),
        ("lembo_error.png", png_bytes(lembo_error)),
        ("triangle_error.png", png_bytes(triangle_error)),
        ("lembo_flip.png", png_bytes(&lembo_maps.flip)),
        ("triangle_flip.png", png_bytes(&triangle_maps.flip)),
        ("montage.png", png_bytes(&montage_image)),
        (
            "compare.json",
            serde_json::to_vec_pretty(&report).expect("the report serialises"),
        ),
        ("compare.txt", table.as_bytes().to_vec()),
        (html::REPORT_HTML, page(report).into_bytes()),
    ]
}

/// Frame cycles over the pixels a report's frame covered.
fn per_pixel(cycles: f64, r: &Report) -> Option<f64> {
    (r.counts.pixels_covered > 0).then(|| cycles / r.counts.pixels_covered as f64)
}

fn ratios(arch: Option<&ArchConfig>, lembo: &Report, triangle: &Report) -> Option<Ratios> {
    let (cl, ct) = (lembo.cycles.as_ref()?, triangle.cycles.as_ref()?);
    let (fl, ft) = (lembo.fetch.as_ref()?, triangle.fetch.as_ref()?);
    let (nl, nt) = (lembo.primitives.count, triangle.primitives.count);
    let (cl_total, ct_total) = (cl.total.as_f64(), ct.total.as_f64());
    if nl == 0 || nt == 0 || cl_total == 0.0 || ct_total == 0.0 {
        return None;
    }
    let per_lembo = cl_total / nl as f64;
    let per_triangle = ct_total / nt as f64;
    Some(Ratios {
        arch: arch.map(|a| a.name.clone()).unwrap_or_default(),
        cycles_per_lembo: per_lembo,
        cycles_per_triangle: per_triangle,
        lembo_over_triangle_cycles_per_primitive: per_lembo / per_triangle,
        lembo_cycles_per_covered_pixel: per_pixel(cl_total, lembo),
        triangle_cycles_per_covered_pixel: per_pixel(ct_total, triangle),
        triangle_over_lembo_cycles: ct_total / cl_total,
        triangle_over_lembo_bytes: triangle.primitives.bytes as f64
            / lembo.primitives.bytes.max(1) as f64,
        triangle_over_lembo_bytes_fetched: ft.bytes as f64 / fl.bytes.max(1) as f64,
    })
}

/// The side-by-side comparison, once, for compare.txt and report.html: a title, rows of
/// (name, lembo, triangle) and notes below.
pub struct Table {
    /// What was compared, on which architecture, at which k and tessellation.
    pub title: String,
    /// One row per quantity: its name, the lembo path's value and the triangle path's.
    pub rows: Vec<[String; 3]>,
    /// Lines under the rows: the ratios and, for a search, the levels tried and how close
    /// the chosen one came.
    pub notes: Vec<String>,
}

/// The side-by-side table: primitives, vertices, bytes, cycles, fragments, then every
/// accuracy metric, per path.
pub fn rows(r: &CompareReport) -> Table {
    let (l, tr) = (&r.lembo, &r.triangle);
    let title = title(r);
    let mut rows: Vec<[String; 3]> = Vec::new();
    // A row with one value per report.
    let mut both = |name: &str, value: &dyn Fn(&Report) -> String| {
        rows.push([name.to_string(), value(l), value(tr)])
    };
    both("primitives", &|r| r.primitives.count.to_string());
    both("vertices", &|r| r.primitives.vertices.to_string());
    // What the geometry fetch read through the memory port (a mesh's vertices once per
    // vertex-cache miss), and the primitive data as it lies in memory.
    both("primitive bytes fetched", &|r| {
        r.fetch
            .as_ref()
            .map_or_else(|| "-".into(), |f| f.bytes.to_string())
    });
    both("primitive bytes stored", &|r| {
        r.primitives.bytes.to_string()
    });
    both("cycles per frame", &|r| {
        r.cycles
            .as_ref()
            .map_or_else(|| "-".into(), |c| c.total.to_string())
    });
    both("bottleneck", &|r| {
        r.cycles
            .as_ref()
            .and_then(|c| c.bottleneck.clone())
            .unwrap_or_else(|| "-".into())
    });
    both("area mm2", &|r| {
        r.cost
            .as_ref()
            .map_or_else(|| "-".into(), |c| format!("{:.3}", c.area_mm2))
    });
    both("energy uJ/frame", &|r| {
        r.cost
            .as_ref()
            .map_or_else(|| "-".into(), |c| format!("{:.1}", c.energy_pj * 1e-6))
    });
    both("  of it on chip uJ", &|r| {
        r.cost.as_ref().map_or_else(
            || "-".into(),
            |c| format!("{:.1}", c.on_chip_energy_pj() * 1e-6),
        )
    });
    both("  of it DRAM uJ", &|r| {
        r.cost.as_ref().map_or_else(
            || "-".into(),
            |c| format!("{:.1}", c.dram_energy_pj() * 1e-6),
        )
    });
    both("fragments", &|r| r.counts.fragments.to_string());
    rows.push([
        "quad efficiency".to_string(),
        "-".into(),
        tr.primitives
            .quad_efficiency
            .map(|q| format!("{:.1} %", 100.0 * q))
            .unwrap_or_else(|| "-".into()),
    ]);
    if let (Some(a), Some(b)) = (&l.accuracy, &tr.accuracy) {
        for ((name, va), (_, vb)) in a.lines().into_iter().zip(b.lines()) {
            rows.push([name, va, vb]);
        }
    }
    let mut notes = Vec::new();
    if let Some(x) = &r.ratios {
        let pixel = |c: Option<f64>| c.map_or_else(|| "-".into(), |c| format!("{c:.3}"));
        rows.push([
            "cycles per primitive".to_string(),
            format!("{:.1}", x.cycles_per_lembo),
            format!("{:.2}", x.cycles_per_triangle),
        ]);
        rows.push([
            "cycles per covered pixel".to_string(),
            pixel(x.lembo_cycles_per_covered_pixel),
            pixel(x.triangle_cycles_per_covered_pixel),
        ]);
        notes.push(format!(
            "triangle/lembo: cycles per frame {:.2}, primitive bytes fetched {:.2} (stored {:.2}); lembo/triangle cycles per primitive {:.2} ({})",
            x.triangle_over_lembo_cycles,
            x.triangle_over_lembo_bytes_fetched,
            x.triangle_over_lembo_bytes,
            x.lembo_over_triangle_cycles_per_primitive,
            if r.tess.level == 1 {
                "at n = 1 a triangle spans its lembo's corners: the paper's \"a lembo costs 2-3 triangles\" compares this".to_string()
            } else {
                format!("per primitive, not per surface: at n = {} a lembo's surface is {} triangles", r.tess.level, r.tess.level * r.tess.level)
            }
        ));
    }
    if let Some(m) = &r.matched {
        notes.extend(match_notes(m));
    }
    Table { title, rows, notes }
}

/// The table's title: the scene, its size, the architecture, k and n, and how the searched
/// knob was chosen beside it.
fn title(r: &CompareReport) -> String {
    let l = &r.lembo;
    // How the searched knob was chosen, said beside it.
    let how = |path: &str| {
        r.matched
            .as_ref()
            .filter(|m| m.searched_path == path)
            .map(|m| {
                let target = format!(
                    "{} {} {}, the {} run's",
                    m.field,
                    m.relation,
                    m.metric.value(m.target),
                    m.target_path
                );
                match m.start {
                    Level::Tess(_) => format!(" (auto: smallest n with {target})"),
                    Level::K(k) => format!(" (matched: largest k from {k} px with {target})"),
                }
            })
            .unwrap_or_default()
    };
    format!(
        "compare {} ({}x{} px), architecture {}, k = {} px{}, tessellation {}{}",
        l.scene.name,
        l.scene.width,
        l.scene.height,
        l.arch.as_ref().map(|a| a.name.as_str()).unwrap_or("-"),
        l.settings.k_px.unwrap_or_default(),
        how("lembo"),
        r.tess.level,
        how("triangle"),
    )
}

/// The notes of a match: what was searched for and the levels tried, and how close the
/// chosen level came.
fn match_notes(m: &MatchReport) -> [String; 2] {
    let tried: Vec<String> = m
        .tried
        .iter()
        .map(|s| format!("{} {}", s.level, m.metric.value(s.value)))
        .collect();
    let searched = format!(
            "match ({}): the {} path's {} searched for {} {} the {} run's {}; tried (functional model) {}",
            m.metric.name(),
            m.searched_path,
            match m.start {
                Level::Tess(_) => "n",
                Level::K(_) => "k",
            },
            m.field,
            m.relation,
            m.target_path,
            m.metric.value(m.target),
            tried.join(", ")
        );
    [searched, format!("matched: {}", m.summary)]
}

/// The table as compare.txt and the command print it.
pub fn table(r: &CompareReport) -> String {
    let Table { title, rows, notes } = rows(r);
    let mut t = String::new();
    let _ = writeln!(t, "{title}");
    let _ = writeln!(t, "{:<28} {:>18} {:>18}", "", "lembo", "triangle");
    for [name, a, b] in rows {
        let _ = writeln!(t, "{name:<28} {a:>18} {b:>18}");
    }
    for note in notes {
        let _ = writeln!(t, "{note}");
    }
    t
}

/// The compare's `report.html`: the seven images and the montage, links to compare.json and
/// compare.txt, the table, and each path's report.
fn page(r: &CompareReport) -> String {
    let Table { title, rows, notes } = rows(r);
    let figures: String = [
        ("lembo.png", "lembo path".to_string()),
        (
            "triangle.png",
            format!("triangle path, tessellation {}", r.tess.level),
        ),
        ("reference.png", "exact reference".to_string()),
        (
            "lembo_error.png",
            format!("lembo {}", html::ERROR_MAP_CAPTION),
        ),
        (
            "triangle_error.png",
            format!("triangle {}", html::ERROR_MAP_CAPTION),
        ),
        (
            "lembo_flip.png",
            format!("lembo path's {}", html::flip_map_caption(&r.lembo)),
        ),
        (
            "triangle_flip.png",
            format!("triangle path's {}", html::flip_map_caption(&r.triangle)),
        ),
        (
            "montage.png",
            "montage: the two paths' images, the reference and the two error maps side by \
             side, labelled with cycles, PSNR, FLIP and the silhouette error"
                .to_string(),
        ),
    ]
    .iter()
    .map(|(file, caption)| html::figure(file, caption, false))
    .collect::<String>()
        + &html::file_links(&["compare.json", "compare.txt"]);
    let rows: Vec<Vec<String>> = rows.into_iter().map(Vec::from).collect();
    let notes: String = notes.iter().map(|n| html::para(n)).collect();
    let body = html::section("Images", &figures)
        + &html::section(
            "Side by side",
            &(html::table(&["", "lembo", "triangle"], &rows) + &notes),
        )
        + &html::section("Lembo path", &html::report_sections(&r.lembo, None, 3))
        + &html::section(
            "Triangle path",
            &html::report_sections(&r.triangle, None, 3),
        );
    html::page(
        &format!("lembo-sim compare: {}", r.lembo.scene.name),
        &title,
        &body,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A compare request with these knobs, the rest as the command's defaults.
    fn request(
        tess: Tess,
        matching: Option<MatchMetric>,
        match_path: Option<MatchPath>,
    ) -> CompareJob {
        CompareJob {
            scene: None,
            out: None,
            k: crate::tolerance::DEFAULT_K_PX,
            perspective_tol: PerspectiveTol::default(),
            tess,
            datapath: Datapath::default(),
            arch: None,
            arch_set: Vec::new(),
            tech: None,
            no_memory_check: false,
            viewport: None,
            supersample: 1,
            supersample_given: false,
            samples: Samples::ONE,
            flip_ppd: PixelsPerDegree::default(),
            host_threads: 1,
            matching,
            match_path,
        }
    }

    /// The field a request's refusal names.
    fn refused(job: &CompareJob) -> String {
        match job.search() {
            Err(Error::Invalid { field, .. }) => field,
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn the_match_flags_are_refused_where_nothing_is_searched() {
        use MatchMetric::*;
        let psnr = Some(Psnr);
        assert_eq!(
            request(Tess::Auto, None, None).search().unwrap(),
            Search::Tess(Silhouette)
        );
        assert_eq!(
            request(Tess::Auto, psnr, None).search().unwrap(),
            Search::Tess(Psnr)
        );
        assert_eq!(
            request(Tess::Level(3), None, None).search().unwrap(),
            Search::None(3)
        );
        assert_eq!(
            request(Tess::Level(3), Some(Flip), Some(MatchPath::Lembo))
                .search()
                .unwrap(),
            Search::K(Flip, 3)
        );
        assert_eq!(refused(&request(Tess::Level(3), psnr, None)), "--match");
        assert_eq!(
            refused(&request(Tess::Level(3), psnr, Some(MatchPath::Triangle))),
            "--match"
        );
        assert_eq!(
            refused(&request(Tess::Level(3), None, Some(MatchPath::Triangle))),
            "--match-path"
        );
        assert_eq!(
            refused(&request(Tess::Auto, psnr, Some(MatchPath::Lembo))),
            "--tess"
        );
    }
}
