//! The timed discoid passes (Piranda et al. 2006, DESIGN.md §4): the depth pass and the
//! accumulation pass each run the whole pipeline (the lembo path for curved discoids, the triangle
//! path for planar ones) with the ROPs in that pass's mode, one after the other as a GPU runs
//! render passes; the resolve pass reads every pixel's accumulation target and writes its colour.
//! The frame's cycles are the three passes' sums.
//!
//! The accumulation pass's ROPs keep the fragments they accept and the blend is applied in
//! primitive order at the pass's end ([`DiscoidTarget::blend_in_order`]), as GPU ROPs blend
//! in API order; so the image is the functional model's, bit for bit. The cost of the
//! reordering hardware is not modelled.
//!
//! Resolve cost: each ROP reads and resolves the pixels of its tiles at
//! `rop.fragments_per_cycle`, and the frame-buffer port moves the mode's bytes per pixel
//! (one read of the accumulation target) and a 4-byte colour write per pixel; the pass
//! takes the longer of the two.
//!
//! The blend units work inside their ROPs (`graph::UnitKind::BlendUnit`): a kept fragment
//! costs its ROP `blend.cycles_per_fragment_<mode>` more, so their cycles are the ROPs'
//! and `cycles.units` does not list them; [`DiscoidTimed::blend_units`] gives each its
//! share (busy for its ROP's kept fragments at that rate), which the cost model sizes the
//! blend units by.

use super::unit::FetchPlan;
use super::{run_in, Cycle, CycleReport, DiscoidPass, Source, UnitCycles, UnitInstance, UnitKind};
use crate::camera::{View, Viewport};
use crate::config::{ArchConfig, BlendConfig};
use crate::datapath::{Datapath, Real};
use crate::discoid::blend::BlendMode;
use crate::discoid::report::BlendReport;
use crate::error::{Error, Result};
use crate::frame::discoid::{
    check_scene, resolve, DiscoidTable, DiscoidTarget, KeptFragment, Pass,
};
use crate::graph::TessSource;
use crate::raster::Counts;
use crate::rop::fragment_shader::FragmentShader;
use crate::rop::shade::to_u8;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::Tolerance;

use super::tiles::RopTiles;
use super::SimOptions;

/// What the timed discoid passes produced.
pub struct DiscoidTimed {
    /// The resolved image.
    pub framebuffer: FrameBuffer,
    /// The accumulation pass's counts, with the fragments blended as passed depth.
    pub counts: Counts,
    /// The units instantiated, the blend units included.
    pub units: Vec<UnitInstance>,
    /// The three passes' accounting, per unit and in total.
    pub cycles: CycleReport,
    /// The passes' counters and the blend error.
    pub blend: BlendReport,
    /// Each pass's frame cycles.
    pub passes: PassCycles,
    /// Each ROP's blend unit over the frame: busy for the fragments its ROP kept at
    /// `blend.cycles_per_fragment_<mode>`, starved the rest (cycles inside its ROP's busy
    /// ones, so not in `cycles.units`); `items_in` are the fragments it blended.
    pub blend_units: Vec<UnitCycles>,
    /// The bytes the passes moved through the frame-buffer port.
    pub port_bytes: PortBytes,
}

/// The bytes a discoid frame moves through the frame-buffer port, as the ROPs and the
/// resolve charge the port for them \[bytes\].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PortBytes {
    /// Depth and colour: the depth pass's depth reads for every fragment and depth writes
    /// for every winner, the accumulation pass's depth reads for every fragment, and the
    /// resolve's colour write per pixel.
    pub framebuffer: u64,
    /// The accumulation target: a read and a write of the pixel per kept fragment
    /// (`BlendMode::bytes_per_fragment`) and the resolve's read per pixel.
    pub accumulation: u64,
    /// The discoids the geometry fetch read, once a pass (DRAM bytes, read at the port's
    /// rate by the fetch itself, not through the frame-buffer port's time).
    pub geometry: u64,
}

/// The frame cycles of each timed discoid pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PassCycles {
    /// The depth pass's.
    pub depth: Cycle,
    /// The accumulation pass's.
    pub accumulation: Cycle,
    /// The resolve pass's.
    pub resolve: Cycle,
}

/// What a discoid scene's timed passes take their primitives from: its curved discoids as
/// lembos, or its planar ones as triangles; a scene with both is refused, naming it.
fn source_of<'t, R: Real>(scene: &Scene, table: &'t DiscoidTable<R>) -> Result<Source<'t>> {
    let (curved, planar) = (scene.lembo_count() > 0, !table.planar.items.is_empty());
    if curved && planar {
        return Err(Error::invalid(
            scene.source_name(),
            "objects",
            "curved and planar discoids",
            "the timed passes draw either curved or planar discoids in one scene (use --mode functional for both)",
        ));
    }
    Ok(if planar {
        Source::Triangles(&table.planar)
    } else {
        Source::Lembos
    })
}

/// The bytes through the memory port over the three passes: each pass's tested fragments
/// and the depth pass's writes, the accumulation target's fragments, the resolve, and the
/// primitives `geometry` read.
fn port_bytes(
    arch: &ArchConfig,
    vp: Viewport,
    mode: BlendMode,
    [first, second]: [&Counts; 2],
    accumulated: u64,
    geometry: u64,
) -> PortBytes {
    let fbc = &arch.framebuffer;
    let resolve_pass = blend_resolve_bytes(vp, mode);
    PortBytes {
        framebuffer: first.fragments * fbc.bytes_per_fragment_tested
            + first.fragments_passed_depth * fbc.bytes_per_fragment_tested
            + second.fragments * fbc.bytes_per_fragment_tested
            + resolve_pass.framebuffer,
        accumulation: accumulated * mode.bytes_per_fragment() + resolve_pass.accumulation,
        geometry,
    }
}

/// The unit with the most busy cycles (the first of a tie), by name.
fn busiest(units: &[UnitCycles]) -> Option<String> {
    units
        .iter()
        .fold(None::<&UnitCycles>, |best, u| match best {
            Some(b) if b.busy >= u.busy => Some(b),
            _ => Some(u),
        })
        .map(|u| u.name.clone())
}

/// Runs a discoid scene's three passes on the timed pipeline of `arch`.
#[allow(clippy::too_many_arguments)]
pub fn run_discoid_timed(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    arch: &ArchConfig,
    mode: BlendMode,
    threshold: f64,
    options: &SimOptions,
) -> Result<DiscoidTimed> {
    let tol = tol.into();
    match datapath {
        Datapath::F32 => passes::<f32>(scene, view, tol, arch, mode, threshold, options),
        Datapath::F64 => passes::<f64>(scene, view, tol, arch, mode, threshold, options),
    }
}

/// The DRAM memory model does not price the discoid passes yet (the accumulation target
/// needs its own surface and cache): refused, naming the field.
fn check_memory_model(arch: &ArchConfig) -> Result<()> {
    if arch.memory.model == crate::config::MemoryModel::Dram {
        return Err(Error::invalid(
            "architecture",
            "memory.model",
            "dram",
            "the DRAM memory model does not yet price the discoid passes; use \"port\" for a discoid scene",
        ));
    }
    Ok(())
}

fn passes<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    arch: &ArchConfig,
    mode: BlendMode,
    threshold: f64,
    options: &SimOptions,
) -> Result<DiscoidTimed> {
    check_scene(scene)?;
    check_memory_model(arch)?;
    let table = DiscoidTable::<R>::new(scene, view);
    let source = source_of(scene, &table)?;
    let pass = |pass: Pass, depth: &[f32], winner: &[u32]| {
        run_in::<R>(
            scene,
            view,
            tol,
            arch,
            source,
            Some(DiscoidPass {
                pass,
                table: &table,
                mode,
                blend_cycles: blend_cycles(&arch.blend, mode),
                threshold,
                depth,
                winner,
            }),
            options,
        )
    };
    let first = pass(Pass::Depth, &[], &[])?;
    let (depth, winner) = (first.framebuffer.depth, first.framebuffer.primitive);
    let second = pass(Pass::Accumulate, &depth, &winner)?;
    let blended = blended_per_rop(arch, view.viewport, second.discoid.as_ref());

    let vp = view.viewport;
    let mut target = DiscoidTarget::new(vp.width, vp.height, mode, threshold);
    target.depth = depth.into();
    target.winner = winner.into();
    if let Some((pending, counters)) = second.discoid {
        target.kept = pending;
        let r = &mut target.report;
        r.culled_backface = counters.culled_backface;
        r.discarded_beta_zero = counters.discarded_beta_zero;
        r.discarded_threshold = counters.discarded_threshold;
    }
    target.blend_in_order::<f32>();
    let shader = FragmentShader::<R>::new(&scene.light, view);
    let background = scene.background.map(to_u8::<f64>);
    let framebuffer = resolve::<R, f32>(&mut target, &table, &shader, background, vp.height);

    let (rop_busy, port_busy) = resolve_cost(arch, vp, mode);
    let port_bytes = port_bytes(
        arch,
        vp,
        mode,
        [&first.counts, &second.counts],
        target.report.fragments_accumulated,
        2 * FetchPlan::new(arch, source, TessSource::Memory, scene.lembo_count(), true).bytes,
    );
    let resolve_total = rop_busy.iter().copied().max().unwrap_or(0).max(port_busy);
    let (c1, c2) = (first.cycles, second.cycles);
    let units = merged_units(&c1, &c2, &rop_busy, port_busy, resolve_total);
    let total = c1.total + c2.total + resolve_total;
    let blend_units = blend_unit_cycles(arch, mode, &blended, total);
    let bottleneck = busiest(&units);
    let blend = target.report;
    let passes = PassCycles {
        depth: c1.total,
        accumulation: c2.total,
        resolve: Cycle(resolve_total),
    };
    let mut counts = second.counts;
    counts.fragments_passed_depth = blend.fragments_accumulated;
    counts.pixels_covered = framebuffer.covered() as u64;
    // The blend units and their accumulation target exist only in a discoid pass, which
    // lists them with its units (model only what the scene requires).
    let instances = second.units;
    Ok(DiscoidTimed {
        framebuffer,
        counts,
        units: instances,
        cycles: CycleReport {
            total,
            clock_mhz: arch.clock_mhz,
            fps: (total > Cycle::ZERO).then(|| arch.clock_mhz * 1e6 / total.as_f64()),
            bottleneck,
            units,
        },
        blend,
        passes,
        blend_units,
        port_bytes,
    })
}

/// The fragments each ROP's blend unit blends: the accumulation pass's kept fragments in
/// the ROP's tiles.
fn blended_per_rop(
    arch: &ArchConfig,
    vp: Viewport,
    kept: Option<&(Vec<KeptFragment>, BlendReport)>,
) -> Vec<u64> {
    let tiles = RopTiles::new(vp.width, vp.height, arch.rop.tile_px, arch.rop.count);
    let mut blended = vec![0u64; arch.rop.count as usize];
    for f in kept.into_iter().flat_map(|(k, _)| k) {
        let (i, j) = (f.idx % vp.width, f.idx / vp.width);
        blended[tiles.owner(i, j).0] += 1;
    }
    blended
}

/// Each blend unit's accounting over the frame of `total` cycles: busy for its fragments
/// at the mode's rate, starved otherwise (DiscoidTimed::blend_units).
fn blend_unit_cycles(
    arch: &ArchConfig,
    mode: BlendMode,
    blended: &[u64],
    total: Cycle,
) -> Vec<UnitCycles> {
    let rate = blend_cycles(&arch.blend, mode);
    blended
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            let busy = Cycle(n * rate);
            UnitCycles {
                name: format!("{}[{k}]", UnitKind::BlendUnit.name()),
                kind: UnitKind::BlendUnit,
                busy,
                starved: Cycle(total - busy),
                blocked: Cycle::ZERO,
                items_in: n,
                items_out: 0,
                max_fifo_occupancy: 0,
            }
        })
        .collect()
}

/// The resolve pass's busy cycles: each ROP's (its tiles' pixels at its fragment rate)
/// and the frame-buffer port's (every pixel's accumulation read and colour write).
fn resolve_cost(arch: &ArchConfig, vp: Viewport, mode: BlendMode) -> (Vec<u64>, u64) {
    let tiles = RopTiles::new(vp.width, vp.height, arch.rop.tile_px, arch.rop.count);
    let mut owned = vec![0u64; arch.rop.count as usize];
    for j in 0..vp.height {
        for i in 0..vp.width {
            owned[tiles.owner(i, j).0] += 1;
        }
    }
    let rop_busy: Vec<u64> = owned
        .iter()
        .map(|&p| arch.rop.fragments_per_cycle.ceil_div(p))
        .collect();
    let bytes = blend_resolve_bytes(vp, mode);
    let port_busy = arch
        .framebuffer
        .transfer_cycles(bytes.framebuffer + bytes.accumulation);
    (rop_busy, port_busy)
}

/// The colour bytes the resolve writes per pixel (RGBA8) \[bytes\].
const RESOLVE_COLOR_BYTES: u64 = 4;

/// The blend resolve pass's bytes through the frame-buffer port (not a multisample
/// resolve's, [`FrameBuffer::resolve_bytes`]): every pixel's accumulation
/// target read and its colour written.
fn blend_resolve_bytes(vp: Viewport, mode: BlendMode) -> PortBytes {
    let pixels = vp.pixels() as u64;
    PortBytes {
        framebuffer: pixels * RESOLVE_COLOR_BYTES,
        accumulation: pixels * mode.bytes_per_pixel(),
        geometry: 0,
    }
}

/// Each unit's accounting over the three passes: the depth and accumulation passes' sums,
/// plus the resolve pass, in which the ROPs and the port are busy for their share and
/// every unit starves the rest of `resolve_total`.
fn merged_units(
    c1: &CycleReport,
    c2: &CycleReport,
    rop_busy: &[u64],
    port_busy: u64,
    resolve_total: u64,
) -> Vec<UnitCycles> {
    // The resolve runs in the blend units' hosts (the ROPs) and the shared port they
    // write through, as the graph says.
    let host = UnitKind::BlendUnit.inside();
    let port = crate::graph::SHARED
        .iter()
        .find(|s| host.is_some_and(|h| crate::graph::boundary(h, s.port).is_some()))
        .map(|s| s.port);
    let mut rop_index = 0;
    c1.units
        .iter()
        .zip(&c2.units)
        .map(|(a, b)| {
            let busy = if Some(a.kind) == host {
                rop_index += 1;
                rop_busy[rop_index - 1]
            } else if Some(a.kind) == port {
                port_busy
            } else {
                0
            };
            UnitCycles {
                name: a.name.clone(),
                kind: a.kind,
                busy: a.busy + b.busy + busy,
                starved: a.starved + b.starved + (resolve_total - busy),
                blocked: a.blocked + b.blocked,
                items_in: a.items_in + b.items_in,
                items_out: a.items_out + b.items_out,
                max_fifo_occupancy: a.max_fifo_occupancy.max(b.max_fifo_occupancy),
            }
        })
        .collect()
}

/// Blend-unit cycles per kept fragment in `mode`.
pub fn blend_cycles(cfg: &BlendConfig, mode: BlendMode) -> u64 {
    match mode {
        BlendMode::Rgba8 => cfg.cycles_per_fragment_rgba8,
        BlendMode::F16 => cfg.cycles_per_fragment_f16,
        BlendMode::F32 => cfg.cycles_per_fragment_f32,
    }
}
