//! A unit's area and energy from what it did (DESIGN.md §12).
//!
//! - **Datapath area.** A kind that performed `n` operations of a class over `b` busy
//!   cycles (summed over its instances) needs `ceil(n / b)` functional units of that class
//!   per instance to sustain the rate its architecture configures: the configured cycles
//!   per item are what the busy cycles count. A class it never used costs nothing.
//! - **FIFO area.** A unit owns its input FIFOs: one link per producer instance, each
//!   `fifo_depth` entries of the producing unit's `OUT_WORDS` datapath words.
//! - **Energy.** Operations times their energy; every item through a FIFO is written once
//!   and read once; every byte through the frame-buffer port is a DRAM byte; plus leakage
//!   over the frame's time when the technology file gives a figure.
//!
//! A kind's operations are shared among its instances in proportion to the items each
//! took in.

use super::counted::OpTable;
use super::tech::Tech;
use crate::config::ArchConfig;
use crate::datapath::{Datapath, OPS};
use crate::graph::UnitKind;
use crate::pipeline::{self, CycleReport};
use serde::Serialize;

/// `cost` in report.json: what the unit would cost in silicon for this frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CostReport {
    /// The technology file's name.
    pub tech: String,
    /// Die area of the instantiated units: datapaths and FIFOs \[mm²\].
    pub area_mm2: f64,
    /// Energy of the frame: operations, FIFO traffic, frame-buffer bytes, leakage \[pJ\].
    pub energy_pj: f64,
    /// Average power over the frame at the architecture's clock; null for an empty frame
    /// \[mW\].
    pub power_mw: Option<f64>,
    /// The frame's bytes through the frame-buffer port, priced as DRAM \[bytes\].
    pub framebuffer_bytes: u64,
    /// Each instance, in dataflow order.
    pub units: Vec<UnitCost>,
    /// The operations each kind performed, counted by the code that does them.
    pub ops: Vec<KindOps>,
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
    /// Functional units of each class its datapath needs \[units\].
    pub functional_units: OpCounts,
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
    /// The operations per kind (the counting run).
    pub ops: &'a OpTable,
    /// The timed run's per-unit accounting.
    pub cycles: &'a CycleReport,
    /// Bytes through the frame-buffer port.
    pub framebuffer_bytes: u64,
}

/// The cost of `work` on `arch` in `datapath`, priced by `tech`.
pub fn cost(tech: &Tech, arch: &ArchConfig, datapath: Datapath, work: &Work) -> CostReport {
    let units = &work.cycles.units;
    let word_bits = match datapath {
        Datapath::F32 => 32.0,
        Datapath::F64 => 64.0,
    };
    let of_kind = |kind: UnitKind| units.iter().filter(move |u| u.kind == kind);
    let instances = |kind: UnitKind| of_kind(kind).count() as u64;
    let mut out = Vec::with_capacity(units.len());
    for u in units {
        let ops = work.ops.of(u.kind);
        let busy: u64 = of_kind(u.kind).map(|v| v.busy.0).sum();
        let items: u64 = of_kind(u.kind).map(|v| v.items_in).sum();
        let share = if items > 0 {
            u.items_in as f64 / items as f64
        } else {
            1.0 / instances(u.kind) as f64
        };
        let mut fus = [0u64; OPS.len()];
        let (mut area_um2, mut energy_pj) = (0.0, 0.0);
        for (k, &op) in OPS.iter().enumerate() {
            if ops[k] == 0 {
                continue;
            }
            fus[k] = ops[k].div_ceil(busy.max(1));
            let (pj, um2) = tech.op(datapath, op);
            area_um2 += fus[k] as f64 * um2;
            energy_pj += ops[k] as f64 * share * pj;
        }
        // Input FIFOs: one link from every producer instance.
        let (mut fifo_um2, mut fifo_pj) = (0.0, 0.0);
        for (b, link) in arch.links.boundaries().filter(|(b, _)| b.to == u.kind) {
            let producers = instances(b.from);
            let bits = pipeline::out_words(b.from) as f64 * word_bits;
            fifo_um2 +=
                (producers * link.fifo_depth as u64) as f64 * bits * tech.sram.area_um2_per_bit;
            if producers > 0 {
                fifo_pj += 2.0 * u.items_in as f64 * bits / 64.0 * tech.sram.access_pj_per_64_bits;
            }
        }
        if u.kind == UnitKind::FrameBuffer {
            energy_pj += work.framebuffer_bytes as f64 * tech.dram.pj_per_byte;
        }
        out.push(UnitCost {
            name: u.name.clone(),
            area_mm2: (area_um2 + fifo_um2) * 1e-6,
            energy_pj: energy_pj + fifo_pj,
            fifo_area_mm2: fifo_um2 * 1e-6,
            fifo_energy_pj: fifo_pj,
            functional_units: OpCounts::from_array(fus),
        });
    }
    let area_mm2: f64 = out.iter().map(|u| u.area_mm2).sum();
    let frame_us = work.cycles.total.0 as f64 / work.cycles.clock_mhz;
    // mW × µs = nJ.
    let leakage_pj = tech.logic_leakage.mw_per_mm2 * area_mm2 * frame_us * 1e3;
    let energy_pj = out.iter().map(|u| u.energy_pj).sum::<f64>() + leakage_pj;
    let mut kinds: Vec<UnitKind> = units.iter().map(|u| u.kind).collect();
    kinds.dedup();
    CostReport {
        tech: tech.name.clone(),
        area_mm2,
        energy_pj,
        // pJ / µs = µW.
        power_mw: (frame_us > 0.0).then(|| energy_pj / frame_us * 1e-3),
        framebuffer_bytes: work.framebuffer_bytes,
        units: out,
        ops: kinds
            .into_iter()
            .map(|k| KindOps {
                kind: k.name().to_string(),
                ops: OpCounts::from_array(work.ops.of(k)),
            })
            .collect(),
    }
}
