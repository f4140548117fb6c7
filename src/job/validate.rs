//! What a render request is and its flags' checks: [`RenderJob`] (with [`PrimitivePath`],
//! [`Mode`] and [`Given`]) is validated once, every flag against its range and the flags
//! that only apply in one mode against that mode, so nothing downstream re-checks it.

use crate::camera::{Samples, MAX_VIEWPORT_SIDE};
use crate::cost::tech::Tech;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::output::{check_out_dir, check_out_file};
use crate::reference::PixelsPerDegree;
use crate::tolerance::{check_k, PerspectiveTol, Tolerance};
use serde::Deserialize;
use std::path::PathBuf;

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

/// Which primitives the scene's surfaces are drawn as: the graph's path type, which the
/// timed pipeline instantiates too.
pub use crate::graph::PrimitivePath;

/// How a render is simulated: the crate's one mode type (`--mode`, a sweep spec's `mode`,
/// which is why it deserializes: `timed`, `functional`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// The Figure 5 pipeline with cycle accounting (the default).
    #[default]
    Timed,
    /// The functional model alone: the same image, no cycles.
    Functional,
}

impl Mode {
    /// The mode's name in reports, specs and on the command line (`timed`, `functional`).
    pub const fn name(self) -> &'static str {
        match self {
            Mode::Timed => "timed",
            Mode::Functional => "functional",
        }
    }
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
    /// Reference samples per pixel side, as given (`--supersample`; see
    /// [`RenderJob::reference_supersample`]).
    pub supersample: u32,
    /// Samples per pixel of the render (`--samples`): multisampling on either path.
    pub samples: Samples,
    /// The observer FLIP is computed for (`--flip-ppd`).
    pub flip_ppd: PixelsPerDegree,
    /// Viewport override (width, height) \[pixels\].
    pub viewport: Option<(u32, u32)>,
    /// Timed pipeline or functional model alone (`--mode`).
    pub mode: Mode,
    /// Architecture file; None for the embedded baseline. Timed mode only.
    pub arch: Option<PathBuf>,
    /// Architecture fields set on top of `arch` (`--set FIELD=VALUE`, dotted paths as in a
    /// sweep's `arch.` parameters); timed mode only.
    pub arch_set: Vec<(String, serde_json::Value)>,
    /// Where to write the Chrome trace-event timeline. Timed mode only.
    pub trace_out: Option<PathBuf>,
    /// Technology pricing the unit's area and energy (`--tech`, or a sweep point's
    /// `tech.<field>` values); None for the embedded `sim/tech/45nm.json`. Timed mode only.
    pub tech: Option<TechSource>,
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
    /// machine's cores. No pixel or count depends on it (`frame::bands`).
    pub threads: Option<u32>,
    /// Which settings with a default the user gave, so that one that does not apply to the
    /// scene is refused instead of ignored.
    pub given: Given,
    /// Run even when the memory estimate exceeds the memory available
    /// (`--no-memory-check`).
    pub no_memory_check: bool,
    /// How the exact reference is traced (`--reference-tile`, `--reference-threads`): its
    /// memory and time, never its result.
    pub trace: TraceSettings,
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
    /// `--flip-ppd`.
    pub flip_ppd: bool,
    /// `--supersample`.
    pub supersample: bool,
}

/// The reference's sub-samples per pixel side a multisampled run is measured against when
/// `--supersample` is not given: 8 x 8, 64 a pixel (DESIGN.md §6: its own error beside the
/// unit's).
pub const AA_SUPERSAMPLE: u32 = 8;

/// The fewest sub-samples per pixel side a multisampled run's reference may have: the
/// area-averaged colour a resolve approximates needs more sub-samples than the 8 a pixel
/// the unit takes at most.
pub const MIN_AA_SUPERSAMPLE: u32 = 4;

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

    /// The lembo path's tolerances: k and Setup's perspective tolerance \[pixels\].
    pub fn tolerance(&self) -> Tolerance {
        self.perspective_tol.with_k(self.k)
    }

    /// [`Self::tolerance`] in the units of the grid the scan-line stages walk: the sample
    /// grid's rows are 1/samples of a pixel apart, so both tolerances are that many rows
    /// (the error stays k pixels across the scan-lines whatever the samples).
    pub fn grid_tolerance(&self) -> Tolerance {
        self.tolerance().on_grid(self.samples.get())
    }

    /// The reference's sub-samples per pixel side: `--supersample`, or for a multisampled
    /// run without it, [`AA_SUPERSAMPLE`].
    pub fn reference_supersample(&self) -> u32 {
        if self.samples != Samples::ONE && !self.given.supersample {
            AA_SUPERSAMPLE
        } else {
            self.supersample
        }
    }

    /// The flags of the reference: in range, and refused without `--reference`.
    fn check_reference_flags(&self) -> Result<()> {
        if self.given.flip_ppd && !self.reference {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--flip-ppd",
                self.flip_ppd.get(),
                "only meaningful with --reference (FLIP compares the render with it)",
            ));
        }
        self.trace.check()?;
        if self.trace != TraceSettings::default() && !self.reference {
            let flag = if self.trace.tile != TraceSettings::default().tile {
                ("--reference-tile", self.trace.tile)
            } else {
                ("--reference-threads", self.trace.threads.unwrap_or(0))
            };
            return Err(Error::invalid(
                COMMAND_LINE,
                flag.0,
                flag.1,
                "only meaningful with --reference (it says how the reference is traced)",
            ));
        }
        Ok(())
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
        check_aa_supersample(self.samples, self.reference_supersample(), "--supersample")?;
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
        self.check_reference_flags()?;
        if let Some(t) = self.threshold {
            check_threshold(t)
                .map_err(|why| Error::invalid(COMMAND_LINE, "--threshold", t, why))?;
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
                ("--set", !self.arch_set.is_empty()),
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

    /// The technology pricing a timed run's cost: `--tech`, a sweep point's, or the
    /// embedded 45 nm one.
    pub fn tech(&self) -> Result<Tech> {
        match &self.tech {
            Some(TechSource::File(path)) => Tech::load(path),
            Some(TechSource::Given(tech)) => Ok(Tech::clone(tech)),
            None => Ok(Tech::default_45nm()),
        }
    }
}

/// Where a timed run's technology comes from, besides the embedded 45 nm file.
#[derive(Clone, Debug)]
pub enum TechSource {
    /// A technology file (`--tech`), read when the run is priced.
    File(PathBuf),
    /// A technology already validated (a sweep point's: the embedded file with the point's
    /// `tech.<field>` values).
    Given(std::sync::Arc<Tech>),
}

/// Checks a discoid threshold t \[world units\] (`--threshold`, a sweep's `threshold`): it
/// must be finite and above 0. The error says what is accepted; the caller names the flag or
/// field and the value as given.
pub fn check_threshold(t: f64) -> std::result::Result<f64, &'static str> {
    if t.is_finite() && t > 0.0 {
        Ok(t)
    } else {
        Err("must be a finite distance above 0 world units")
    }
}

/// With `samples` per pixel above one, the reference's `supersample` sub-samples per pixel
/// side must be at least [`MIN_AA_SUPERSAMPLE`]; `flag` names where it was given.
pub fn check_aa_supersample(samples: Samples, supersample: u32, flag: &str) -> Result<()> {
    if samples != Samples::ONE && supersample < MIN_AA_SUPERSAMPLE {
        return Err(Error::invalid(
            COMMAND_LINE,
            flag,
            supersample,
            format!(
                "with {samples} samples per pixel the image is measured against the \
                 area-averaged reference, which needs at least {MIN_AA_SUPERSAMPLE} sub-samples \
                 per pixel side (default {AA_SUPERSAMPLE})"
            ),
        ));
    }
    Ok(())
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

/// How the exact reference is traced: never what it traces (every image and metric is the
/// same bit for bit at any setting), only its memory and time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceSettings {
    /// Side of the square screen tiles the lembos are binned into \[pixels\], in
    /// [`crate::reference::oracle::TILE_RANGE`] (`--reference-tile`).
    pub tile: u32,
    /// Host threads the reference and the metrics run on (`--reference-threads`); None:
    /// the pool the caller runs in (the machine's cores, or a sweep's `--jobs`).
    pub threads: Option<u32>,
}

impl Default for TraceSettings {
    fn default() -> Self {
        TraceSettings {
            tile: crate::reference::oracle::DEFAULT_TILE,
            threads: None,
        }
    }
}

impl TraceSettings {
    /// Refuses a tile side outside [`crate::reference::oracle::TILE_RANGE`] or a thread count outside 1 to
    /// [`MAX_THREADS`], naming the flag.
    pub fn check(&self) -> Result<()> {
        if !crate::reference::oracle::TILE_RANGE.contains(&self.tile) {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--reference-tile",
                self.tile,
                format!(
                    "must be from {} to {} pixels (the side of the screen tiles the reference bins lembos into)",
                    crate::reference::oracle::TILE_RANGE.start(),
                    crate::reference::oracle::TILE_RANGE.end()
                ),
            ));
        }
        if let Some(n) = self.threads {
            check_count("--reference-threads", n, MAX_THREADS, "host threads")?;
        }
        Ok(())
    }

    /// Runs `f` on [`TraceSettings::threads`] threads, or on the caller's pool.
    pub fn install<T: Send>(&self, f: impl FnOnce() -> T + Send) -> Result<T> {
        match self.threads {
            None => Ok(f()),
            Some(n) => Ok(rayon::ThreadPoolBuilder::new()
                .num_threads(n as usize)
                .thread_name(|i| format!("reference-{i}"))
                .build()
                .map_err(|e| {
                    Error::Internal(format!("cannot start the reference's {n} threads: {e}"))
                })?
                .install(f)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tolerance::DEFAULT_K_PX;

    /// `render` with no flag given.
    fn job() -> RenderJob {
        RenderJob {
            trace: Default::default(),
            scene: None,
            out: None,
            k: DEFAULT_K_PX,
            perspective_tol: PerspectiveTol::FollowK,
            datapath: Datapath::F32,
            reference: false,
            supersample: 1,
            samples: Samples::ONE,
            flip_ppd: PixelsPerDegree::default(),
            viewport: None,
            mode: Mode::Timed,
            arch: None,
            arch_set: Vec::new(),
            trace_out: None,
            tech: None,
            path: PrimitivePath::Lembo,
            tess: None,
            blend: BlendMode::Rgba8,
            threshold: None,
            host_threads: 1,
            threads: None,
            given: Given::default(),
            no_memory_check: false,
        }
    }

    /// The flag, value and reason of an `Error::Invalid` from the command line.
    fn refused(e: Error) -> (String, String, String) {
        match e {
            Error::Invalid {
                file,
                field,
                value,
                reason,
            } if file == COMMAND_LINE => (field, value, reason),
            other => panic!("expected a command-line Error::Invalid, got {other:?}"),
        }
    }

    #[test]
    fn k_and_threshold_are_refused_with_their_checks_reasons() {
        assert!(job().validate().is_ok());
        let e = RenderJob { k: 100.0, ..job() }.validate().unwrap_err();
        let why = check_k(100.0).unwrap_err();
        assert_eq!(refused(e), ("--k".into(), "100".into(), why));
        let e = RenderJob {
            trace: Default::default(),
            threshold: Some(-0.5),
            ..job()
        }
        .validate()
        .unwrap_err();
        let why = check_threshold(-0.5).unwrap_err().to_string();
        assert_eq!(refused(e), ("--threshold".into(), "-0.5".into(), why));
    }

    #[test]
    fn flip_ppd_is_refused_without_a_reference() {
        let with = |reference| RenderJob {
            trace: Default::default(),
            reference,
            flip_ppd: PixelsPerDegree::new(30.0).unwrap(),
            given: Given {
                flip_ppd: true,
                ..Given::default()
            },
            ..job()
        };
        assert!(with(true).validate().is_ok());
        let (flag, value, why) = refused(with(false).validate().unwrap_err());
        assert_eq!((flag.as_str(), value.as_str()), ("--flip-ppd", "30"));
        assert!(why.contains("--reference"), "{why}");
    }

    #[test]
    fn check_threshold_accepts_a_positive_finite_distance_only() {
        assert_eq!(check_threshold(0.25), Ok(0.25));
        for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                check_threshold(t),
                Err("must be a finite distance above 0 world units"),
                "{t}"
            );
        }
    }
}
