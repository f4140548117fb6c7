//! The technology file (`sim/tech/*.json`, `--tech FILE`): energy per operation \[pJ\] and
//! area per functional unit \[µm²\] for the f32, f64 and fixed-point datapaths (and the
//! discoid blend units' f16 and 8-bit fixed-point units); on-chip SRAM per bit, per access
//! and its leakage per MB; the DRAM's kind and energy per byte; logic leakage per mm².
//! Every figure is required (no defaults: a cost nobody wrote down is not a cost), finite
//! and above 0 (the two leakages: 0 or above); each group carries a `note`
//! citing its source, and the file a `source` (DESIGN.md §12).

use crate::datapath::{Datapath, Op};
use crate::error::{read_text_file, Error, Result};
use crate::json::parse_strict;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The embedded default, `sim/tech/45nm.json`.
pub const DEFAULT_TECH_JSON: &str = include_str!("../../sim/tech/45nm.json");

/// One floating-point datapath's functional units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)] // each field is named by its operation and unit
pub struct FloatUnits {
    pub add_pj: f64,
    pub mul_pj: f64,
    pub div_pj: f64,
    pub sqrt_pj: f64,
    pub cmp_pj: f64,
    pub round_pj: f64,
    pub add_um2: f64,
    pub mul_um2: f64,
    pub div_um2: f64,
    pub sqrt_um2: f64,
    pub cmp_um2: f64,
    pub round_um2: f64,
    /// Where the figures come from.
    pub note: String,
}

/// The fixed-point units beside the datapath (32-bit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct IntUnits {
    pub add_pj: f64,
    pub mul_pj: f64,
    pub add_um2: f64,
    pub mul_um2: f64,
    /// Where the figures come from.
    pub note: String,
}

/// The 8-bit fixed-point units of the rgba8 blend units (Piranda et al. 2006 Table 1: unorm8
/// averages, Σβ in nibble sums): an adder (adds, compares, roundings and the saturating
/// nibble adds), a multiplier and a divider.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)]
pub struct Int8Units {
    pub add_pj: f64,
    pub mul_pj: f64,
    pub div_pj: f64,
    pub add_um2: f64,
    pub mul_um2: f64,
    pub div_um2: f64,
    /// Where the figures come from.
    pub note: String,
}

/// On-die SRAM: every on-chip buffer the model prices (the FIFOs today).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sram {
    /// Energy of reading or writing 64 bits \[pJ\].
    pub access_pj_per_64_bits: f64,
    /// Area per stored bit, array overhead included \[µm²\].
    pub area_um2_per_bit: f64,
    /// Static power of the arrays per MB stored (2^20 bytes), drawn for the whole frame
    /// \[mW/MB\].
    pub leakage_mw_per_mb: f64,
    /// Where the figures come from.
    pub note: String,
}

/// Which DRAM the frame buffer is: the rows of Jouppi et al. 2021, Table 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DramKind {
    /// DDR3 or DDR4 on a DIMM (Table 2's "DDR3/4" row).
    Ddr4,
    /// Stacked HBM2 beside the die (Table 2's "HBM2" row).
    Hbm2,
}

impl DramKind {
    /// Its name in technology files and reports (`ddr4`).
    pub fn name(self) -> &'static str {
        match self {
            DramKind::Ddr4 => "ddr4",
            DramKind::Hbm2 => "hbm2",
        }
    }
}

/// Off-chip DRAM: the frame buffer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dram {
    /// The memory the figure is for.
    pub kind: DramKind,
    /// Energy per byte read or written \[pJ\].
    pub pj_per_byte: f64,
    /// Where the figure comes from.
    pub note: String,
}

/// Static power of the logic (datapaths), apart from the SRAM's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogicLeakage {
    /// Leakage power per mm² of datapath area \[mW/mm²\] (0: not modelled).
    pub mw_per_mm2: f64,
    /// Where the figure comes from, or why it is 0.
    pub note: String,
}

/// A technology file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tech {
    /// Its name in reports (`45nm`).
    pub name: String,
    /// The process node \[nm\].
    pub node_nm: f64,
    /// The file's sources.
    pub source: String,
    /// Units of the f32 datapath.
    pub f32: FloatUnits,
    /// Units of the f64 datapath.
    pub f64: FloatUnits,
    /// Half-precision units: the f16 blend units.
    pub f16: FloatUnits,
    /// Fixed-point units.
    pub int32: IntUnits,
    /// 8-bit fixed-point units: the rgba8 blend units.
    pub int8: Int8Units,
    /// On-chip buffers (the FIFOs).
    pub sram: Sram,
    /// Frame-buffer memory.
    pub dram: Dram,
    /// Static power of the datapaths (the SRAM's is in `sram`).
    pub logic_leakage: LogicLeakage,
}

impl Tech {
    /// The embedded `sim/tech/45nm.json`.
    pub fn default_45nm() -> Tech {
        // Part of the binary and checked by a unit test: failing is a build defect.
        Tech::from_json(DEFAULT_TECH_JSON, "sim/tech/45nm.json (embedded)")
            .expect("the embedded technology file is valid")
    }

    /// Reads, parses and validates a technology file.
    pub fn load(path: &Path) -> Result<Tech> {
        let text = read_text_file(path)?;
        Tech::from_json(&text, &path.display().to_string())
    }

    /// Parses and validates technology JSON; `file` names it in errors.
    pub fn from_json(text: &str, file: &str) -> Result<Tech> {
        let tech: Tech = parse_strict(text, file)?;
        tech.validate(file)?;
        Ok(tech)
    }

    /// Checks every figure; the first refused is [`Error::Invalid`] naming its dotted field
    /// path (`dram.pj_per_byte`).
    pub fn validate(&self, file: &str) -> Result<()> {
        if self.name.is_empty() || self.name.chars().count() > 64 {
            return Err(Error::invalid(
                file,
                "name",
                format!("{:?}", self.name),
                "must be 1 to 64 characters long",
            ));
        }
        let positive = |field: &str, x: f64| -> Result<()> {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    file,
                    field,
                    x,
                    "must be a finite number above 0",
                ))
            }
        };
        positive("node_nm", self.node_nm)?;
        for (group, f) in [("f32", &self.f32), ("f64", &self.f64)] {
            for (name, x) in f.figures() {
                positive(&format!("{group}.{name}"), x)?;
            }
        }
        let i = &self.int32;
        for (name, x) in [
            ("add_pj", i.add_pj),
            ("mul_pj", i.mul_pj),
            ("add_um2", i.add_um2),
            ("mul_um2", i.mul_um2),
        ] {
            positive(&format!("int32.{name}"), x)?;
        }
        for (name, x) in self.f16.figures() {
            positive(&format!("f16.{name}"), x)?;
        }
        for (name, x) in self.int8.figures() {
            positive(&format!("int8.{name}"), x)?;
        }
        positive(
            "sram.access_pj_per_64_bits",
            self.sram.access_pj_per_64_bits,
        )?;
        positive("sram.area_um2_per_bit", self.sram.area_um2_per_bit)?;
        positive("dram.pj_per_byte", self.dram.pj_per_byte)?;
        for (field, leak) in [
            ("sram.leakage_mw_per_mb", self.sram.leakage_mw_per_mb),
            ("logic_leakage.mw_per_mm2", self.logic_leakage.mw_per_mm2),
        ] {
            if !(leak.is_finite() && leak >= 0.0) {
                return Err(Error::invalid(
                    file,
                    field,
                    leak,
                    "must be a finite number, 0 or above",
                ));
            }
        }
        Ok(())
    }

    /// The floating-point units of `datapath`.
    pub fn float(&self, datapath: Datapath) -> &FloatUnits {
        match datapath {
            Datapath::F32 => &self.f32,
            Datapath::F64 => &self.f64,
        }
    }

    /// Energy \[pJ\] and area \[µm²\] of one operation of class `op` in `datapath`; `Other`
    /// (a transcendental, never used by the model) is costed as a divide.
    pub fn op(&self, datapath: Datapath, op: Op) -> (f64, f64) {
        let f = self.float(datapath);
        match op {
            Op::Add => (f.add_pj, f.add_um2),
            Op::Mul => (f.mul_pj, f.mul_um2),
            Op::Div | Op::Other => (f.div_pj, f.div_um2),
            Op::Sqrt => (f.sqrt_pj, f.sqrt_um2),
            Op::Cmp => (f.cmp_pj, f.cmp_um2),
            Op::Round => (f.round_pj, f.round_um2),
            Op::IntAdd => (self.int32.add_pj, self.int32.add_um2),
            Op::IntMul => (self.int32.mul_pj, self.int32.mul_um2),
        }
    }
}

impl Tech {
    /// Energy \[pJ\] and area \[µm²\] of one operation of class `op` on the half-precision
    /// units (the integer classes on the 32-bit fixed-point units, as [`Tech::op`]).
    pub fn f16_op(&self, op: Op) -> (f64, f64) {
        let f = &self.f16;
        match op {
            Op::Add => (f.add_pj, f.add_um2),
            Op::Mul => (f.mul_pj, f.mul_um2),
            Op::Div | Op::Other => (f.div_pj, f.div_um2),
            Op::Sqrt => (f.sqrt_pj, f.sqrt_um2),
            Op::Cmp => (f.cmp_pj, f.cmp_um2),
            Op::Round => (f.round_pj, f.round_um2),
            Op::IntAdd | Op::IntMul => self.op(Datapath::F32, op),
        }
    }

    /// Energy \[pJ\] and area \[µm²\] of one operation of class `op` on the 8-bit
    /// fixed-point units: adds, compares and roundings on the adder, multiplies on the
    /// multiplier, divides (and anything else) on the divider.
    pub fn int8_op(&self, op: Op) -> (f64, f64) {
        let i = &self.int8;
        match op {
            Op::Add | Op::Cmp | Op::Round | Op::IntAdd => (i.add_pj, i.add_um2),
            Op::Mul | Op::IntMul => (i.mul_pj, i.mul_um2),
            Op::Div | Op::Sqrt | Op::Other => (i.div_pj, i.div_um2),
        }
    }
}

impl Int8Units {
    fn figures(&self) -> [(&'static str, f64); 6] {
        [
            ("add_pj", self.add_pj),
            ("mul_pj", self.mul_pj),
            ("div_pj", self.div_pj),
            ("add_um2", self.add_um2),
            ("mul_um2", self.mul_um2),
            ("div_um2", self.div_um2),
        ]
    }
}

impl FloatUnits {
    fn figures(&self) -> [(&'static str, f64); 12] {
        [
            ("add_pj", self.add_pj),
            ("mul_pj", self.mul_pj),
            ("div_pj", self.div_pj),
            ("sqrt_pj", self.sqrt_pj),
            ("cmp_pj", self.cmp_pj),
            ("round_pj", self.round_pj),
            ("add_um2", self.add_um2),
            ("mul_um2", self.mul_um2),
            ("div_um2", self.div_um2),
            ("sqrt_um2", self.sqrt_um2),
            ("cmp_um2", self.cmp_um2),
            ("round_um2", self.round_um2),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_file_is_valid_and_holds_horowitz_figures() {
        let t = Tech::default_45nm();
        assert_eq!(t.name, "45nm");
        assert_eq!(t.op(Datapath::F32, Op::Add), (0.9, 4184.0));
        assert_eq!(t.op(Datapath::F32, Op::Mul), (3.7, 7700.0));
        assert_eq!(t.op(Datapath::F32, Op::IntAdd), (0.1, 137.0));
        assert_eq!(t.sram.access_pj_per_64_bits, 10.0);
        assert_eq!(t.sram.leakage_mw_per_mb, 100.0);
        assert_eq!(t.dram.kind, DramKind::Ddr4);
        assert_eq!(t.dram.pj_per_byte, 1300.0 / 8.0);
        assert_eq!(t.logic_leakage.mw_per_mm2, 0.0);
        // The blend units' narrower figures: Horowitz's 16-bit float and 8-bit integer ones.
        assert_eq!(t.f16_op(Op::Add), (0.4, 1360.0));
        assert_eq!(t.f16_op(Op::Mul), (1.1, 1640.0));
        assert_eq!(t.int8_op(Op::Add), (0.03, 36.0));
        assert_eq!(t.int8_op(Op::IntAdd), (0.03, 36.0));
        assert_eq!(t.int8_op(Op::Mul), (0.2, 282.0));
    }

    /// The blend units' groups are required like every other: a file without one, or with
    /// a bad figure in one, is refused naming it.
    #[test]
    fn the_blend_units_groups_are_required() {
        for group in ["f16", "int8"] {
            let e = refused(|v| {
                v.as_object_mut().unwrap().remove(group);
            });
            assert!(
                matches!(&e, Error::Parse { message, .. } if message.contains(group)),
                "{e}"
            );
        }
        let e = refused(|v| {
            v["int8"].as_object_mut().unwrap().remove("div_um2");
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "int8" && message.contains("div_um2")),
            "{e}"
        );
        let e = refused(|v| v["f16"]["mul_pj"] = 0.0.into());
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "f16.mul_pj"),
            "{e}"
        );
        let e = refused(|v| v["int8"]["add_um2"] = (-36.0).into());
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "int8.add_um2"),
            "{e}"
        );
    }

    #[test]
    fn the_sram_leakage_is_required_a_number_and_not_negative() {
        let e = refused(|v| {
            v["sram"]
                .as_object_mut()
                .unwrap()
                .remove("leakage_mw_per_mb");
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "sram" && message.contains("missing field `leakage_mw_per_mb`")),
            "{e}"
        );
        let e = refused(|v| v["sram"]["leakage_mw_per_mb"] = "100".into());
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "sram.leakage_mw_per_mb" && message.contains("invalid type")),
            "{e}"
        );
        let e = refused(|v| v["sram"]["leakage_mw_per_mb"] = (-1.0).into());
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "sram.leakage_mw_per_mb"),
            "{e}"
        );
        // 0 is a figure (no leakage), as for the logic.
        let mut v: serde_json::Value = serde_json::from_str(DEFAULT_TECH_JSON).unwrap();
        v["sram"]["leakage_mw_per_mb"] = 0.0.into();
        assert!(Tech::from_json(&v.to_string(), "t.json").is_ok());
    }

    #[test]
    fn the_dram_kind_is_required_and_one_of_the_known_kinds() {
        let e = refused(|v| {
            v["dram"].as_object_mut().unwrap().remove("kind");
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "dram" && message.contains("missing field `kind`")),
            "{e}"
        );
        assert!(e.to_string().contains("`dram`"), "{e}");
        for kind in [serde_json::json!("gddr6"), "DDR4".into(), 4.into()] {
            let e = refused(|v| v["dram"]["kind"] = kind.clone());
            assert!(
                matches!(&e, Error::Parse { field, .. } if field == "dram.kind"),
                "{kind}: {e}"
            );
            assert!(e.to_string().contains("`dram.kind`"), "{e}");
        }
        let mut v: serde_json::Value = serde_json::from_str(DEFAULT_TECH_JSON).unwrap();
        v["dram"]["kind"] = "hbm2".into();
        let t = Tech::from_json(&v.to_string(), "t.json").unwrap();
        assert_eq!((t.dram.kind, t.dram.kind.name()), (DramKind::Hbm2, "hbm2"));
    }

    /// A file written before the logic's leakage was named as such: its `leakage` group is
    /// refused by name, and a file without `logic_leakage` is refused naming it.
    #[test]
    fn the_logic_leakage_group_is_required_under_its_name() {
        let e = refused(|v| {
            let o = v.as_object_mut().unwrap();
            let old = o.remove("logic_leakage").unwrap();
            o.insert("leakage".into(), old);
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "leakage" && message.contains("unknown field")),
            "{e}"
        );
        let e = refused(|v| {
            v.as_object_mut().unwrap().remove("logic_leakage");
        });
        assert!(
            e.to_string().contains("missing field `logic_leakage`"),
            "{e}"
        );
    }

    fn refused(edit: impl Fn(&mut serde_json::Value)) -> Error {
        let mut v: serde_json::Value = serde_json::from_str(DEFAULT_TECH_JSON).unwrap();
        edit(&mut v);
        Tech::from_json(&v.to_string(), "t.json").unwrap_err()
    }

    #[test]
    fn a_missing_negative_or_non_finite_figure_is_refused_naming_its_field() {
        let e = refused(|v| {
            v["f32"].as_object_mut().unwrap().remove("mul_pj");
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "f32" && message.contains("mul_pj")),
            "{e}"
        );
        let e = refused(|v| v["f64"]["sqrt_um2"] = (-1.0).into());
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "f64.sqrt_um2"),
            "{e}"
        );
        let e = refused(|v| v["dram"]["pj_per_byte"] = 0.0.into());
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "dram.pj_per_byte"),
            "{e}"
        );
        let e = refused(|v| v["logic_leakage"]["mw_per_mm2"] = (-0.5).into());
        assert!(matches!(&e, Error::Invalid { field, .. } if field == "logic_leakage.mw_per_mm2"));
        // JSON has no NaN or infinity: 1e999 overflows the parser, refused as a parse error.
        let mut text = DEFAULT_TECH_JSON.replace("\"add_pj\": 0.9", "\"add_pj\": 1e999");
        assert!(Tech::from_json(&text, "t.json").is_err());
        text = DEFAULT_TECH_JSON.replace("\"node_nm\": 45", "\"node_nm\": 45, \"extra\": 1");
        assert!(matches!(
            Tech::from_json(&text, "t.json"),
            Err(Error::Parse { .. })
        ));
    }
}
