//! The `lembo-sim` command: parse, validate, run, print. Everything else is in the library.

use clap::{Args, Parser, Subcommand, ValueEnum};
use lembo_sim::datapath::Datapath;
use lembo_sim::job::{self, run_render, RenderJob};
use std::path::PathBuf;
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
    /// Render a scene with the extreme method on the simulated unit and write image.png,
    /// report.json, report.txt (and reference.png, error.png with --reference).
    Render(RenderArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum Mode {
    /// The Figure 5 pipeline, one thread per unit, with cycle accounting.
    Timed,
    /// The untimed functional model (what is drawn; the same image, no cycles).
    Functional,
}

#[derive(Clone, Copy, ValueEnum)]
enum DatapathArg {
    /// IEEE binary32 throughout the extreme method, as hardware would be built.
    F32,
    /// IEEE binary64, to separate the method's error from rounding.
    F64,
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (JSON, see traces/README.md); the embedded default scene when omitted.
    scene: Option<PathBuf>,
    /// Output directory [default: out/<scene name>/].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Tolerance k of the extreme method: the largest |y(u,v) - y_j| along a scanline's
    /// curve and the largest x error of a subsegment, in pixels, in [0.0001, 64].
    #[arg(
        long,
        value_name = "PX",
        default_value_t = 0.5,
        allow_negative_numbers = true
    )]
    k: f64,
    /// Datapath precision of the extreme method.
    #[arg(long, value_enum, default_value = "f32")]
    datapath: DatapathArg,
    /// Also render the exact f64 reference and report accuracy (reference.png, error.png).
    #[arg(long)]
    reference: bool,
    /// Reference samples per pixel side for reference.png (metrics use pixel centres).
    #[arg(long, value_name = "N", default_value_t = 1)]
    supersample: u32,
    /// Simulation mode.
    #[arg(long, value_enum, default_value = "timed")]
    mode: Mode,
    /// Architecture configuration (JSON, see sim/arch/README.md): unit counts, costs,
    /// FIFO depths and latencies, clock [default: the embedded sim/arch/baseline.json].
    #[arg(long, value_name = "FILE")]
    arch: Option<PathBuf>,
    /// Write a Chrome trace-event timeline of unit activity (open in ui.perfetto.dev or
    /// chrome://tracing); coarsened beyond a fixed number of events.
    #[arg(long, value_name = "FILE")]
    trace_out: Option<PathBuf>,
    /// Override the scene's viewport, e.g. 1024x1024.
    #[arg(long, value_name = "WxH", value_parser = parse_viewport)]
    viewport: Option<(u32, u32)>,
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
        k: 0.5,
        datapath: DatapathArg::F32,
        reference: false,
        supersample: 1,
        mode: Mode::Timed,
        arch: None,
        trace_out: None,
        viewport: None,
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let Command::Render(args) = cli.command.unwrap_or(Command::Render(default_render()));
    let job = RenderJob {
        scene: args.scene,
        out: args.out,
        k: args.k,
        datapath: match args.datapath {
            DatapathArg::F32 => Datapath::F32,
            DatapathArg::F64 => Datapath::F64,
        },
        reference: args.reference,
        supersample: args.supersample,
        viewport: args.viewport,
        mode: match args.mode {
            Mode::Timed => job::Mode::Timed,
            Mode::Functional => job::Mode::Functional,
        },
        arch: args.arch,
        trace_out: args.trace_out,
    };
    match run_render(&job) {
        Ok(out) => {
            let r = &out.report;
            let c = &r.counts;
            println!(
                "{}: {} lembos, {}x{} px, k = {} px, {}: {} scanlines, {} intervals, {} segments, {} subsegments, {} fragments ({} passed depth)",
                r.scene.name,
                r.scene.lembos,
                r.scene.width,
                r.scene.height,
                r.settings.k_px,
                r.settings.datapath,
                c.scanlines,
                c.intervals,
                c.segments,
                c.subsegments,
                c.fragments,
                c.fragments_passed_depth
            );
            match &r.cycles {
                Some(cy) => println!(
                    "timed ({}): {} cycles = {} at {} MHz, bottleneck {}; host {:.3} s, {:.1} M simulated cycles/s",
                    r.arch.as_ref().map(|a| a.name.as_str()).unwrap_or("?"),
                    cy.total,
                    cy.fps
                        .map(|f| format!("{f:.1} frames/s"))
                        .unwrap_or_else(|| "empty frame".into()),
                    cy.clock_mhz,
                    cy.bottleneck.as_deref().unwrap_or("none"),
                    r.host.wall_seconds,
                    r.host.simulated_cycles_per_second.unwrap_or(0.0) / 1e6
                ),
                None => println!(
                    "render {:.3} s ({:.1} M fragments/s, functional model, single thread)",
                    r.host.wall_seconds,
                    r.host.fragments_per_second / 1e6
                ),
            }
            if let Some(a) = &r.accuracy {
                println!(
                    "accuracy: PSNR {:.2} dB, coverage +{} / -{} px, silhouette max {:.2} px, cracks {}, double hits {}, max |y - y_j| {:.4} px",
                    a.psnr_db,
                    a.coverage_false_positive,
                    a.coverage_false_negative,
                    a.silhouette_max_px,
                    a.crack_pixels,
                    a.double_hit_pixels,
                    a.max_scanline_deviation_px
                );
            }
            println!("wrote {} to {}", out.files.join(", "), out.dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("lembo-sim: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
