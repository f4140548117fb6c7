//! The `lembo-sim` command: parse, validate, run, print. Everything else is in the library.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand, ValueEnum};
use lembo_sim::camera::Samples;
use lembo_sim::compare::{run_compare, CompareJob, MatchMetric, MatchPath, Tess};
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::graph::TessSource;
use lembo_sim::job::{self, run_render, Given, Mode, PrimitivePath, RenderJob};
use lembo_sim::reference::PixelsPerDegree;
use lembo_sim::sweep::{run_merge, run_sweep, MergeJob, Shard, SweepJob, SweepOutcome};
use lembo_sim::tolerance::{PerspectiveTol, DEFAULT_K_PX};
use std::io::Write as _;
use std::path::PathBuf;

/// Prints a line to standard output; a closed pipe (`| head`) is not an error worth a
/// panic, so write errors are ignored.
macro_rules! out {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}
use std::process::ExitCode;

/// Simulator of Martinelli's lembo rasterization unit (extreme method, WSCG 2006).
///
/// With no command, renders the embedded default scene (the paper's Figure 6 sphere of 24
/// lembos) on the timed pipeline of the baseline architecture into out/default/.
#[derive(Parser)]
#[command(name = "lembo-sim", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with the extreme method on the simulated unit (or as triangles,
    /// --path triangle) and write image.png, report.json, report.txt (and reference.png,
    /// error.png with --reference).
    Render(RenderArgs),
    /// Render a scene as lembos and as tessellated triangles on the same architecture,
    /// measure both against the exact surface, and write lembo.png, triangle.png,
    /// reference.png, lembo_error.png, triangle_error.png, lembo_flip.png,
    /// triangle_flip.png, montage.png, compare.json, compare.txt and report.html; print the
    /// table (primitives, vertices, bytes fetched and stored, cycles, area, energy on chip
    /// and in DRAM, fragments, accuracy per path). By default the triangle path's n is
    /// chosen to match the lembo path's accuracy (--tess auto, --match).
    Compare(CompareArgs),
    /// Run every point of a sweep spec (sim/sweeps/README.md) on every scene it names, in
    /// parallel, appending each run's record to DIR/results.jsonl as it finishes; then write
    /// results.jsonl in run order, results.csv and spec.json. Started again on the same
    /// DIR, it skips the runs already recorded.
    // Test hook, in builds with the `testkit` feature only (`stop_after_hook`): with the
    // environment variable LEMBO_SWEEP_STOP_AFTER=K the sweep stops once K records were
    // appended and exits with status 3, as if interrupted.
    Sweep(SweepArgs),
    /// Union the results of the shards of one sweep (each run with --shard I/N) into what
    /// an unsharded sweep writes: results.jsonl, results.csv and spec.json.
    SweepMerge(MergeArgs),
    /// Print the timed pipeline's unit graph, generated from the simulator's own
    /// description (src/graph.rs): the unit kinds in dataflow order, the boundaries between
    /// them (each a crossbar of FIFO links) with their dispatch rule (round-robin, batches,
    /// screen tile) and default FIFO depth and latency, and the units several kinds share
    /// (the memory port). --dot prints it as a Graphviz graph (`| dot -Tsvg`).
    Graph(GraphArgs),
}

#[derive(Args)]
struct GraphArgs {
    /// Which path's graph.
    #[arg(long, default_value = "lembo", value_parser = choices(&PATHS, PrimitivePath::name))]
    path: PrimitivePath,
    /// Where the triangle path's triangles come from (the architecture's
    /// tessellation.source); the lembo path has one graph.
    #[arg(long, default_value = "memory", value_parser = choices(&SOURCES, TessSource::name))]
    source: TessSource,
    /// Print Graphviz dot instead of text.
    #[arg(long)]
    dot: bool,
}

#[derive(Args)]
struct SweepArgs {
    /// Sweep spec (JSON, see sim/sweeps/README.md); scene and architecture paths in it are
    /// relative to its directory.
    spec: PathBuf,
    /// Output directory [default: out/sweeps/<spec name>/].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Runs at once, each on its own thread [default: the host's available parallelism].
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    /// Run only the runs whose index is I modulo N (0 <= I < N); merge the shards'
    /// directories with sweep-merge.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    shard: Option<(u32, u32)>,
    /// Host threads of each timed run (see `render --help`), clamped to each run's unit
    /// count; `--jobs` runs already fill the cores, so 1 is usually best.
    #[arg(long, value_name = "N", default_value_t = 1)]
    host_threads: u32,
    /// Run even when the runs at once (--jobs) are estimated to need more memory than the
    /// machine has available (/proc/meminfo's MemAvailable, or LEMBO_MEMORY_AVAILABLE bytes
    /// when set).
    #[arg(long)]
    no_memory_check: bool,
    /// Also give the answer for each value of this swept field (answer_by_<FIELD>.md, the
    /// table of how the answer moves with it, and one answer.md per value under
    /// by_<FIELD>/): `arch.framebuffer.bytes_per_cycle`, `samples`, `viewport`, ... Needs the
    /// spec's area_budget_mm2 [default: the spec's `by`, if any].
    #[arg(long, value_name = "FIELD")]
    by: Option<String>,
}

#[derive(Args)]
struct MergeArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", required = true)]
    out: PathBuf,
    /// The shards' output directories.
    #[arg(value_name = "SHARD_DIR", required = true)]
    shards: Vec<PathBuf>,
    /// Also give the answer for each value of this swept field (see `sweep --help`)
    /// [default: the spec's `by`, if any].
    #[arg(long, value_name = "FIELD")]
    by: Option<String>,
}

/// The test hook's environment variable: stop after this many records (exit status 3), read
/// in builds with the `testkit` feature only.
const STOP_AFTER_ENV: &str = "LEMBO_SWEEP_STOP_AFTER";
/// Exit status of a sweep stopped by the test hook.
const EXIT_STOPPED: u8 = 3;

/// The test hook: the records after which a sweep stops, from [`STOP_AFTER_ENV`] when set.
/// Only builds with the `testkit` feature read it (the tests' builds: Cargo.toml).
#[cfg(feature = "testkit")]
fn stop_after_hook() -> Result<Option<usize>, String> {
    match std::env::var(STOP_AFTER_ENV) {
        Err(_) => Ok(None),
        Ok(v) => v
            .trim()
            .parse::<usize>()
            .map(Some)
            .map_err(|e| format!("environment variable {STOP_AFTER_ENV} = {v:?}: {e}")),
    }
}

/// The shipped binary has no test hook: a sweep runs to its end.
#[cfg(not(feature = "testkit"))]
fn stop_after_hook() -> Result<Option<usize>, String> {
    Ok(None)
}

fn parse_shard(s: &str) -> Result<(u32, u32), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("expected I/N, got `{s}`"))?;
    let num = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("`{v}` in `{s}` is not a whole number: {e}"))
    };
    Ok((num(i)?, num(n)?))
}

#[derive(Clone, Copy, ValueEnum)]
enum BlendArg {
    /// Piranda et al. 2006 Table 1: averages in R and G, the sum of betas nibble-split in B and A,
    /// 8-bit saturating adds (8 bytes per fragment).
    Rgba8,
    /// Half-float target (16 bytes per fragment).
    F16,
    /// Single-float target (32 bytes per fragment).
    F32,
}

/// A flag's values: the command line's word and help for each value of one of the library's
/// own types, which the flag parses into directly (converted here, at the edge, with no
/// second enum for the same concept).
type Choices<T> = [(T, &'static str); 2];

/// `--path`: the library's [`PrimitivePath`], in its own names.
/// The triangle sources `graph --source` takes.
const SOURCES: Choices<TessSource> = [
    (
        TessSource::Memory,
        "A mesh tessellated ahead of the frame, read from memory",
    ),
    (TessSource::OnChip, "The lembos, tessellated on chip"),
];

const PATHS: Choices<PrimitivePath> = [
    (
        PrimitivePath::Lembo,
        "Lembos by the extreme method (Martinelli's unit)",
    ),
    (
        PrimitivePath::Triangle,
        "Each lembo tessellated into n² triangles (--tess), rasterized with edge functions",
    ),
];

/// `--mode`: the library's [`Mode`], in its own names.
const MODES: Choices<Mode> = [
    (
        Mode::Timed,
        "The Figure 5 pipeline with cycle accounting, run by a deterministic executor",
    ),
    (
        Mode::Functional,
        "The untimed functional model (what is drawn; the same image, no cycles)",
    ),
];

/// The parser of a flag whose values are `choices`, each named by `name`: clap lists them
/// with their help, and refuses any other word naming the flag and the values it takes.
fn choices<T: Copy + Send + Sync + 'static>(
    choices: &'static Choices<T>,
    name: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T> {
    let values = choices
        .iter()
        .map(move |&(v, help)| PossibleValue::new(name(v)).help(help));
    PossibleValuesParser::new(values).map(move |word| {
        choices
            .iter()
            .map(|&(v, _)| v)
            .find(|&v| name(v) == word)
            .expect("clap passes only the possible values")
    })
}

#[derive(Clone, Copy, ValueEnum)]
enum MatchArg {
    /// silhouette_max_px: the searched path's no larger than the other run's.
    Silhouette,
    /// psnr_db: the searched path's PSNR no smaller than the other run's.
    Psnr,
    /// flip_mean: the searched path's mean FLIP no larger than the other run's.
    Flip,
}

#[derive(Clone, Copy, ValueEnum)]
enum MatchPathArg {
    /// Search the triangle path's n (--tess auto) against the lembo run at --k.
    Triangle,
    /// Search the lembo path's k against the triangle run at --tess N.
    Lembo,
}

#[derive(Clone, Copy, ValueEnum)]
enum DatapathArg {
    /// IEEE binary32 throughout the extreme method, as hardware would be built.
    F32,
    /// IEEE binary64, to separate the method's error from rounding.
    F64,
}

/// The image-quality flags `render` and `compare` share: the samples a pixel, and the
/// reference and observer the images are measured against.
#[derive(Args)]
struct QualityArgs {
    /// Samples per pixel, 1, 2, 4 or 8, at Direct3D's standard positions: multisample
    /// anti-aliasing on either path (the scan-line stages walk every sample row, the ROPs
    /// depth-test and store every sample, and a resolve averages them; triangles are shaded
    /// once per pixel, lembo fragments once per sample). Cycles, frame-buffer bytes and energy
    /// grow with it (DESIGN.md §2). Not on discoid scenes.
    #[arg(long, value_name = "N", default_value = "1", value_parser = parse_samples)]
    samples: Samples,
    /// Reference samples per pixel side for reference.png (with one sample per pixel the
    /// metrics use pixel centres) [default: 1; with --samples above 1, 8: the
    /// area-averaged colours a resolved image is measured against].
    #[arg(long, value_name = "N")]
    supersample: Option<u32>,
    /// The observer FLIP (the perceptual error in a report's accuracy.flip_mean and its
    /// FLIP map) is computed for, in pixels per degree of visual angle; render takes it with
    /// --reference [default: 67.02, the reference implementation's 0.7 m wide 3840-pixel
    /// monitor seen from 0.7 m].
    #[arg(
        long,
        value_name = "PPD",
        value_parser = parse_flip_ppd,
        allow_hyphen_values = true
    )]
    flip_ppd: Option<PixelsPerDegree>,
    /// Side of the square screen tiles the exact reference bins lembos into, in pixels,
    /// from 4 to 1024: its memory and time, never its result (every image and metric is
    /// the same bit for bit at any tile side) [default: 16].
    #[arg(long, value_name = "PX")]
    reference_tile: Option<u32>,
    /// Host threads the exact reference and its accuracy metrics run on, from 1 to 256
    /// [default: the machine's cores].
    #[arg(long, value_name = "N")]
    reference_threads: Option<u32>,
}

impl QualityArgs {
    /// How the exact reference is traced.
    fn trace(&self) -> job::TraceSettings {
        job::TraceSettings {
            tile: self
                .reference_tile
                .unwrap_or(job::TraceSettings::default().tile),
            threads: self.reference_threads,
        }
    }
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (JSON, see traces/README.md); the embedded default scene when omitted.
    scene: Option<PathBuf>,
    /// Output directory [default: out/<scene name>/].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Tolerance k of the extreme method: the largest |y(u,v) - y_j| along a scanline's
    /// curve and the largest x error of a subsegment, in pixels, in [0.0001, 64]; refused
    /// where no lembo is drawn [default: 0.5].
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    k: Option<f64>,
    /// Setup's perspective tolerance \[pixels\], or `off`: Setup splits a lembo until its
    /// rebuilt screen quadratics are within this distance of the true perspective projection,
    /// and splits and clips lembos at the near plane. `off` is the paper's Setup (six
    /// projected points, no split for perspective, no near-plane clipping) [default: k/2].
    #[arg(
        long,
        value_name = "PX|off",
        value_parser = parse_perspective_tol,
        allow_hyphen_values = true
    )]
    perspective_tol: Option<PerspectiveTol>,
    /// Datapath precision of the extreme method.
    #[arg(long, value_enum, default_value = "f32")]
    datapath: DatapathArg,
    /// Also render the exact f64 reference and report accuracy (reference.png, error.png).
    #[arg(long)]
    reference: bool,
    #[command(flatten)]
    quality: QualityArgs,
    /// Simulation mode.
    #[arg(long, default_value = "timed", value_parser = choices(&MODES, Mode::name))]
    mode: Mode,
    /// Architecture configuration (JSON, see sim/arch/README.md): unit counts, costs,
    /// FIFO depths and latencies, clock [default: the embedded sim/arch/baseline.json].
    #[arg(long, value_name = "FILE")]
    arch: Option<PathBuf>,
    /// Set one architecture field on top of --arch, as FIELD=VALUE with the field's dotted
    /// path as in a sweep's `arch.` parameters (e.g. --set rasterizer.count=8 --set
    /// tessellation.source=onchip); repeatable; timed mode only. The value is JSON, or a
    /// bare word taken as a string.
    #[arg(long = "set", value_name = "FIELD=VALUE", value_parser = parse_set)]
    set: Vec<(String, serde_json::Value)>,
    /// Write a Chrome trace-event timeline of unit activity (open in ui.perfetto.dev or
    /// chrome://tracing); coarsened beyond a fixed number of events.
    #[arg(long, value_name = "FILE")]
    trace_out: Option<PathBuf>,
    /// Technology file pricing area and energy (JSON, see sim/tech/README.md): energy per
    /// operation, area per functional unit, SRAM and DRAM, each figure with its source
    /// [default: the embedded sim/tech/45nm.json]. Timed mode only.
    #[arg(long, value_name = "FILE")]
    tech: Option<PathBuf>,
    /// Override the scene's viewport, e.g. 1024x1024.
    #[arg(long, value_name = "WxH", value_parser = parse_viewport)]
    viewport: Option<(u32, u32)>,
    /// Which primitives draw the scene's surfaces; refused on a discoid scene [default:
    /// lembo].
    #[arg(long, value_parser = choices(&PATHS, PrimitivePath::name))]
    path: Option<PrimitivePath>,
    /// Precision of the discoid blend units in the ROP (scenes with discoids): rgba8 is the
    /// paper's Table 1 packing in one 8-bit target; f16 and f32 are float targets. Refused
    /// on a scene without discoids [default: rgba8].
    #[arg(long, value_enum)]
    blend: Option<BlendArg>,
    /// Discoid threshold t [world units]: fragments farther than t behind the depth pass's
    /// surface are not blended [default: the scene's discoid_threshold].
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    threshold: Option<f64>,
    /// Triangle path: tessellate each lembo into N² triangles, uniform in its domain, with
    /// vertices on the true patch [default: 1, a mesh's own triangles].
    #[arg(long, value_name = "N")]
    tess: Option<u32>,
    /// Host threads the timed model's units are partitioned over (contiguous runs of the
    /// dataflow order). Results are identical for every N; one thread runs all units with
    /// no synchronisation, which is fastest on small machines. At most the number of units
    /// the run instantiates.
    #[arg(long, value_name = "N", default_value_t = 1)]
    host_threads: u32,
    /// Host threads a functional frame (--mode functional) is drawn on, in bands of rows.
    /// The image, depth, every count and the fragment probe's measurements are identical
    /// for every N; the triangle path's frame measured against the reference (--reference)
    /// is drawn on one. [default: the machine's cores]
    #[arg(long, value_name = "N")]
    threads: Option<u32>,
    /// Run even when the memory estimate for this viewport is above the memory the machine
    /// has available (a run that large is refused before it starts otherwise). Available is
    /// /proc/meminfo's MemAvailable, or LEMBO_MEMORY_AVAILABLE (bytes) when set.
    #[arg(long)]
    no_memory_check: bool,
}

#[derive(Args)]
struct CompareArgs {
    /// Scene file (JSON, see traces/README.md); the embedded default scene when omitted.
    scene: Option<PathBuf>,
    /// Output directory [default: out/<scene name>/compare/].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Tolerance k of the lembo path \[pixels\], in [0.0001, 64].
    #[arg(
        long,
        value_name = "PX",
        default_value_t = DEFAULT_K_PX,
        allow_negative_numbers = true
    )]
    k: f64,
    /// Setup's perspective tolerance \[pixels\], or `off`: Setup splits a lembo until its
    /// rebuilt screen quadratics are within this distance of the true perspective projection,
    /// and splits and clips lembos at the near plane. `off` is the paper's Setup (six
    /// projected points, no split for perspective, no near-plane clipping) [default: k/2].
    #[arg(
        long,
        value_name = "PX|off",
        value_parser = parse_perspective_tol,
        allow_hyphen_values = true
    )]
    perspective_tol: Option<PerspectiveTol>,
    /// Tessellation level of the triangle path, or `auto`: the smallest N whose accuracy on
    /// the --match metric (the silhouette error by default) is at least the lembo path's at
    /// this k, N doubled from 1 and then bisected, up to 64 (less where the triangle budget
    /// stops it).
    #[arg(long, value_name = "N|auto", default_value = "auto", value_parser = parse_tess)]
    tess: Tess,
    /// The accuracy metric the search matches the two paths on [default: silhouette]: the
    /// searched level is the first whose metric is at least as good as the other path's
    /// run (silhouette_max_px and flip_mean no larger, psnr_db no smaller). compare.json's
    /// `match` and the notes under the table list every level tried with its value, the
    /// level chosen and how close it came. A target no level up to the knob's cap reaches
    /// is refused (exit status 2) naming the closest run; --match with --tess N and no
    /// --match-path lembo is refused (nothing is searched).
    #[arg(long = "match", value_enum, value_name = "METRIC")]
    matching: Option<MatchArg>,
    /// The path whose accuracy knob the match searches [default: triangle]: `triangle`, n
    /// with --tess auto, against the lembo run at --k; `lembo`, k against the triangle run
    /// at --tess N (a level: auto is refused): the largest k in [0.0001, 64] px, from --k
    /// halved until one matches (or doubled while it does), then bisected until it is
    /// within 5 % of the k above it that did not.
    #[arg(long, value_enum, value_name = "PATH")]
    match_path: Option<MatchPathArg>,
    /// Datapath precision of both paths.
    #[arg(long, value_enum, default_value = "f32")]
    datapath: DatapathArg,
    /// Architecture configuration shared by both paths [default: the embedded baseline].
    #[arg(long, value_name = "FILE")]
    arch: Option<PathBuf>,
    /// Set one architecture field on top of --arch, as FIELD=VALUE with the field's dotted
    /// path as in a sweep's `arch.` parameters (e.g. --set rasterizer.count=8 --set
    /// tessellation.source=onchip); repeatable; timed mode only. The value is JSON, or a
    /// bare word taken as a string.
    #[arg(long = "set", value_name = "FIELD=VALUE", value_parser = parse_set)]
    set: Vec<(String, serde_json::Value)>,
    /// Technology file pricing area and energy (JSON, see sim/tech/README.md): energy per
    /// operation, area per functional unit, SRAM and DRAM, each figure with its source
    /// [default: the embedded sim/tech/45nm.json].
    #[arg(long, value_name = "FILE")]
    tech: Option<PathBuf>,
    #[command(flatten)]
    quality: QualityArgs,
    /// Override the scene's viewport, e.g. 1024x1024.
    #[arg(long, value_name = "WxH", value_parser = parse_viewport)]
    viewport: Option<(u32, u32)>,
    /// Host threads each path's timed model is partitioned over (see `render --help`). At
    /// most the unit count of the smaller path (the triangle path's).
    #[arg(long, value_name = "N", default_value_t = 1)]
    host_threads: u32,
    /// Run even when the memory estimate for this viewport is above the memory the machine
    /// has available (a run that large is refused before it starts otherwise). Available is
    /// /proc/meminfo's MemAvailable, or LEMBO_MEMORY_AVAILABLE (bytes) when set.
    #[arg(long)]
    no_memory_check: bool,
}

fn parse_perspective_tol(s: &str) -> Result<PerspectiveTol, String> {
    PerspectiveTol::parse(s)
}

fn parse_flip_ppd(s: &str) -> Result<PixelsPerDegree, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a number: {e}"))?;
    PixelsPerDegree::new(v)
}

fn parse_samples(s: &str) -> Result<Samples, String> {
    let n: u32 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a count: {e}"))?;
    Samples::try_from(n)
}

fn parse_tess(s: &str) -> Result<Tess, String> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(Tess::Auto);
    }
    s.trim()
        .parse::<u32>()
        .map(Tess::Level)
        .map_err(|e| format!("expected a level N or `auto`, got `{s}`: {e}"))
}

fn datapath(d: DatapathArg) -> Datapath {
    match d {
        DatapathArg::F32 => Datapath::F32,
        DatapathArg::F64 => Datapath::F64,
    }
}

fn parse_viewport(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got `{s}`"))?;
    let num = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|e| format!("`{v}` is not a pixel count: {e}"))
    };
    Ok((num(w)?, num(h)?))
}

fn default_render() -> RenderArgs {
    RenderArgs {
        scene: None,
        out: None,
        k: None,
        perspective_tol: None,
        datapath: DatapathArg::F32,
        reference: false,
        quality: QualityArgs {
            samples: Samples::ONE,
            supersample: None,
            flip_ppd: None,
            reference_tile: None,
            reference_threads: None,
        },
        mode: Mode::Timed,
        arch: None,
        set: Vec::new(),
        trace_out: None,
        tech: None,
        viewport: None,
        path: None,
        tess: None,
        blend: None,
        threshold: None,
        host_threads: 1,
        threads: None,
        no_memory_check: false,
    }
}

fn main() -> ExitCode {
    // First, so that a Ctrl-C at any later point removes the temporary output files.
    if let Err(e) = lembo_sim::output::remove_temporaries_on_signals() {
        eprintln!("lembo-sim: warning: cannot handle SIGINT/SIGTERM ({e}); an interrupted run may leave hidden .*.tmp files, removed by the next run into the same directory");
    }
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Render(default_render())) {
        Command::Render(args) => render(args),
        Command::Compare(args) => compare(args),
        Command::Sweep(args) => sweep(args),
        Command::SweepMerge(args) => sweep_merge(args),
        Command::Graph(args) => graph(args),
    }
}

fn graph(args: GraphArgs) -> ExitCode {
    let (path, source) = (args.path, args.source);
    let text = if args.dot {
        lembo_sim::graph::dot(path, source)
    } else {
        lembo_sim::graph::diagram(path, source)
    };
    let _ = write!(std::io::stdout().lock(), "{text}");
    ExitCode::SUCCESS
}

fn sweep(args: SweepArgs) -> ExitCode {
    let fail = |message: String, code: u8| {
        eprintln!("lembo-sim: error: {message}");
        ExitCode::from(code)
    };
    let shard = match args.shard {
        None => Shard::ALL,
        Some((i, n)) => match Shard::new(i, n) {
            Ok(s) => s,
            Err(e) => return fail(e.to_string(), e.exit_code()),
        },
    };
    let stop_after = match stop_after_hook() {
        Ok(k) => k,
        Err(message) => return fail(message, 2),
    };
    let job = SweepJob {
        spec: args.spec,
        out: args.out,
        jobs: args.jobs,
        shard,
        stop_after,
        progress: true,
        host_threads: args.host_threads,
        no_memory_check: args.no_memory_check,
        by: args.by,
    };
    match run_sweep(&job) {
        Ok(SweepOutcome::Done(out)) => {
            let runs = format!(
                "{}{} ({} already done)",
                out.runs,
                if shard == Shard::ALL {
                    String::new()
                } else {
                    format!(" in shard {}/{}", shard.index, shard.count)
                },
                out.skipped,
            );
            let time = format!("{:.1} s on {} threads", out.wall_seconds, out.jobs);
            summary(
                &out.name,
                &runs,
                Some(&time),
                &out.dir,
                &out.files,
                &out.answer,
            );
            ExitCode::SUCCESS
        }
        Ok(SweepOutcome::Stopped { dir, appended }) => {
            eprintln!(
                "lembo-sim: stopped by {STOP_AFTER_ENV} after {appended} runs; results so far in {}",
                dir.display()
            );
            ExitCode::from(EXIT_STOPPED)
        }
        Err(e) => fail(e.to_string(), e.exit_code()),
    }
}

fn sweep_merge(args: MergeArgs) -> ExitCode {
    let job = MergeJob {
        out: args.out,
        shards: args.shards,
        by: args.by,
    };
    match run_merge(&job) {
        Ok(out) => {
            let runs = format!("{} merged", out.runs);
            summary(&out.name, &runs, None, &out.dir, &out.files, &out.answer);
            ExitCode::SUCCESS
        }
        Err(e) => failed(&e),
    }
}

/// A finished sweep's (or merge's) summary on stdout: runs, failures and time, where the
/// files are, and the answer's rows where the spec has an area budget.
fn summary(
    name: &str,
    runs: &str,
    time: Option<&str>,
    dir: &std::path::Path,
    files: &[String],
    answer: &[String],
) {
    out!("sweep {name}");
    out!("  runs     {runs}");
    // A failed run stops the sweep with its error; a rerun resumes after the runs done.
    out!("  failed   0");
    if let Some(time) = time {
        out!("  time     {time}");
    }
    let main: Vec<&str> = ["report.html", "answer.md", "results.csv"]
        .into_iter()
        .filter(|f| files.iter().any(|g| g == f))
        .collect();
    out!(
        "  folder   {} ({}; {} files)",
        dir.display(),
        main.join(", "),
        files.len()
    );
    if !answer.is_empty() {
        out!("answer (answer.md):");
        for line in answer {
            out!("  {line}");
        }
    }
}

/// Reports an error on stderr and gives its exit status (2 for bad input).
fn failed(e: &lembo_sim::error::Error) -> ExitCode {
    eprintln!("lembo-sim: error: {e}");
    ExitCode::from(e.exit_code())
}

/// After this long a render or compare shows its progress (when stderr is a terminal): a
/// shorter one ends before a bar would be read.
const PROGRESS_AFTER: std::time::Duration = std::time::Duration::from_secs(2);

/// Runs `work`, and while it runs, once it has taken [`PROGRESS_AFTER`] and if stderr is a
/// terminal, a progress bar on stderr: the stage (`lembo_sim::progress`) and its primitives
/// taken of those to take, cleared when the work ends. Nothing is drawn otherwise, so
/// captured output and pipes see none of it.
fn with_progress<T>(work: impl FnOnce() -> T) -> T {
    use std::io::IsTerminal as _;
    use std::sync::atomic::{AtomicBool, Ordering};
    if !std::io::stderr().is_terminal() {
        return work();
    }
    let done = AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| {
            let started = std::time::Instant::now();
            let tick = std::time::Duration::from_millis(200);
            while started.elapsed() < PROGRESS_AFTER {
                if done.load(Ordering::Relaxed) {
                    return;
                }
                std::thread::sleep(tick);
            }
            let bar = indicatif::ProgressBar::new(1).with_elapsed(started.elapsed());
            bar.set_style(
                indicatif::ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {msg}")
                    .expect("the template is valid")
                    .progress_chars("=> "),
            );
            while !done.load(Ordering::Relaxed) {
                // A stage that counts no primitives (the reference, the metrics) shows its
                // name over an empty bar.
                let (stage, taken, total) = lembo_sim::progress::snapshot();
                bar.set_length(total.max(taken).max(1));
                bar.set_position(taken);
                bar.set_message(match total {
                    0 => stage.to_string(),
                    _ => format!("{stage}: {taken}/{total} primitives"),
                });
                std::thread::sleep(tick);
            }
            bar.finish_and_clear();
        });
        let out = work();
        done.store(true, Ordering::Relaxed);
        out
    })
}

fn compare(args: CompareArgs) -> ExitCode {
    let job = CompareJob {
        trace: args.quality.trace(),
        scene: args.scene,
        out: args.out,
        k: args.k,
        perspective_tol: args.perspective_tol.unwrap_or_default(),
        tess: args.tess,
        datapath: datapath(args.datapath),
        arch: args.arch,
        arch_set: args.set,
        tech: args.tech,
        no_memory_check: args.no_memory_check,
        viewport: args.viewport,
        supersample: args.quality.supersample.unwrap_or(1),
        supersample_given: args.quality.supersample.is_some(),
        samples: args.quality.samples,
        flip_ppd: args.quality.flip_ppd.unwrap_or_default(),
        host_threads: args.host_threads,
        matching: args.matching.map(|m| match m {
            MatchArg::Silhouette => MatchMetric::Silhouette,
            MatchArg::Psnr => MatchMetric::Psnr,
            MatchArg::Flip => MatchMetric::Flip,
        }),
        match_path: args.match_path.map(|p| match p {
            MatchPathArg::Triangle => MatchPath::Triangle,
            MatchPathArg::Lembo => MatchPath::Lembo,
        }),
    };
    match with_progress(|| run_compare(&job)) {
        Ok(out) => {
            let _ = write!(std::io::stdout().lock(), "{}", out.table);
            out!("wrote {} to {}", out.files.join(", "), out.dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => failed(&e),
    }
}

fn render(args: RenderArgs) -> ExitCode {
    let given = Given {
        k: args.k.is_some(),
        perspective_tol: args.perspective_tol.is_some(),
        path: args.path.is_some(),
        blend: args.blend.is_some(),
        flip_ppd: args.quality.flip_ppd.is_some(),
        supersample: args.quality.supersample.is_some(),
    };
    let job = RenderJob {
        trace: args.quality.trace(),
        scene: args.scene,
        out: args.out,
        k: args.k.unwrap_or(DEFAULT_K_PX),
        perspective_tol: args.perspective_tol.unwrap_or_default(),
        datapath: datapath(args.datapath),
        reference: args.reference,
        supersample: args.quality.supersample.unwrap_or(1),
        samples: args.quality.samples,
        flip_ppd: args.quality.flip_ppd.unwrap_or_default(),
        viewport: args.viewport,
        mode: args.mode,
        arch: args.arch,
        arch_set: args.set,
        trace_out: args.trace_out,
        tech: args.tech.map(job::TechSource::File),
        path: args.path.unwrap_or_default(),
        tess: args.tess,
        blend: match args.blend.unwrap_or(BlendArg::Rgba8) {
            BlendArg::Rgba8 => BlendMode::Rgba8,
            BlendArg::F16 => BlendMode::F16,
            BlendArg::F32 => BlendMode::F32,
        },
        threshold: args.threshold,
        host_threads: args.host_threads,
        threads: args.threads,
        given,
        no_memory_check: args.no_memory_check,
    };
    match with_progress(|| run_render(&job)) {
        Ok(out) => {
            let _ = write!(std::io::stdout().lock(), "{}", out.report.summary());
            out!("wrote {} to {}", out.files.join(", "), out.dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => failed(&e),
    }
}

/// `--set FIELD=VALUE`: the field's dotted path and its value, JSON or a bare word.
fn parse_set(s: &str) -> Result<(String, serde_json::Value), String> {
    let (field, value) = s
        .split_once('=')
        .ok_or_else(|| format!("expected FIELD=VALUE, found `{s}`"))?;
    let field = field.trim();
    if field.is_empty() {
        return Err(format!("expected FIELD=VALUE, found `{s}`"));
    }
    let value = value.trim();
    let value = serde_json::from_str(value).unwrap_or_else(|_| serde_json::Value::from(value));
    Ok((field.to_string(), value))
}
