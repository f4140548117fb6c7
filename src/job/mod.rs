//! The `render` job: load the scene and the architecture, run one path (lembo or triangle)
//! on the timed pipeline (or the functional model alone), optionally the exact reference
//! and its metrics, and write the outputs. Flags arrive here already parsed; this module
//! validates them once into a [`RenderJob`] and nothing downstream re-checks them.
//! [`run_path`] is the part `compare` reuses for each path.

use crate::camera::{View, MAX_VIEWPORT_SIDE};
use crate::config::ArchConfig;
use crate::cost::{self, model::CostReport, tech::Tech};
use crate::datapath::Datapath;
use crate::discoid::{self, blend::BlendMode};
use crate::error::{Error, Result, COMMAND_LINE};
use crate::lembo::tessellate::Tessellation;
use crate::lembo::Lembo;
use crate::output::{check_out_dir, check_out_file, write_set};
use crate::pipeline::{self, Cycle, CycleReport, SimOptions, Source};
use crate::raster;
use crate::reference::oracle::ReferenceImage;
use crate::reference::{heatmap, metrics, oracle, see_through, Accuracy};
use crate::report::html::{self, REPORT_HTML};
use crate::report::{
    peak_rss_bytes, png_bytes, Host, Memory, PerspectiveSetting, Primitives, Report, SceneInfo,
    Settings, SCHEMA_VERSION,
};
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::{check_k, PerspectiveTol, Tolerance};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod discoids;
use discoids::run_discoids;
pub use discoids::{CURVED_DISCOID_BYTES, PLANAR_DISCOID_BYTES};

/// Checks a count given on the command line: `value` of `flag` must be in 1..=`max`
/// (`unit` says of what); the error names the flag.
pub fn check_count<T: Copy + PartialOrd + From<u8> + std::fmt::Display>(
    flag: &str,
    value: T,
    max: T,
    unit: &str,
) -> Result<()> {
    if (T::from(1)..=max).contains(&value) {
        Ok(())
    } else {
        Err(Error::invalid(
            COMMAND_LINE,
            flag,
            value,
            format!("must be in 1..={max} {unit}"),
        ))
    }
}
/// Largest accepted reference supersampling factor (samples per pixel side).
pub const MAX_SUPERSAMPLE: u32 = 8;

/// The largest accepted tessellation level (triangles per lembo edge).
pub const MAX_TESS: u32 = 1024;
/// The most triangles a tessellated scene may have: beyond it a run takes hours, and
/// triangle ids must fit 32 bits.
pub const MAX_TRIANGLES: u64 = 1 << 26;

/// Which primitives the scene's surfaces are drawn as.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PrimitivePath {
    /// Lembos, by the extreme method (the default).
    #[default]
    Lembo,
    /// Each lembo tessellated into n² triangles, rasterized as a GPU does.
    Triangle,
}

impl PrimitivePath {
    /// The path's name in reports and on the command line (`lembo`, `triangle`).
    pub fn name(self) -> &'static str {
        match self {
            PrimitivePath::Lembo => "lembo",
            PrimitivePath::Triangle => "triangle",
        }
    }
}

/// How a render is simulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Mode {
    /// The Figure 5 pipeline with cycle accounting (the default).
    #[default]
    Timed,
    /// The functional model alone: the same image, no cycles.
    Functional,
}

/// A validated render request.
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Scene file, or None for the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output directory; None for `out/<scene name>/`.
    pub out: Option<PathBuf>,
    /// Tolerance k \[pixels\].
    pub k: f64,
    /// Setup's perspective tolerance (`--perspective-tol`; lembo path only).
    pub perspective_tol: PerspectiveTol,
    /// Datapath precision of the functional model and the units (`--datapath`).
    pub datapath: Datapath,
    /// Whether the exact reference is rendered and the frame measured (`--reference`).
    pub reference: bool,
    /// Reference samples per pixel side.
    pub supersample: u32,
    /// Viewport override (width, height) \[pixels\].
    pub viewport: Option<(u32, u32)>,
    /// Timed pipeline or functional model alone (`--mode`).
    pub mode: Mode,
    /// Architecture file; None for the embedded baseline. Timed mode only.
    pub arch: Option<PathBuf>,
    /// Where to write the Chrome trace-event timeline. Timed mode only.
    pub trace_out: Option<PathBuf>,
    /// Technology file pricing the unit's area and energy (`--tech`); None for the
    /// embedded `sim/tech/45nm.json`. Timed mode only.
    pub tech: Option<PathBuf>,
    /// Which primitives the surfaces are drawn as (`--path`).
    pub path: PrimitivePath,
    /// Tessellation level n (n² triangles per lembo); None for the default, 1. Triangle
    /// path only.
    pub tess: Option<u32>,
    /// Precision of the discoid blend units (scenes with discoids only).
    pub blend: BlendMode,
    /// The discoid threshold t [world units]; None for the scene's.
    pub threshold: Option<f64>,
    /// Host threads the timed model's units are partitioned over (`--host-threads`, >= 1;
    /// no simulated result depends on it).
    pub host_threads: u32,
    /// Host threads a functional frame is drawn on (`--threads`, >= 1); None for the
    /// machine's cores. No pixel or count depends on it (`raster::parallel`).
    pub threads: Option<u32>,
    /// Which settings with a default the user gave, so that one that does not apply to the
    /// scene is refused instead of ignored.
    pub given: Given,
    /// Run even when the memory estimate exceeds the memory available
    /// (`--no-memory-check`).
    pub no_memory_check: bool,
}

/// Which of `render`'s defaulted settings were given on the command line (`tess` and
/// `threshold` are options and say so themselves). A setting given where it does not apply
/// is refused, naming it and why (DESIGN.md §8), as a sweep refuses such a parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Given {
    /// `--k`.
    pub k: bool,
    /// `--perspective-tol`.
    pub perspective_tol: bool,
    /// `--path`.
    pub path: bool,
    /// `--blend`.
    pub blend: bool,
}

/// Most host threads a timed run may use (`--host-threads`).
pub const MAX_HOST_THREADS: u32 = 1024;

/// Most host threads a functional frame may be drawn on (`--threads`).
pub const MAX_THREADS: u32 = 256;

/// The machine's cores, as the default of `--threads` (at most [`MAX_THREADS`]).
pub fn machine_threads() -> u32 {
    std::thread::available_parallelism()
        .map(|n| n.get() as u32)
        .unwrap_or(1)
        .min(MAX_THREADS)
}

impl RenderJob {
    /// The host threads a functional frame is drawn on: `--threads`, or the machine's cores.
    pub fn threads(&self) -> u32 {
        self.threads.unwrap_or_else(machine_threads)
    }

    /// The lembo path's tolerances: k and Setup's perspective tolerance.
    pub fn tolerance(&self) -> Tolerance {
        self.perspective_tol.with_k(self.k)
    }

    /// Checks every flag; errors name the flag and the value.
    pub fn validate(&self) -> Result<()> {
        if let PerspectiveTol::Px(px) = self.perspective_tol {
            if let Err(why) = PerspectiveTol::px(px) {
                return Err(Error::invalid(COMMAND_LINE, "--perspective-tol", px, why));
            }
        }
        if self.perspective_tol != PerspectiveTol::FollowK && self.path == PrimitivePath::Triangle {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--perspective-tol",
                format!("{:?}", self.perspective_tol),
                "only meaningful with --path lembo (the triangle path clips its triangles)",
            ));
        }
        check_k(self.k).map_err(|why| Error::invalid(COMMAND_LINE, "--k", self.k, why))?;
        check_count(
            "--supersample",
            self.supersample,
            MAX_SUPERSAMPLE,
            "samples per pixel side",
        )?;
        if let Some((w, h)) = self.viewport {
            for (name, v) in [("--viewport width", w), ("--viewport height", h)] {
                check_count(name, v, MAX_VIEWPORT_SIDE, "pixels")?;
            }
        }
        check_count(
            "--host-threads",
            self.host_threads,
            MAX_HOST_THREADS,
            "host threads",
        )?;
        if let Some(n) = self.threads {
            check_count("--threads", n, MAX_THREADS, "host threads")?;
            if self.mode == Mode::Timed {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--threads",
                    n,
                    "only meaningful with --mode functional (a timed run's units take --host-threads)",
                ));
            }
        }
        if let Some(dir) = &self.out {
            check_out_dir("--out", dir)?;
        }
        if let Some(path) = &self.trace_out {
            check_out_file("--trace-out", path)?;
            if path.file_name().is_none() {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--trace-out",
                    path.display(),
                    "must name a file",
                ));
            }
        }
        if let Some(t) = self.threshold {
            if !(t.is_finite() && t > 0.0) {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--threshold",
                    t,
                    "must be a finite distance above 0 world units",
                ));
            }
        }
        if let Some(n) = self.tess {
            if self.path != PrimitivePath::Triangle {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--tess",
                    n,
                    "only meaningful with --path triangle",
                ));
            }
            check_tess_range(n)?;
        }
        if self.mode == Mode::Functional {
            for (flag, set) in [
                ("--arch", self.arch.is_some()),
                ("--trace-out", self.trace_out.is_some()),
                ("--tech", self.tech.is_some()),
                ("--host-threads", self.host_threads != 1),
            ] {
                if set {
                    return Err(Error::invalid(
                        COMMAND_LINE,
                        flag,
                        "given",
                        "only meaningful with --mode timed",
                    ));
                }
            }
        }
        self.tech()?;
        Ok(())
    }

    /// The technology file pricing a timed run's cost: `--tech`, or the embedded 45 nm one.
    pub fn tech(&self) -> Result<Tech> {
        match &self.tech {
            Some(path) => Tech::load(path),
            None => Ok(Tech::default_45nm()),
        }
    }
}

/// Bytes a run holds per pixel, measured as peak resident memory over pixels on the bunny
/// at 2048x2048 and 4096x4096 (2026-11-25), rounded up: the functional model's frame buffer
/// and image; the timed pipeline's shared frame buffer and FIFOs besides; the exact
/// reference's image, supersampled colours and metrics; a discoid scene's accumulation
/// target and kept fragments (measured on bunny_discoids at 512x512).
const BYTES_PER_PIXEL_FUNCTIONAL: f64 = 17.0;
const BYTES_PER_PIXEL_TIMED: f64 = 25.0;
const BYTES_PER_PIXEL_REFERENCE: f64 = 175.0;
const BYTES_PER_PIXEL_DISCOIDS: f64 = 160.0;
/// What a run holds whatever its size: the binary, the scene, the thread stacks.
const BYTES_FIXED: f64 = 64.0 * 1024.0 * 1024.0;

/// The memory `job` on `scene` is estimated to need \[bytes\], plus `extra_per_pixel`.
pub fn memory_estimate(job: &RenderJob, scene: &Scene, extra_per_pixel: f64) -> f64 {
    let pixels = scene.viewport.width as f64 * scene.viewport.height as f64;
    let mut per_pixel = match job.mode {
        Mode::Functional => BYTES_PER_PIXEL_FUNCTIONAL,
        Mode::Timed => BYTES_PER_PIXEL_TIMED,
    } + extra_per_pixel;
    if job.reference {
        per_pixel += BYTES_PER_PIXEL_REFERENCE;
    }
    if scene.discoid_count() > 0 {
        per_pixel += BYTES_PER_PIXEL_DISCOIDS;
    }
    BYTES_FIXED + pixels * per_pixel
}

/// The memory the system can give a new allocation without swapping \[bytes\]
/// (`MemAvailable` of /proc/meminfo); None where it cannot be read.
fn memory_available() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Refuses, before any work, a run estimated to need more memory than is available,
/// naming `--viewport` and the estimate; `--no-memory-check` runs it anyway. A run estimated
/// at over 1 GiB says so on standard error before it starts.
pub fn check_memory(job: &RenderJob, scene: &Scene, extra_per_pixel: f64) -> Result<()> {
    let size = format!("{}x{}", scene.viewport.width, scene.viewport.height);
    check_available(
        memory_estimate(job, scene, extra_per_pixel),
        job.no_memory_check,
        ("--viewport", &size),
        &format!("{size} px: this run"),
        "render a smaller viewport",
    )
}

/// Refuses work estimated at `need` bytes when the system has less available, naming
/// `flag` = value (`(flag, value)`) with `advice`, unless `insist` (`--no-memory-check`);
/// `what` needs it, as the note above 1 GiB says.
pub fn check_available(
    need: f64,
    insist: bool,
    (flag, value): (&str, &str),
    what: &str,
    advice: &str,
) -> Result<()> {
    const GIB: f64 = (1u64 << 30) as f64;
    let have = memory_available();
    if need > GIB {
        eprintln!(
            "lembo-sim: {what} needs about {:.1} GiB of memory (estimate{})",
            need / GIB,
            have.map(|h| format!("; {:.1} GiB available", h / GIB))
                .unwrap_or_default()
        );
    }
    match have {
        Some(have) if need > have && !insist => Err(Error::invalid(
            COMMAND_LINE,
            flag,
            value,
            format!(
                "{what} would need about {:.1} GiB (estimate), more than the {:.1} GiB of memory available; {advice}, or pass --no-memory-check to run anyway",
                need / GIB,
                have / GIB
            ),
        )),
        _ => Ok(()),
    }
}

/// `--tess` must be in 1..=MAX_TESS.
pub fn check_tess_range(n: u32) -> Result<()> {
    if (1..=MAX_TESS).contains(&n) {
        Ok(())
    } else {
        Err(Error::invalid(
            COMMAND_LINE,
            "--tess",
            n,
            format!("must be 1 to {MAX_TESS} (triangles per lembo edge)"),
        ))
    }
}

/// The scene tessellated at level n must stay within [`MAX_TRIANGLES`].
pub fn check_triangle_budget(scene: &Scene, n: u32) -> Result<()> {
    let triangles = scene.lembo_count() as u64 * n as u64 * n as u64;
    if triangles > MAX_TRIANGLES {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--tess",
            n,
            format!(
                "{} lembos x {n}² = {triangles} triangles, more than the {MAX_TRIANGLES} accepted",
                scene.lembo_count()
            ),
        ));
    }
    Ok(())
}

/// What a finished render hands back to the caller for its summary.
pub struct RenderOutput {
    /// What `report.json` holds.
    pub report: Report,
    /// The folder the files were written to.
    pub dir: PathBuf,
    /// The files written, by name (the trace, when written elsewhere, is not listed).
    pub files: Vec<String>,
}

/// Loads the job's scene (or the embedded default) with the viewport override applied.
pub fn load_scene(job: &RenderJob) -> Result<Scene> {
    let mut scene = match &job.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::default_scene(),
    };
    if let Some((w, h)) = job.viewport {
        scene.set_viewport(w, h)?;
    }
    Ok(scene)
}

/// The scene whose lembos the exact reference of `scene` renders: the scene itself, or for
/// a discoid scene the surface its discoids stand for (`discoid::surface`); a discoid
/// scene that does not say what surface that is has `--reference` refused naming why.
pub fn reference_scene(scene: &Scene) -> Result<std::borrow::Cow<'_, Scene>> {
    if scene.discoid_count() == 0 {
        return Ok(std::borrow::Cow::Borrowed(scene));
    }
    discoid::surface::surface_scene(scene)
        .map(std::borrow::Cow::Owned)
        .map_err(no_surface)
}

/// Refuses, before any work, `--reference` on a discoid scene that does not say what
/// surface it stands for ([`reference_scene`] without building the surface).
pub fn check_reference_scene(scene: &Scene) -> Result<()> {
    discoid::surface::check_surfaces(scene).map_err(no_surface)
}

/// The `--reference` error of a discoid scene without a surface.
fn no_surface(why: String) -> Error {
    Error::invalid(
        COMMAND_LINE,
        "--reference",
        "given",
        format!("the reference of a discoid scene is the surface its discoids stand for: {why}"),
    )
}

/// The exact reference of `scene`'s lembo surfaces, with the wall time it took; for a
/// discoid scene, pass its [`reference_scene`].
pub fn render_reference(scene: &Scene, view: &View, supersample: u32) -> (ReferenceImage, f64) {
    let t = Instant::now();
    let lembos: Vec<_> = scene.lembos().collect();
    let reference = oracle::render_reference(&oracle::ReferenceInput {
        lembos: &lembos,
        view,
        light: &scene.light,
        background: scene.background,
        supersample,
    });
    (reference, t.elapsed().as_secs_f64())
}

/// The architecture a job runs on: None in functional mode.
pub fn load_arch(job: &RenderJob) -> Result<Option<ArchConfig>> {
    Ok(match (&job.arch, job.mode) {
        (_, Mode::Functional) => None,
        (Some(path), Mode::Timed) => Some(ArchConfig::load(path)?),
        (None, Mode::Timed) => Some(ArchConfig::baseline()),
    })
}

/// Bytes of one lembo as the Setup unit reads it: six points and six normals in f32.
pub const LEMBO_BYTES: u64 = 6 * 2 * 3 * 4;

/// Which model a run is simulated on.
#[derive(Clone, Copy, Debug)]
pub enum Model<'a> {
    /// The functional model alone: the image and its counts, no cycles.
    Functional,
    /// The timed pipeline of this architecture (the image is checked against the
    /// functional model's wherever both ran).
    Timed(&'a ArchConfig),
}

impl<'a> Model<'a> {
    /// The model of a job whose architecture [`load_arch`] gave: timed when there is one.
    pub fn new(arch: Option<&'a ArchConfig>) -> Self {
        arch.map_or(Model::Functional, Model::Timed)
    }

    /// The architecture, for a timed run.
    pub fn arch(self) -> Option<&'a ArchConfig> {
        match self {
            Model::Functional => None,
            Model::Timed(arch) => Some(arch),
        }
    }
}

/// What a scene is drawn as: decided once, from the scene and `--path`.
pub enum Route<'s> {
    /// Its lembos, by the extreme method.
    Lembos,
    /// Its lembos tessellated into triangles, rasterized as a GPU does.
    Triangles(Tessellation<'s>),
    /// Its atlas of discoids, in three passes through the ROPs' blend units.
    Discoids,
}

impl<'s> Route<'s> {
    /// The route of `job` on `scene`; a tessellation must stay within [`MAX_TRIANGLES`].
    pub fn new(job: &RenderJob, scene: &'s Scene) -> Result<Self> {
        check_applies(job, scene)?;
        if scene.discoid_count() > 0 {
            return Ok(Route::Discoids);
        }
        Ok(match job.path {
            PrimitivePath::Lembo => Route::Lembos,
            PrimitivePath::Triangle => {
                let level = job.tess.unwrap_or(1);
                check_triangle_budget(scene, level)?;
                Route::Triangles(Tessellation::new(scene, level))
            }
        })
    }
}

/// Refuses a setting the user gave that does not apply to `scene` or to the path: the
/// discoid settings on a scene without discoids, the path and tessellation on a discoid
/// scene, k and the perspective tolerance where no lembo is drawn.
fn check_applies(job: &RenderJob, scene: &Scene) -> Result<()> {
    let discoids = scene.discoid_count();
    if job.reference {
        check_reference_scene(scene)?;
    }
    let curved = scene.lembo_count() > 0;
    let lembos_drawn = if discoids > 0 {
        curved
    } else {
        job.path == PrimitivePath::Lembo
    };
    let on_scene = if discoids > 0 {
        format!(
            "does not apply to {}, a scene of {discoids} {} discoids",
            scene.name,
            if curved { "curved" } else { "planar" }
        )
    } else {
        format!("does not apply to {}, which has no discoids", scene.name)
    };
    let no_lembos = if discoids > 0 {
        on_scene.clone()
    } else {
        "does not apply to the triangle path (it has no tolerance k)".to_string()
    };
    let given: [(&str, bool, String, bool, &String); 6] = [
        (
            "--path",
            job.given.path,
            job.path.name().into(),
            discoids == 0,
            &on_scene,
        ),
        (
            "--tess",
            job.tess.is_some(),
            job.tess.unwrap_or_default().to_string(),
            discoids == 0,
            &on_scene,
        ),
        (
            "--blend",
            job.given.blend,
            job.blend.name().into(),
            discoids > 0,
            &on_scene,
        ),
        (
            "--threshold",
            job.threshold.is_some(),
            job.threshold.unwrap_or_default().to_string(),
            discoids > 0,
            &on_scene,
        ),
        (
            "--k",
            job.given.k,
            job.k.to_string(),
            lembos_drawn,
            &no_lembos,
        ),
        (
            "--perspective-tol",
            job.given.perspective_tol,
            "given".into(),
            lembos_drawn,
            &no_lembos,
        ),
    ];
    for (flag, set, value, applies, why) in given {
        if set && !applies {
            return Err(Error::invalid(COMMAND_LINE, flag, value, why.as_str()));
        }
    }
    Ok(())
}

/// One path's run on a loaded scene: what `render` writes, and what `compare` puts side by
/// side.
pub struct PathRun {
    /// The run's report.
    pub report: Report,
    /// The image (the timed pipeline's, or the functional model's).
    pub framebuffer: FrameBuffer,
    /// The error heat map against the reference, when one was given.
    pub error_map: Option<image::RgbImage>,
    /// Chrome trace-event JSON, when requested.
    pub trace: Option<String>,
}

/// Runs `job`'s path on `scene` on `model`, and with a `reference` (and the wall time it
/// took) the accuracy metrics, from the functional model's fragment probe; the timed image
/// must equal the functional one bit for bit, and this is checked on every such run.
pub fn run_path(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    reference: Option<(&ReferenceImage, f64)>,
) -> Result<PathRun> {
    let route = Route::new(job, scene)?;
    if let Route::Discoids = route {
        return run_discoids(job, scene, view, model, reference);
    }
    let (drawn, wall) = draw(job, scene, view, model, &route, reference.is_some())?;
    let measured = match (reference, drawn.probed()) {
        (Some(reference), Some(frame)) => Some(measure(job, scene, view, &route, frame, reference)),
        _ => None,
    };
    let counts = drawn.counts();
    let primitives = match &route {
        Route::Triangles(t) => Primitives {
            kind: "triangle".into(),
            count: t.len(),
            vertices: t.vertex_count(),
            bytes: t.bytes(),
            quad_efficiency: counts.quad_efficiency(),
        },
        _ => {
            let lembos = scene.lembo_count() as u64;
            Primitives {
                kind: "lembo".into(),
                count: lembos,
                vertices: 6 * lembos,
                bytes: LEMBO_BYTES * lembos,
                quad_efficiency: None,
            }
        }
    };
    let (framebuffer, units, cycles, trace) = match drawn {
        Drawn::Functional(f) => (f.framebuffer, Vec::new(), None, None),
        Drawn::Timed { timed, .. } => (
            timed.framebuffer,
            timed.units,
            Some(timed.cycles),
            timed.trace,
        ),
    };
    let cost = match (model, &cycles) {
        (Model::Timed(arch), Some(cycles)) => Some(cost_of(
            job,
            scene,
            view,
            &route,
            arch,
            cycles,
            &counts,
            &framebuffer,
        )?),
        _ => None,
    };
    let memory = Memory::new(
        FrameBuffer::stored_bytes(scene.viewport.width, scene.viewport.height),
        0,
        primitives.bytes,
        model.arch().map(|a| pipeline::fifo_entries(a, &units)),
    );
    let tess = match &route {
        Route::Triangles(t) => Some(t.level()),
        _ => None,
    };
    let report = Report {
        schema_version: SCHEMA_VERSION,
        scene: scene_info(scene),
        settings: settings(
            job,
            model,
            job.path.name(),
            (job.path == PrimitivePath::Lembo).then_some(job.k),
            tess,
            reference.is_some(),
        ),
        primitives,
        units,
        counts,
        host: {
            let mut h = host(
                wall,
                counts.fragments,
                cycles.as_ref().map(|c| (c.total, job.host_threads)),
                measured.as_ref().map(|m| m.reference_wall),
                measured.as_ref().map(|m| m.metrics_wall),
            );
            if cycles.is_none() {
                // The functional frame's threads: the analysed frame is drawn on one.
                h.host_threads = Some(if measured.is_some() { 1 } else { job.threads() });
            }
            h
        },
        cycles,
        cost,
        arch: model.arch().cloned(),
        accuracy: measured.as_ref().map(|m| m.accuracy.clone()),
        blend: None,
        memory,
    };
    Ok(PathRun {
        report,
        framebuffer,
        error_map: measured.map(|m| m.error_map),
        trace,
    })
}

/// The cost of a timed lembo or triangle frame (DESIGN.md §12): the functional model runs
/// again in a counting datapath for the operations of each kind (its image must equal the
/// timed one, so counting cannot have changed what was drawn), priced with the timed run's
/// busy cycles and items and the bytes through the frame-buffer port.
#[allow(clippy::too_many_arguments)]
fn cost_of(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    route: &Route,
    arch: &ArchConfig,
    cycles: &CycleReport,
    counts: &raster::Counts,
    timed: &FrameBuffer,
) -> Result<CostReport> {
    let (frame, ops) = match route {
        Route::Triangles(t) => cost::triangle_ops(scene, view, t, job.datapath),
        _ => cost::lembo_ops(scene, view, job.tolerance(), job.datapath)?,
    };
    if frame.framebuffer.color != timed.color {
        return Err(Error::Internal(
            "the counting run's image differs from the timed one".into(),
        ));
    }
    let fb = &arch.framebuffer;
    let framebuffer_bytes = counts.fragments * fb.bytes_per_fragment_tested
        + counts.fragments_passed_depth * fb.bytes_per_fragment_written;
    let work = cost::model::Work {
        ops: &ops,
        cycles,
        framebuffer_bytes,
    };
    Ok(cost::model::cost(&job.tech()?, arch, job.datapath, &work))
}

/// A surface path's image with what each model contributed (one per run, so the variants'
/// sizes do not matter).
#[allow(clippy::large_enum_variant)]
enum Drawn {
    /// The functional model alone (with its probe when the run is measured).
    Functional(raster::Frame),
    /// The timed pipeline; for a measured run also the functional model's probed frame.
    Timed {
        timed: pipeline::TimedFrame,
        probed: Option<raster::Frame>,
    },
}

impl Drawn {
    /// The functional frame carrying the fragment probe, when the run is measured.
    fn probed(&self) -> Option<&raster::Frame> {
        match self {
            Drawn::Functional(f) => Some(f),
            Drawn::Timed { probed, .. } => probed.as_ref(),
        }
    }

    /// The counts of the model that made the image.
    fn counts(&self) -> raster::Counts {
        match self {
            Drawn::Functional(f) => f.counts,
            Drawn::Timed { timed, .. } => timed.counts,
        }
    }
}

/// Draws a lembo or triangle `route` on `model`, with the wall time of that render alone
/// \[seconds\]; with `analyse`, the functional model also runs with its probe (a timed run
/// checks its image against it), outside the time taken.
fn draw(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    model: Model,
    route: &Route,
    analyse: bool,
) -> Result<(Drawn, f64)> {
    let functional = |analyse: bool| -> Result<raster::Frame> {
        let triangles = match route {
            Route::Triangles(t) => Some(t as &dyn raster::triangle::TriangleSource),
            _ => None,
        };
        raster::render_functional_on(
            scene,
            view,
            job.tolerance(),
            triangles,
            job.datapath,
            analyse,
            job.threads(),
        )
    };
    let arch = match model {
        Model::Functional => {
            let t0 = Instant::now();
            let frame = functional(analyse)?;
            return Ok((Drawn::Functional(frame), t0.elapsed().as_secs_f64()));
        }
        Model::Timed(arch) => arch,
    };
    let (path, source) = match route {
        Route::Triangles(t) => (pipeline::Path::Triangle, Source::Triangles(t)),
        _ => (pipeline::Path::Lembo, Source::Lembos),
    };
    let options = sim_options(job, arch, path)?;
    let t0 = Instant::now();
    let timed = pipeline::run_timed(
        scene,
        view,
        job.tolerance(),
        job.datapath,
        arch,
        source,
        &options,
    )?;
    let wall = t0.elapsed().as_secs_f64();
    let probed = if analyse {
        let frame = functional(true)?;
        if timed.framebuffer.color != frame.framebuffer.color {
            return Err(Error::Internal(
                "the timed image differs from the functional one".into(),
            ));
        }
        Some(frame)
    } else {
        None
    };
    Ok((Drawn::Timed { timed, probed }, wall))
}

/// A measured run's accuracy, error map and the wall time the measuring took.
struct Measured {
    accuracy: Accuracy,
    error_map: image::RgbImage,
    /// The reference's wall time plus the metrics' \[seconds\].
    reference_wall: f64,
    /// The metrics' wall time \[seconds\].
    metrics_wall: f64,
}

/// Measures `frame` (probed) against `reference` (with the wall time it took).
fn measure(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    route: &Route,
    frame: &raster::Frame,
    (reference, wall): (&ReferenceImage, f64),
) -> Measured {
    let t1 = Instant::now();
    let ids_per_lembo = match route {
        Route::Triangles(t) => t.triangles_per_lembo(),
        _ => 1,
    };
    let accuracy = measure_frame(scene, view, frame, reference, job.path, ids_per_lembo);
    let metrics_wall = t1.elapsed().as_secs_f64();
    let error_map = heatmap::error_heatmap(&frame.framebuffer, reference);
    Measured {
        accuracy,
        error_map,
        reference_wall: wall + t1.elapsed().as_secs_f64(),
        metrics_wall,
    }
}

/// The accuracy of `frame` (rendered with `analyse`) of `scene` against its `reference`:
/// the metrics, with the reference traced anew where the sub-pixel silhouette asks, the
/// fragment probe's counts and the see-through count. `ids_per_lembo` maps the frame's
/// winner ids to lembo ids: 1 on the lembo path, n² on the triangle path at level n.
pub fn measure_frame(
    scene: &Scene,
    view: &View,
    frame: &raster::Frame,
    reference: &ReferenceImage,
    path: PrimitivePath,
    ids_per_lembo: u64,
) -> Accuracy {
    let probe = frame.probe.unwrap_or_default();
    let tracer = oracle::Tracer::new(scene.lembos().map(|(l, _)| l), view);
    metrics::measure(
        &frame.framebuffer,
        reference,
        &tracer,
        probe.double_hit_pixels,
        match path {
            PrimitivePath::Lembo => Some(probe.max_scanline_deviation_px),
            PrimitivePath::Triangle => None,
        },
        see_through_px(scene, view, &frame.framebuffer, ids_per_lembo),
    )
}

/// The see-through pixels of a render of `scene` (`reference::see_through`): the lembos
/// of objects built from a triangle mesh (`mesh` and `builtin` objects) are checked against
/// their triangles; None when the scene has no such object.
pub fn see_through_px(
    scene: &Scene,
    view: &View,
    render: &FrameBuffer,
    ids_per_lembo: u64,
) -> Option<u64> {
    if scene.objects.iter().all(|o| o.mesh.is_none()) {
        return None;
    }
    let lembos: Vec<(&Lembo, bool)> = scene
        .objects
        .iter()
        .flat_map(|o| o.lembos.iter().map(move |l| (l, o.mesh.is_some())))
        .collect();
    Some(see_through::see_through(&lembos, view, render, ids_per_lembo).total())
}

/// The scene section of a report.
fn scene_info(scene: &Scene) -> SceneInfo {
    SceneInfo {
        name: scene.name.clone(),
        source: scene.source_name(),
        width: scene.viewport.width,
        height: scene.viewport.height,
        lembos: scene.lembo_count() as u64,
        objects: scene
            .objects
            .iter()
            .map(|o| match &o.discoids {
                Some(d) => format!(
                    "{} ({} discoids, {} beta)",
                    o.label,
                    d.planar.len() + d.lembo_texcoords.len(),
                    d.beta.name()
                ),
                None => format!("{} ({} lembos)", o.label, o.lembos.len()),
            })
            .collect(),
    }
}

/// The settings section of a report.
fn settings(
    job: &RenderJob,
    model: Model,
    path: &str,
    k_px: Option<f64>,
    tess: Option<u32>,
    reference: bool,
) -> Settings {
    let perspective_tol = k_px.map(|_| match job.tolerance().perspective {
        Some(px) => PerspectiveSetting::Px(px),
        None => PerspectiveSetting::Off("off"),
    });
    Settings {
        mode: match model {
            Model::Timed(_) => "timed",
            Model::Functional => "functional",
        }
        .into(),
        arch_file: model.arch().map(|_| {
            job.arch
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "(embedded baseline)".into())
        }),
        path: path.into(),
        k_px,
        perspective_tol,
        tess,
        datapath: job.datapath.name().into(),
        reference,
        supersample: job.supersample,
    }
}

/// The host options of a timed run of `job` on `path`: `--host-threads` is refused when it
/// exceeds the units the run instantiates (each host thread runs at least one unit).
fn sim_options(job: &RenderJob, arch: &ArchConfig, path: pipeline::Path) -> Result<SimOptions> {
    let units = pipeline::graph::units(path, arch).len();
    if job.host_threads as usize > units {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--host-threads",
            job.host_threads,
            format!("more than the {units} units this run instantiates (each host thread runs at least one)"),
        ));
    }
    Ok(SimOptions {
        host_threads: job.host_threads as usize,
        trace: job.trace_out.is_some(),
        ..SimOptions::default()
    })
}

/// The host section of a report; `timed` is the frame's cycles and the host threads.
fn host(
    wall: f64,
    fragments: u64,
    timed: Option<(Cycle, u32)>,
    reference_wall: Option<f64>,
    metrics_wall: Option<f64>,
) -> Host {
    Host {
        wall_seconds: wall,
        fragments_per_second: if wall > 0.0 {
            fragments as f64 / wall
        } else {
            0.0
        },
        simulated_cycles_per_second: timed.map(|(c, _)| c.as_f64() / wall.max(1e-9)),
        host_threads: timed.map(|(_, n)| n),
        reference_wall_seconds: reference_wall,
        metrics_wall_seconds: metrics_wall,
        peak_rss_bytes: peak_rss_bytes(),
    }
}

/// The render's `report.html`: its images with what they show, and the report.
fn render_page(
    report: &Report,
    files: &[(&str, Vec<u8>)],
    trace: Option<&PathBuf>,
    dir: &Path,
) -> String {
    let images: Vec<(&str, String)> = files
        .iter()
        .filter(|(name, _)| name.ends_with(".png"))
        .map(|(name, _)| {
            let caption = match *name {
                "image.png" => format!(
                    "{} path, as the simulated unit drew it",
                    report.settings.path
                ),
                "reference.png" => {
                    "exact reference: each sample's ray against the true lembos, in f64".to_string()
                }
                _ => html::ERROR_MAP_CAPTION.to_string(),
            };
            (*name, caption)
        })
        .collect();
    let trace = trace.map(|t| html::link_from(dir, t));
    html::render_page(report, &images, trace.as_deref())
}

/// Runs a render job to completion: nothing is written unless everything succeeded.
pub fn run_render(job: &RenderJob) -> Result<RenderOutput> {
    job.validate()?;
    let scene = load_scene(job)?;
    check_memory(job, &scene, 0.0)?;
    let view = View::new(&scene.camera, scene.viewport);
    let arch = load_arch(job)?;
    if job.path == PrimitivePath::Triangle {
        check_triangle_budget(&scene, job.tess.unwrap_or(1))?;
    }
    let reference = match job.reference {
        true => Some(render_reference(
            reference_scene(&scene)?.as_ref(),
            &view,
            job.supersample,
        )),
        false => None,
    };
    let run = run_path(
        job,
        &scene,
        &view,
        Model::new(arch.as_ref()),
        reference.as_ref().map(|(r, w)| (r, *w)),
    )?;

    let mut files: Vec<(&str, Vec<u8>)> =
        vec![("image.png", png_bytes(&run.framebuffer.to_image()))];
    if let (Some((reference, _)), Some(error_map)) = (&reference, &run.error_map) {
        let shown = reference
            .to_image_supersampled()
            .unwrap_or_else(|| reference.to_image());
        files.push(("reference.png", png_bytes(&shown)));
        files.push(("error.png", png_bytes(error_map)));
    }
    let mut report = run.report;
    // The images are encoded: what remains to allocate is the report and the writes.
    report.host.peak_rss_bytes = peak_rss_bytes();
    let json = serde_json::to_vec_pretty(&report).expect("the report serialises");
    files.push(("report.json", json));
    files.push(("report.txt", report.to_text().into_bytes()));

    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name));
    // The timeline, where --trace-out says, is part of the same atomic set: a trace that
    // cannot be written leaves no image or report either.
    let mut elsewhere: Vec<(PathBuf, &[u8])> = Vec::new();
    if let (Some(path), Some(trace)) = (&job.trace_out, &run.trace) {
        elsewhere.push((path.clone(), trace.as_bytes()));
    }
    let page = render_page(&report, &files, elsewhere.first().map(|(p, _)| p), &dir);
    files.push((REPORT_HTML, page.into_bytes()));
    write_set(&dir, "render", &files, &elsewhere)?;
    Ok(RenderOutput {
        report,
        dir,
        files: files.iter().map(|(n, _)| n.to_string()).collect(),
    })
}
