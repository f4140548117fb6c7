//! A unit's area and energy (DESIGN.md §12): its area from the architecture, its energy
//! from what it did this frame.
//!
//! - **Datapath area.** An instance of a kind gets, of each operation class, the
//!   functional units that sustain its configured rate at the design point
//!   ([`super::design_point`]): the largest operations per busy cycle the kind performed
//!   over a calibration set at the baseline's rates, scaled by the unit's speed-up over
//!   them, rounded up. The same on every scene, k, n and sample count: a frame's own
//!   operations per busy cycle are kept beside the report ([`CostReport::per_busy_cycle`],
//!   not serialised) for the calibration to take its maximum from. A class the design point
//!   has no entry for costs nothing.
//! - **FIFO area.** A unit owns its input FIFOs: one link per producer instance, each
//!   `fifo_depth` entries of the producing unit's `OUT_WORDS` datapath words.
//! - **Energy.** Operations times their energy; every item through a FIFO is written once
//!   and read once; every byte through the frame-buffer port is a DRAM byte (a discoid
//!   frame's accumulation target included); every bit stored on chip leaks for the whole
//!   frame at the SRAM's leakage per MB; the datapaths leak at the logic figure per mm² (0
//!   in the shipped files: not modelled).
//! - **On-chip SRAM.** Every buffer the model stores on chip is priced by one function,
//!   [`price_sram`]: area per bit, energy per 64 bits moved, leakage per bit stored over the
//!   frame. The FIFOs are the only such buffers today; a vertex cache or a parameter buffer
//!   priced later goes through it too.
//! - **Blend units** (a discoid frame). They sit inside their ROPs: their busy cycles are
//!   their share of the ROP's, a kept fragment's `blend.cycles_per_fragment_<mode>`
//!   ([`BlendWork::units`]), which the ROPs' own operations per busy cycle are measured
//!   without; they have no FIFO of their own. Their operations are the
//!   blend ALU's, counted in `f32`, and priced at the width of the mode's stored word
//!   ([`blend_figures`]): rgba8 on 8-bit fixed-point units, f16 on half-precision ones, f32
//!   on single-precision ones; their design point is their mode's.
//!
//! A kind's operations are shared among its instances in proportion to the items each
//! took in.

use super::counted::OpTable;
use super::design_point::{self, DesignPointFile, Sizing};
use super::memory_kind::DramEnergySplit;
use super::tech::{DramKind, Sram, Tech};
use crate::config::ArchConfig;
use crate::datapath::{Datapath, Op, OPS};
use crate::discoid::blend::BlendMode;
use crate::graph::{Traffic, UnitKind, DISCOID_KINDS, KINDS};
use crate::pipeline::{self, CycleReport, UnitCycles};
use serde::Serialize;
use std::collections::BTreeMap;

/// `cost` in report.json: what the unit would cost in silicon for this frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CostReport {
    /// The technology file that priced the frame.
    pub tech: TechUsed,
    /// Die area of the instantiated units: datapaths and FIFOs \[mm²\].
    pub area_mm2: f64,
    /// Energy of the frame: operations, FIFO traffic, frame-buffer bytes, leakage \[pJ\].
    pub energy_pj: f64,
    /// The part of `energy_pj` that is the on-chip SRAM's leakage over the frame \[pJ\].
    pub sram_leakage_pj: f64,
    /// The part of `energy_pj` that is the datapaths' leakage over the frame (0 with the
    /// shipped technology files: not modelled) \[pJ\].
    pub logic_leakage_pj: f64,
    /// Average power over the frame at the architecture's clock; null for an empty frame
    /// \[mW\].
    pub power_mw: Option<f64>,
    /// The frame's bytes through the frame-buffer port, priced as DRAM, without the
    /// discoid accumulation target's \[bytes\].
    pub framebuffer_bytes: u64,
    /// The discoid accumulation target's bytes through the frame-buffer port, priced as
    /// DRAM beside `framebuffer_bytes`: a read and a write per fragment blended and the
    /// resolve's read per pixel; 0 without discoids \[bytes\].
    pub accumulation_bytes: u64,
    /// The primitives the geometry fetch read through the port (every pass's), priced as
    /// DRAM beside `framebuffer_bytes` \[bytes\].
    pub geometry_bytes: u64,
    /// The blend units, for a discoid frame; null otherwise.
    pub blend: Option<BlendCost>,
    /// With the DRAM memory model, the frame buffer's DRAM energy by atoms read, atoms
    /// written and activations, which replaces `framebuffer_bytes` at `dram_pj_per_byte`
    /// \[pJ\]; left out with the port.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub framebuffer_dram: Option<DramEnergySplit>,
    /// Each instance, in dataflow order.
    pub units: Vec<UnitCost>,
    /// The operations each kind performed, counted by the code that does them; for the
    /// units priced as built (the triangle path's), as hardware would do them
    /// (`cost::built`).
    pub ops: Vec<KindOps>,
    /// This frame's operations per busy cycle of each kind that computed, by design-point
    /// key ([`Sizing::key`]): what the calibration set's maximum is taken over. Not in
    /// report.json.
    #[serde(skip)]
    pub per_busy_cycle: BTreeMap<String, f64>,
}

impl CostReport {
    /// The part of [`Self::energy_pj`] spent in DRAM: every byte through the memory port
    /// (`framebuffer_bytes`, `accumulation_bytes` and `geometry_bytes`) at the DRAM's
    /// figure, or with the DRAM memory model the controller's atoms and activations (the
    /// geometry fetch's reads among them) \[pJ\]. Computed from the report's own fields, so a reader of report.json
    /// gets the same figure.
    pub fn dram_energy_pj(&self) -> f64 {
        match &self.framebuffer_dram {
            // The controller's atoms include the geometry fetch's reads.
            Some(d) => d.total_pj + self.accumulation_bytes as f64 * self.tech.dram_pj_per_byte,
            None => {
                (self.framebuffer_bytes + self.accumulation_bytes + self.geometry_bytes) as f64
                    * self.tech.dram_pj_per_byte
            }
        }
    }

    /// The part of [`Self::energy_pj`] spent on chip: the operations, the FIFOs' accesses and
    /// the SRAM's and logic's leakage, everything but [`Self::dram_energy_pj`] \[pJ\].
    pub fn on_chip_energy_pj(&self) -> f64 {
        self.energy_pj - self.dram_energy_pj()
    }
}

/// `cost.tech` in report.json: which technology file priced the frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TechUsed {
    /// The file's name (`45nm`).
    pub name: String,
    /// Its process node \[nm\].
    pub node_nm: f64,
    /// The DRAM the frame-buffer bytes were priced as.
    pub dram_kind: DramKind,
    /// That DRAM's energy per byte \[pJ\].
    pub dram_pj_per_byte: f64,
}

/// One unit instance's cost.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitCost {
    /// The instance's name (`Segmenter[1]`).
    pub name: String,
    /// Its area, datapath and FIFOs \[mm²\].
    pub area_mm2: f64,
    /// Its energy this frame \[pJ\].
    pub energy_pj: f64,
    /// The part of the area in its input FIFOs \[mm²\].
    pub fifo_area_mm2: f64,
    /// The part of the energy in its input FIFOs' writes and reads \[pJ\].
    pub fifo_energy_pj: f64,
    /// The part of the energy its input FIFOs leak over the frame \[pJ\].
    pub fifo_leakage_pj: f64,
    /// With the DRAM memory model, a ROP's colour and depth caches' part of the area
    /// \[mm²\]; left out when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub cache_area_mm2: f64,
    /// Their accesses and leakage this frame \[pJ\]; left out when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub cache_energy_pj: f64,
    /// Functional units of each class its datapath has: the architecture's, sized for
    /// its configured rate at the design point (DESIGN.md §12), whatever the frame \[units\].
    pub functional_units: OpCounts,
}

/// `cost.blend`: what a discoid frame's blend units and accumulation target cost, for
/// holding the precision modes side by side (their instances are among `units`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlendCost {
    /// The precision mode: `rgba8`, `f16` or `f32`.
    pub mode: String,
    /// The technology file's group the blend units are priced with: `int8`, `f16` or
    /// `f32` ([`blend_figures`]).
    pub priced_as: String,
    /// Fragments the blend units blended \[fragments\].
    pub fragments: u64,
    /// The blend units' area, summed over the instances \[mm²\].
    pub area_mm2: f64,
    /// Their operations' energy this frame \[pJ\].
    pub energy_pj: f64,
    /// That energy per fragment blended; null when none was \[pJ\].
    pub energy_pj_per_fragment: Option<f64>,
    /// The accumulation target's bytes per pixel (`BlendMode::bytes_per_pixel`) \[bytes\].
    pub accumulation_bytes_per_pixel: u64,
    /// The accumulation bytes' energy at the DRAM figure, part of the frame-buffer port's
    /// \[pJ\].
    pub accumulation_energy_pj: f64,
}

/// Counts per operation class (report order of [`OPS`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
#[allow(missing_docs)] // named by their class, see datapath::Op
pub struct OpCounts {
    pub add: u64,
    pub mul: u64,
    pub div: u64,
    pub sqrt: u64,
    pub cmp: u64,
    pub round: u64,
    pub other: u64,
    pub int_add: u64,
    pub int_mul: u64,
}

impl OpCounts {
    fn from_array(a: [u64; OPS.len()]) -> OpCounts {
        let [add, mul, div, sqrt, cmp, round, other, int_add, int_mul] = a;
        OpCounts {
            add,
            mul,
            div,
            sqrt,
            cmp,
            round,
            other,
            int_add,
            int_mul,
        }
    }

    /// The counts in [`OPS`] order.
    pub fn to_array(self) -> [u64; OPS.len()] {
        [
            self.add,
            self.mul,
            self.div,
            self.sqrt,
            self.cmp,
            self.round,
            self.other,
            self.int_add,
            self.int_mul,
        ]
    }
}

/// One kind's operations this frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct KindOps {
    /// The kind's name.
    pub kind: String,
    /// Its operations, summed over its instances.
    #[serde(flatten)]
    pub ops: OpCounts,
}

/// What a timed frame did, for its cost.
pub struct Work<'a> {
    /// The operations per kind and the hardware events (the counting run), before the
    /// units built differently are priced as built.
    pub ops: &'a OpTable,
    /// The timed run's per-unit accounting.
    pub cycles: &'a CycleReport,
    /// Bytes through the frame-buffer port, the accumulation target's apart.
    pub framebuffer_bytes: u64,
    /// The discoid accumulation target's bytes through the frame-buffer port.
    pub accumulation_bytes: u64,
    /// The geometry fetch's bytes through the port.
    pub geometry_bytes: u64,
    /// Triangle corners whose transformed vertex setup reused (post-transform vertex cache
    /// hits; on-chip, corners beyond each patch's first use of a point), whose vertex work
    /// the triangle setup does not do ([`super::built::setup_per_vertex`]).
    pub vertices_reused: u64,
    /// The blend units' work, for a discoid frame.
    pub blend: Option<BlendWork<'a>>,
    /// With the DRAM memory model: the frame buffer's DRAM energy, priced per atom and
    /// activation, and the ROP caches; None with the port (its bytes at the DRAM's figure).
    pub memory: Option<MemoryWork>,
}

/// What the DRAM memory model's frame buffer did, for its cost.
#[derive(Clone, Copy, Debug)]
pub struct MemoryWork {
    /// The frame buffer's DRAM energy: atoms read and written and row activations, priced
    /// by the technology file's memory kind ([`super::memory_kind::MemoryKind::energy_pj`]).
    pub dram: DramEnergySplit,
    /// Bits of SRAM in each ROP's colour and depth caches.
    pub cache_bits_per_rop: f64,
    /// Bits every ROP's caches read or wrote: sectors touched, filled and written back.
    pub cache_bits_moved: f64,
}

/// What a discoid frame's blend units did.
pub struct BlendWork<'a> {
    /// Their precision mode.
    pub mode: BlendMode,
    /// Each blend unit's accounting: busy for its fragments at the mode's rate, the
    /// fragments it blended as items in (`pipeline::discoid::DiscoidTimed::blend_units`).
    pub units: &'a [UnitCycles],
}

/// The technology group a blend unit of `mode` is priced with, and one operation's energy
/// \[pJ\] and area \[µm²\] of class `op` there: the width of the word the mode stores. The
/// model computes every mode's update in `f32` (the image is that of an `f32` blend ALU
/// storing the mode's words); the counts follow the hardware, a unit as wide as its words.
pub fn blend_figures(tech: &Tech, mode: BlendMode, op: Op) -> (&'static str, (f64, f64)) {
    match mode {
        BlendMode::Rgba8 => ("int8", tech.int8_op(op)),
        BlendMode::F16 => ("f16", tech.f16_op(op)),
        BlendMode::F32 => ("f32", tech.op(Datapath::F32, op)),
    }
}

/// Bits in a MB of SRAM (2^20 bytes), the unit of [`Sram::leakage_mw_per_mb`].
pub const BITS_PER_MB: f64 = 8.0 * 1_048_576.0;

/// What an on-chip SRAM array costs this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SramCost {
    /// Its area \[µm²\].
    pub area_um2: f64,
    /// Its reads and writes \[pJ\].
    pub access_pj: f64,
    /// Its leakage over the frame \[pJ\].
    pub leakage_pj: f64,
}

impl std::ops::AddAssign for SramCost {
    fn add_assign(&mut self, c: SramCost) {
        self.area_um2 += c.area_um2;
        self.access_pj += c.access_pj;
        self.leakage_pj += c.leakage_pj;
    }
}

/// The one price of on-chip storage: an array of `bits_stored` bits through which
/// `bits_moved` bits were written or read, powered for `frame_us` microseconds.
pub fn price_sram(sram: &Sram, bits_stored: f64, bits_moved: f64, frame_us: f64) -> SramCost {
    let leakage_mw = sram.leakage_mw_per_mb * bits_stored / BITS_PER_MB;
    SramCost {
        area_um2: bits_stored * sram.area_um2_per_bit,
        access_pj: bits_moved / 64.0 * sram.access_pj_per_64_bits,
        // mW × µs = nJ.
        leakage_pj: leakage_mw * frame_us * 1e3,
    }
}

/// The cost of `work` on `arch` in `datapath`, priced by `tech`, its units sized at the
/// embedded design point.
pub fn cost(tech: &Tech, arch: &ArchConfig, datapath: Datapath, work: &Work) -> CostReport {
    cost_at(tech, arch, datapath, work, design_point::embedded())
}

/// [`cost`] with the units sized at `design`.
pub fn cost_at(
    tech: &Tech,
    arch: &ArchConfig,
    datapath: Datapath,
    work: &Work,
    design: &DesignPointFile,
) -> CostReport {
    let sizing = Sizing {
        datapath,
        blend: work.blend.as_ref().map(|b| b.mode),
        reciprocal: arch.triangle_rasterizer.reciprocal,
        path: pipeline::PrimitivePath::of_kinds(work.cycles.units.iter().map(|u| u.kind)),
    };
    // The units built differently from the model priced as built (DESIGN.md §12).
    let ops = super::built::as_built(
        work.ops,
        arch.triangle_rasterizer.reciprocal,
        work.vertices_reused,
    );
    // The timed units and the blend units inside their ROPs, in dataflow order.
    let mut units: Vec<&UnitCycles> = work.cycles.units.iter().collect();
    units.extend(work.blend.iter().flat_map(|b| b.units));
    units.sort_by_key(|u| KINDS.iter().position(|&k| k == u.kind));
    let frame = Frame {
        tech,
        arch,
        datapath,
        work,
        design,
        sizing,
        ops: &ops,
        units: &units,
        kinds: units.iter().map(|u| u.kind).collect(),
        frame_us: work.cycles.total.0 as f64 / work.cycles.clock_mhz,
    };
    let mut per_busy_cycle = BTreeMap::new();
    let mut logic_leakage_pj = 0.0;
    let out: Vec<UnitCost> = units
        .iter()
        .map(|u| {
            let (cost, leak) = frame.unit(u, &mut per_busy_cycle);
            logic_leakage_pj += leak;
            cost
        })
        .collect();
    let area_mm2: f64 = out.iter().map(|u| u.area_mm2).sum();
    let energy_pj: f64 = out.iter().map(|u| u.energy_pj).sum();
    let mut kinds = frame.kinds.clone();
    kinds.dedup();
    let blend = work
        .blend
        .as_ref()
        .map(|b| blend_cost(tech, b.mode, &units, &out, work.accumulation_bytes));
    let frame_us = frame.frame_us;
    CostReport {
        tech: TechUsed::of(tech),
        area_mm2,
        energy_pj,
        sram_leakage_pj: out.iter().map(|u| u.fifo_leakage_pj).sum(),
        logic_leakage_pj,
        // pJ / µs = µW.
        power_mw: (frame_us > 0.0).then(|| energy_pj / frame_us * 1e-3),
        framebuffer_bytes: work.framebuffer_bytes,
        accumulation_bytes: work.accumulation_bytes,
        geometry_bytes: work.geometry_bytes,
        blend,
        framebuffer_dram: work.memory.map(|m| m.dram),
        units: out,
        ops: kinds
            .into_iter()
            .map(|k| KindOps {
                kind: k.name().to_string(),
                ops: OpCounts::from_array(ops.of(k)),
            })
            .collect(),
        per_busy_cycle,
    }
}

/// Whether a figure is 0 (left out of report.json).
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// What pricing one frame's units needs, worked out once for all of them.
struct Frame<'f> {
    tech: &'f Tech,
    arch: &'f ArchConfig,
    datapath: Datapath,
    work: &'f Work<'f>,
    design: &'f DesignPointFile,
    sizing: Sizing,
    /// The operations as built.
    ops: &'f OpTable,
    /// The units priced, in dataflow order, and their kinds.
    units: &'f [&'f UnitCycles],
    kinds: Vec<UnitKind>,
    /// The frame's length \[µs\].
    frame_us: f64,
}

impl Frame<'_> {
    /// One operation of class `op` in a unit of `kind`: its energy \[pJ\] and area
    /// \[µm²\]; a discoid kind's in the blend mode's number format ([`DISCOID_KINDS`]).
    fn price(&self, kind: UnitKind, op: Op) -> (f64, f64) {
        match &self.work.blend {
            Some(b) if DISCOID_KINDS.contains(&kind) => blend_figures(self.tech, b.mode, op).1,
            _ => self.tech.op(self.datapath, op),
        }
    }

    /// The DRAM bytes priced on `kind` ([`UnitKind::dram`]).
    fn dram_bytes(&self, kind: UnitKind) -> u64 {
        let w = self.work;
        match kind.dram() {
            Some(Traffic::Frame) => w.framebuffer_bytes + w.accumulation_bytes,
            Some(Traffic::Geometry) => w.geometry_bytes,
            None => 0,
        }
    }

    /// The DRAM energy priced on `kind`: its bytes at the DRAM's figure, or with the DRAM
    /// memory model the controller's atoms and activations, the geometry fetch's reads
    /// among them, all on the frame buffer \[pJ\].
    fn dram_energy(&self, kind: UnitKind) -> f64 {
        let w = self.work;
        match (kind.dram(), &w.memory) {
            (Some(Traffic::Frame), Some(m)) => {
                m.dram.total_pj + w.accumulation_bytes as f64 * self.tech.dram.pj_per_byte
            }
            // Read through the controller, priced there.
            (Some(Traffic::Geometry), Some(_)) => 0.0,
            _ => self.dram_bytes(kind) as f64 * self.tech.dram.pj_per_byte,
        }
    }

    /// A ROP's colour and depth caches with the DRAM memory model (none otherwise): its
    /// arrays, its `share` of every ROP's sector traffic, and their leakage.
    fn rop_caches(&self, u: &UnitCycles, share: f64) -> SramCost {
        match &self.work.memory {
            Some(m) if u.kind.frame_caches() => price_sram(
                &self.tech.sram,
                m.cache_bits_per_rop,
                m.cache_bits_moved * share,
                self.frame_us,
            ),
            _ => SramCost::default(),
        }
    }

    /// Unit `u`'s cost and its datapath's leakage \[pJ\], its kind's operations per busy
    /// cycle recorded in `per_busy_cycle`.
    fn unit(&self, u: &UnitCycles, per_busy_cycle: &mut BTreeMap<String, f64>) -> (UnitCost, f64) {
        let kind_ops = self.ops.of(u.kind);
        let (busy, share) = busy_and_share(self.units, u);
        let fus = self.sizing.functional_units(self.design, self.arch, u.kind);
        let (mut area_um2, mut energy_pj) = (0.0, 0.0);
        for (k, &op) in OPS.iter().enumerate() {
            let (pj, um2) = self.price(u.kind, op);
            area_um2 += fus[k] as f64 * um2;
            if kind_ops[k] == 0 {
                continue;
            }
            energy_pj += kind_ops[k] as f64 * share * pj;
            if busy > 0 {
                let key = self.sizing.key(u.kind, op);
                per_busy_cycle.insert(key, kind_ops[k] as f64 / busy as f64);
            }
        }
        // mW/mm² × mm² × µs = nJ.
        let tech = self.tech;
        let logic_leak_pj = tech.logic_leakage.mw_per_mm2 * area_um2 * 1e-6 * self.frame_us * 1e3;
        let word_bits = match self.datapath {
            Datapath::F32 => 32.0,
            Datapath::F64 => 64.0,
        };
        let fifo = input_fifos(tech, self.arch, u, &self.kinds, word_bits, self.frame_us);
        energy_pj += self.dram_energy(u.kind);
        let cache = self.rop_caches(u, share);
        let cost = UnitCost {
            name: u.name.clone(),
            area_mm2: (area_um2 + fifo.area_um2 + cache.area_um2) * 1e-6,
            energy_pj: energy_pj
                + logic_leak_pj
                + fifo.access_pj
                + fifo.leakage_pj
                + cache.access_pj
                + cache.leakage_pj,
            fifo_area_mm2: fifo.area_um2 * 1e-6,
            fifo_energy_pj: fifo.access_pj,
            fifo_leakage_pj: fifo.leakage_pj,
            cache_area_mm2: cache.area_um2 * 1e-6,
            cache_energy_pj: cache.access_pj + cache.leakage_pj,
            functional_units: OpCounts::from_array(fus),
        };
        (cost, logic_leak_pj)
    }
}

/// Unit `u`'s kind's own busy cycles over `units` (those of the units inside it, a ROP's
/// blend units whose cycles its ROP's include, are theirs), and `u`'s share of the kind's
/// work (its items over the kind's; an equal share when no item came in).
fn busy_and_share(units: &[&UnitCycles], u: &UnitCycles) -> (u64, f64) {
    let of_kind = || units.iter().filter(|v| v.kind == u.kind);
    let hosted: u64 = units
        .iter()
        .filter(|v| v.kind.inside() == Some(u.kind))
        .map(|v| v.busy.0)
        .sum();
    let busy = of_kind()
        .map(|v| v.busy.0)
        .sum::<u64>()
        .saturating_sub(hosted);
    let items: u64 = of_kind().map(|v| v.items_in).sum();
    let share = if items > 0 {
        u.items_in as f64 / items as f64
    } else {
        1.0 / of_kind().count() as f64
    };
    (busy, share)
}

/// Unit `u`'s input FIFOs: one link from every producer instance (of `kinds`, every unit's
/// kind), each item written and read.
fn input_fifos(
    tech: &Tech,
    arch: &ArchConfig,
    u: &UnitCycles,
    kinds: &[UnitKind],
    word_bits: f64,
    frame_us: f64,
) -> SramCost {
    let mut fifo = SramCost::default();
    let wired = arch.links.boundaries().filter(|(b, _)| {
        b.to == u.kind
            && b.wired_in(
                kinds,
                arch.tessellation.source,
                arch.memory.model == crate::config::MemoryModel::Dram,
            )
    });
    for (b, link) in wired {
        let producers = kinds.iter().filter(|&&k| k == b.from).count() as u64;
        let bits = pipeline::out_words(b.from) as f64 * word_bits;
        let stored = (producers * link.fifo_depth as u64) as f64 * bits;
        let moved = if producers > 0 {
            2.0 * u.items_in as f64 * bits
        } else {
            0.0
        };
        fifo += price_sram(&tech.sram, stored, moved, frame_us);
    }
    fifo
}

impl TechUsed {
    /// What report.json says of the technology that priced the frame.
    fn of(tech: &Tech) -> TechUsed {
        TechUsed {
            name: tech.name.clone(),
            node_nm: tech.node_nm,
            dram_kind: tech.dram.kind,
            dram_pj_per_byte: tech.dram.pj_per_byte,
        }
    }
}

/// The blend units' part of a discoid frame's cost: their area and energy, summed from
/// the priced units (`out`, in the order of `units`).
fn blend_cost(
    tech: &Tech,
    mode: BlendMode,
    units: &[&UnitCycles],
    out: &[UnitCost],
    accumulation_bytes: u64,
) -> BlendCost {
    let priced = units
        .iter()
        .zip(out)
        .filter(|(u, _)| DISCOID_KINDS.contains(&u.kind));
    let (area_mm2, energy_pj) = priced.clone().fold((0.0, 0.0), |(a, e), (_, c)| {
        (a + c.area_mm2, e + c.energy_pj)
    });
    let fragments: u64 = priced.map(|(u, _)| u.items_in).sum();
    BlendCost {
        mode: mode.name().to_string(),
        priced_as: blend_figures(tech, mode, Op::Add).0.to_string(),
        fragments,
        area_mm2,
        energy_pj,
        energy_pj_per_fragment: (fragments > 0).then(|| energy_pj / fragments as f64),
        accumulation_bytes_per_pixel: mode.bytes_per_pixel(),
        accumulation_energy_pj: accumulation_bytes as f64 * tech.dram.pj_per_byte,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::datapath::Op;
    use crate::pipeline::{Cycle, UnitCycles};

    /// A megabyte stored for 2 µs at 45 nm leaks 100 mW × 2 µs = 200 nJ; two 64-bit
    /// accesses cost 2 × 10 pJ.
    #[test]
    fn an_sram_array_leaks_its_power_over_the_frame() {
        let t = Tech::default_45nm();
        let c = price_sram(&t.sram, BITS_PER_MB, 128.0, 2.0);
        assert_eq!(c.leakage_pj, 200_000.0);
        assert_eq!(c.access_pj, 20.0);
        assert_eq!(c.area_um2, BITS_PER_MB * 0.69);
        let idle = price_sram(&t.sram, 0.0, 0.0, 2.0);
        assert_eq!(idle, SramCost::default());
    }

    fn unit(name: &str, kind: UnitKind, busy: u64, items_in: u64) -> UnitCycles {
        UnitCycles {
            name: name.to_string(),
            kind,
            busy: Cycle(busy),
            starved: Cycle(0),
            blocked: Cycle(0),
            items_in,
            items_out: items_in,
            max_fifo_occupancy: 1,
        }
    }

    /// A ROP and the frame buffer over 1 000 cycles at 500 MHz (2 µs): the frame buffer's
    /// FIFO (one ROP's link) leaks for the whole frame, whatever passed through it; the
    /// parts add up to the totals; logic leakage is charged on the datapath area only.
    #[test]
    fn leakage_is_charged_per_unit_and_in_the_totals() {
        let mut tech = Tech::default_45nm();
        let arch = ArchConfig::default();
        let mut ops = OpTable::default();
        ops.add(UnitKind::Rop, Op::Mul, 400);
        let cycles = CycleReport {
            total: Cycle(1000),
            clock_mhz: 500.0,
            fps: None,
            bottleneck: None,
            units: vec![
                unit("Rop[0]", UnitKind::Rop, 200, 100),
                unit("FrameBuffer", UnitKind::FrameBuffer, 100, 100),
            ],
        };
        let work = Work {
            ops: &ops,
            cycles: &cycles,
            framebuffer_bytes: 1000,
            accumulation_bytes: 0,
            geometry_bytes: 0,
            vertices_reused: 0,
            blend: None,
            memory: None,
        };
        // A design point of two multipliers in the ROP: 400 over 200 busy cycles, as this
        // frame did.
        let mut design = DesignPointFile::default();
        design.entries.insert(
            "f32 surface Rop/lembo mul".into(),
            design_point::DesignEntry {
                per_busy_cycle: 2.0,
                at: "this test".into(),
            },
        );
        let c = cost_at(&tech, &arch, Datapath::F32, &work, &design);
        assert_eq!(c.per_busy_cycle["f32 surface Rop/lembo mul"], 2.0);
        assert_eq!(c.units[0].functional_units.mul, 2);
        let link = arch.links.get(UnitKind::Rop, UnitKind::FrameBuffer);
        let item_bits = pipeline::out_words(UnitKind::Rop) as f64 * 32.0;
        let stored = link.fifo_depth as f64 * item_bits;
        let fb = &c.units[1];
        let expected = price_sram(&tech.sram, stored, 2.0 * 100.0 * item_bits, 2.0);
        assert_eq!(fb.fifo_leakage_pj, expected.leakage_pj);
        assert!(fb.fifo_leakage_pj > 0.0);
        assert_eq!(fb.fifo_energy_pj, expected.access_pj);
        assert_eq!(
            fb.energy_pj,
            1000.0 * 162.5 + expected.access_pj + expected.leakage_pj
        );
        let sum: f64 = c.units.iter().map(|u| u.fifo_leakage_pj).sum();
        assert_eq!(c.sram_leakage_pj, sum);
        assert_eq!(
            c.energy_pj,
            c.units.iter().map(|u| u.energy_pj).sum::<f64>()
        );
        assert_eq!(c.logic_leakage_pj, 0.0);
        assert_eq!(c.tech.dram_kind, DramKind::Ddr4);
        // The split: the frame buffer's DRAM bytes, and the rest on chip.
        assert_eq!(c.dram_energy_pj(), 1000.0 * 162.5);
        let on_chip = c.energy_pj - 1000.0 * 162.5;
        assert!((c.on_chip_energy_pj() - on_chip).abs() < 1e-9 * c.energy_pj);
        assert!(c.on_chip_energy_pj() >= expected.access_pj + expected.leakage_pj);
        // 1 mW/mm² of logic: the ROP's two multipliers (400 over 200 busy cycles), 2 µs.
        tech.logic_leakage.mw_per_mm2 = 1.0;
        let leaky = cost_at(&tech, &arch, Datapath::F32, &work, &design);
        let logic = 2.0 * 7700.0 * 1e-6 * 2.0 * 1e3;
        assert!((leaky.logic_leakage_pj - logic).abs() < 1e-9, "{leaky:?}");
        assert!((leaky.energy_pj - c.energy_pj - logic).abs() < 1e-6);
    }
}
