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
mod report;
mod table;

pub use matching::{
    largest_k, smallest_level, AutoStep, Level, MatchMetric, MatchPath, MatchReport, MatchStep,
    TessChoice, K_MATCH_WITHIN, MAX_AUTO_TESS,
};
use matching::{measured, search_k, search_tess};
pub use report::{CompareReport, Ratios, COMPARE_SCHEMA_VERSION};
use table::page;
pub use table::{rows, table, Table};

use crate::camera::{Samples, View};
use crate::config::ArchConfig;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::job::{
    self, check_tess_range, check_triangle_budget, load_arch, render_reference_with, run_path,
    Given, Mode, Model, PathRun, PrimitivePath, RenderJob, TraceSettings,
};
use crate::output::{check_out_dir, write_set};
use crate::reference::montage::{montage, Panel};
use crate::reference::oracle::ReferenceImage;
use crate::reference::PixelsPerDegree;
use crate::report::{html, png_bytes, Report};
use crate::scene::Scene;
use crate::tolerance::PerspectiveTol;
use std::path::{Path, PathBuf};

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
    /// How the exact reference is traced (`--reference-tile`, `--reference-threads`).
    pub trace: TraceSettings,
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
            trace: self.trace,
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
            // Both paths are measured, so their functional frames are the analysed ones
            // (the lembo path's in bands on the machine's cores, the triangle path's on one).
            threads: None,
            given: Given {
                supersample: self.supersample_given,
                ..Given::default()
            },
            no_memory_check: self.no_memory_check,
        }
    }
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
    let (search, scene) = checked_scene(job, &lembo_job)?;
    let view = View::new(&scene.camera, scene.viewport);
    let arch = load_arch(&lembo_job)?;
    if let Some(a) = &arch {
        check_host_threads(job, a)?;
    }
    // Every run is measured against the one reference: both paths' accuracy, so every
    // metric `--match` names, is always there.
    let (reference, reference_wall) = render_reference_with(
        &scene,
        &view,
        lembo_job.reference_supersample(),
        job.samples,
        job.trace,
    )?;
    let (lembo, triangle, choice, matched) = run_paths(
        job,
        &lembo_job,
        search,
        &scene,
        &view,
        arch.as_ref(),
        (&reference, reference_wall),
    )?;

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

/// The request's checks before any work, in the order a user meets them (the lembo
/// render's flags, `--out`, the level, what is searched, the scene, its samples, memory
/// and triangle budget): what the compare searches and the scene it draws.
fn checked_scene(job: &CompareJob, lembo_job: &RenderJob) -> Result<(Search, Scene)> {
    lembo_job.validate()?;
    if let Some(dir) = &job.out {
        check_out_dir("--out", dir)?;
    }
    if let Tess::Level(n) = job.tess {
        check_tess_range(n)?;
    }
    let search = job.search()?;
    let scene = job::load_scene(lembo_job)?;
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
    job::check_memory(lembo_job, &scene, 2.0 * BYTES_PER_PIXEL_IMAGES)?;
    if let Tess::Level(n) = job.tess {
        check_triangle_budget(&scene, n)?;
    }
    Ok((search, scene))
}

/// Both paths' runs, each measured against `reference` (with the wall time it took), and
/// the knob `search` names matched between them: the level the triangle path ran at, and
/// what compare.json says of the match.
fn run_paths(
    job: &CompareJob,
    lembo_job: &RenderJob,
    search: Search,
    scene: &Scene,
    view: &View,
    arch: Option<&ArchConfig>,
    (reference, reference_wall): (&ReferenceImage, f64),
) -> Result<(PathRun, PathRun, TessChoice, Option<MatchReport>)> {
    let run = |path: PrimitivePath, tess: Option<u32>, k: f64| {
        run_path(
            &job.render_job(path, tess, k),
            scene,
            view,
            Model::new(arch),
            Some((reference, reference_wall)),
        )
    };

    let (lembo, triangle, choice, found) = match search {
        Search::K(metric, n) => {
            // The triangle run at its given level sets the target; k is searched for it.
            let triangle = run(PrimitivePath::Triangle, Some(n), job.k)?;
            let target = measured(metric, &triangle);
            let (k, found) = search_k(lembo_job, scene, view, reference, metric, target)?;
            let lembo = run(PrimitivePath::Lembo, None, k)?;
            (lembo, triangle, TessChoice::given(n), Some(found))
        }
        Search::Tess(metric) => {
            let lembo = run(PrimitivePath::Lembo, None, job.k)?;
            let target = measured(metric, &lembo);
            let (choice, found) = search_tess(lembo_job, scene, view, reference, metric, target)?;
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
    Ok((lembo, triangle, choice, matched))
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
            trace: Default::default(),
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
