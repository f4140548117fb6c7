//! The design point a unit's datapath is sized for (DESIGN.md §12): area is a property of
//! the architecture, not of the frame drawn on it.
//!
//! A unit that must sustain its configured rate (its `cycles_per_*` or `*_per_cycle`
//! fields) needs, of each operation class, as many functional units as it performs
//! operations of that class per busy cycle. That figure depends on what it is given to do
//! (a lembo's scanlines, a triangle's coverage, a span's length), so it is fixed once, at a
//! stated design point: the largest operations per busy cycle each kind performed over a
//! calibration set of frames, measured at the embedded baseline architecture's rates and
//! committed as `src/cost/design_point.json`, which the build embeds.
//!
//! - **Entries** are keyed `<datapath> <frames> <unit> <op>`: the datapath (`f32`, `f64`),
//!   the frames' class (`surface`, or `discoid` for a scene with discoids, whose ROPs do
//!   the discoid work and host blend units), the unit's kind, with what changes what it
//!   computes: the triangle rasterizer's reciprocal (`TriangleRasterizer/quad`, `/pixel`),
//!   the blend unit's mode (`BlendUnit/rgba8`, `/f16`, `/f32`) and the ROP's path
//!   (`Rop/lembo` works out each fragment's normal from the lembo's (u, v), `Rop/triangle`
//!   interpolates planes), and the operation class. Each holds the operations per busy cycle and the calibration case
//!   that set it.
//! - **Another architecture's rates.** A unit whose rate differs from the baseline's does
//!   proportionally more (or fewer) operations per busy cycle: the design point is scaled
//!   by the unit's speed-up over the baseline ([`speedup`]), the largest ratio among its
//!   rate fields (halving `segmenter.cycles_per_segment` doubles it). A unit with several
//!   rates is thus sized for the fastest of them, an upper bound when only some change.
//! - **Functional units** of a class per instance: `ceil(design point x speed-up)`. The
//!   instance count only multiplies them.
//! - **The calibration set** is the integration test `design_point` (in
//!   `tests/integration/design_point.rs`), which re-measures every entry and fails naming
//!   each that moved; `LEMBO_BLESS=1 cargo test --release --test integration design_point`
//!   rewrites the file.
//!
//! A frame outside the calibration set can do more operations per busy cycle than its
//! units were sized for: its energy (from its own counts) is right, its area is the
//! architecture's, and its cycles assume the rate was sustained.

use crate::config::{ArchConfig, Reciprocal};
use crate::datapath::{Datapath, Op, OPS};
use crate::discoid::blend::BlendMode;
use crate::graph::{PrimitivePath, Rate, UnitKind, Variant};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// The committed design point, embedded.
pub const DESIGN_POINT_JSON: &str = include_str!("design_point.json");

/// The file's shape: what it is, how to regenerate it, and its entries.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignPointFile {
    /// What the file is (DESIGN.md §12).
    pub about: String,
    /// The command that regenerates it.
    pub regenerate: String,
    /// The calibration set, in words.
    pub calibration: String,
    /// Every entry, by key (`f32 surface Rop mul`).
    pub entries: BTreeMap<String, DesignEntry>,
}

/// One entry: a kind's operations of one class per busy cycle at the design point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignEntry {
    /// The largest operations per busy cycle over the calibration set \[operations/cycle\].
    pub per_busy_cycle: f64,
    /// The calibration case that set it.
    pub at: String,
}

/// The embedded design point, parsed once.
pub fn embedded() -> &'static DesignPointFile {
    static FILE: OnceLock<DesignPointFile> = OnceLock::new();
    FILE.get_or_init(|| {
        // Part of the binary and checked by a unit test: failing here is a build defect.
        serde_json::from_str(DESIGN_POINT_JSON).expect("the embedded design point parses")
    })
}

/// What a frame's unit is sized as: the frames' class and the unit's variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizing {
    /// The datapath the frame runs in.
    pub datapath: Datapath,
    /// The discoid frames' blend mode; None for a surface frame.
    pub blend: Option<BlendMode>,
    /// The triangle rasterizer's reciprocal.
    pub reciprocal: Reciprocal,
    /// The path the frame's ROPs serve.
    pub path: PrimitivePath,
}

impl Sizing {
    /// The entries' key of `kind`'s class `op` (the module's text).
    pub fn key(&self, kind: UnitKind, op: Op) -> String {
        let frames = if self.blend.is_some() {
            "discoid"
        } else {
            "surface"
        };
        format!(
            "{} {frames} {} {}",
            self.datapath.name(),
            self.unit(kind),
            op.name()
        )
    }

    /// The unit's name in keys: its kind's, with the variant that changes what it
    /// computes.
    fn unit(&self, kind: UnitKind) -> String {
        let variant = match kind.variant() {
            Some(Variant::Reciprocal) => Some(match self.reciprocal {
                Reciprocal::Quad => "quad",
                Reciprocal::Pixel => "pixel",
            }),
            Some(Variant::BlendMode) => self.blend.map(BlendMode::name),
            Some(Variant::Path) => Some(self.path.name()),
            None => None,
        };
        match variant {
            Some(v) => format!("{}/{v}", kind.name()),
            None => kind.name().to_string(),
        }
    }

    /// Functional units of each class (in [`OPS`] order) one instance of `kind` needs on
    /// `arch`, from `design`: the design point scaled by the unit's [`speedup`], rounded up.
    pub fn functional_units(
        &self,
        design: &DesignPointFile,
        arch: &ArchConfig,
        kind: UnitKind,
    ) -> [u64; OPS.len()] {
        let speed = speedup(arch, kind, self.blend);
        let mut out = [0; OPS.len()];
        for (n, &op) in out.iter_mut().zip(OPS.iter()) {
            if let Some(e) = design.entries.get(&self.key(kind, op)) {
                *n = (e.per_busy_cycle * speed).ceil() as u64;
            }
        }
        out
    }
}

/// How much faster `kind` runs on `arch` than on the embedded baseline: the largest ratio
/// among its rate fields ([`UnitKind::rates`]: baseline over `arch` for cycles an item,
/// `arch` over baseline for items a cycle). A field set to 0 cycles (an item that costs
/// no cycle) is left out; a kind without a rate runs at 1. The blend units' rate is their
/// mode's `cycles_per_fragment_<mode>`.
pub fn speedup(arch: &ArchConfig, kind: UnitKind, blend: Option<BlendMode>) -> f64 {
    static BASE: OnceLock<serde_json::Value> = OnceLock::new();
    let base = BASE.get_or_init(|| rate_fields(&ArchConfig::baseline()));
    let now = rate_fields(arch);
    let mode = blend.unwrap_or(BlendMode::F32).name();
    kind.rates()
        .iter()
        .filter_map(|rate| {
            let (path, per_item) = match *rate {
                Rate::CyclesPerItem(p) => (p, true),
                Rate::ItemsPerCycle(p) => (p, false),
            };
            let path = path.replace("{mode}", mode);
            let (b, a) = (rate_value(base, &path), rate_value(&now, &path));
            (a > 0.0 && b > 0.0).then_some(if per_item { b / a } else { a / b })
        })
        .fold(None, |m: Option<f64>, r| Some(m.map_or(r, |m| m.max(r))))
        .unwrap_or(1.0)
}

/// An architecture as its file holds it, where [`UnitKind::rates`] name their fields.
fn rate_fields(arch: &ArchConfig) -> serde_json::Value {
    serde_json::to_value(arch).expect("an architecture serialises")
}

/// The number at `path` (`section.field`) of an architecture's fields.
///
/// # Panics
/// When the path names no number: a rate the graph declares that the architecture lacks
/// (a unit test reads every kind's rates on the baseline).
fn rate_value(fields: &serde_json::Value, path: &str) -> f64 {
    path.split('.')
        .fold(fields, |v, key| &v[key])
        .as_f64()
        .unwrap_or_else(|| panic!("the graph's rate field {path} is no number of the architecture"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The embedded file parses, says how to regenerate it, and holds entries of every
    /// kind that computes on each path, in both datapaths.
    #[test]
    fn the_embedded_design_point_parses_and_covers_both_paths() {
        let d = embedded();
        assert!(d.regenerate.contains("LEMBO_BLESS=1"), "{}", d.regenerate);
        for (dp, path) in [
            (Datapath::F32, PrimitivePath::Lembo),
            (Datapath::F64, PrimitivePath::Lembo),
            (Datapath::F32, PrimitivePath::Triangle),
            (Datapath::F64, PrimitivePath::Triangle),
        ] {
            let sizing = |datapath| Sizing {
                datapath,
                blend: None,
                reciprocal: Reciprocal::Quad,
                path,
            };
            for kind in [
                UnitKind::Setup,
                UnitKind::MinMax,
                UnitKind::IntervalManager,
                UnitKind::Segmenter,
                UnitKind::Subsegmenter,
                UnitKind::FragmentRasterizer,
                UnitKind::Tessellator,
                UnitKind::DomainEval,
                UnitKind::TriangleSetup,
                UnitKind::TriangleRasterizer,
                UnitKind::Rop,
            ] {
                let key = sizing(dp).key(kind, Op::Add);
                let add = d.entries.get(&key);
                let int_add = d.entries.get(&sizing(dp).key(kind, Op::IntAdd));
                assert!(add.or(int_add).is_some(), "no {key}");
            }
        }
        for e in d.entries.values() {
            assert!(
                e.per_busy_cycle > 0.0 && e.per_busy_cycle.is_finite(),
                "{e:?}"
            );
        }
    }

    /// The baseline runs every kind at 1; halving a cycles-per-item rate or doubling an
    /// items-per-cycle one doubles it; a unit with several rates takes the fastest.
    /// Every rate the graph declares names a positive number of the baseline's fields, in
    /// every blend mode: a renamed field fails here, not in a user's run.
    #[test]
    fn every_rate_the_graph_declares_is_a_field_of_the_architecture() {
        let fields = rate_fields(&ArchConfig::baseline());
        let mut named = 0;
        for kind in crate::graph::KINDS {
            for rate in kind.rates() {
                let (Rate::CyclesPerItem(path) | Rate::ItemsPerCycle(path)) = *rate;
                for mode in BlendMode::ALL {
                    let path = path.replace("{mode}", mode.name());
                    assert!(rate_value(&fields, &path) > 0.0, "{kind:?}: {path}");
                    named += 1;
                }
            }
        }
        assert!(named >= 15 * 3, "{named} rates read");
    }

    #[test]
    fn a_units_speedup_is_its_fastest_rate_over_the_baselines() {
        let base = ArchConfig::baseline();
        for kind in crate::graph::KINDS {
            assert_eq!(speedup(&base, kind, Some(BlendMode::F16)), 1.0, "{kind:?}");
        }
        let mut a = base.clone();
        a.segmenter.cycles_per_segment = 1;
        a.rop.fragments_per_cycle = crate::config::Ratio::whole(2);
        a.interval_manager.cycles_per_scanline = 6;
        a.triangle_setup.culled_per_cycle = 2;
        a.blend.cycles_per_fragment_f32 = 1;
        assert_eq!(speedup(&a, UnitKind::Segmenter, None), 2.0);
        assert_eq!(speedup(&a, UnitKind::Rop, None), 2.0);
        // Slower scanlines, intervals as before: the intervals' rate holds.
        assert_eq!(speedup(&a, UnitKind::IntervalManager, None), 1.0);
        // Culling faster widens only the area test: no speed-up of the setup's datapath.
        assert_eq!(speedup(&a, UnitKind::TriangleSetup, None), 1.0);
        assert_eq!(speedup(&a, UnitKind::BlendUnit, Some(BlendMode::F32)), 2.0);
        assert_eq!(speedup(&a, UnitKind::BlendUnit, Some(BlendMode::F16)), 1.0);
        a.interval_manager.cycles_per_interval = 4;
        assert_eq!(speedup(&a, UnitKind::IntervalManager, None), 0.5);
    }
}
