//! The technology file (`sim/tech/*.json`, `--tech FILE`): energy per operation \[pJ\] and
//! area per functional unit \[µm²\] for the f32, f64 and fixed-point datapaths (and the
//! discoid blend units' f16 and 8-bit fixed-point units); on-chip SRAM per bit, per access
//! and its leakage per MB; the DRAM's kind and energy per byte; the memory kinds the file
//! knows, each priced per bit read or written and per row activation ([`MemoryKind`]);
//! logic leakage per mm².
//! Every figure is required (no defaults: a cost nobody wrote down is not a cost), finite
//! and above 0 (the two leakages: 0 or above); each group carries a `note`
//! citing its source, and the file a `source` (DESIGN.md §12).

use super::memory_kind::MemoryKind;
use crate::datapath::{Datapath, Op};
use crate::error::{read_text_file, Error, Result};
use crate::json::parse_strict;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
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
    /// Frame-buffer memory, priced per byte (`dram.kind` names its row of `memory_kinds`).
    pub dram: Dram,
    /// Every memory kind the file knows, by name (`gddr6`), priced per bit and per row
    /// activation.
    pub memory_kinds: BTreeMap<String, MemoryKind>,
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
        self.validate_memory_kinds(file)?;
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
    /// The memory kind `name`, for the value of `field` in `file` (`dram.kind` here, an
    /// architecture's field for the caller): [`Error::Invalid`] naming `field` and listing
    /// the kinds this file has when it has no such kind.
    pub fn memory_kind(&self, name: &str, file: &str, field: &str) -> Result<&MemoryKind> {
        self.memory_kinds.get(name).ok_or_else(|| {
            let known: Vec<&str> = self.memory_kinds.keys().map(String::as_str).collect();
            Error::invalid(
                file,
                field,
                format!("{name:?}"),
                format!(
                    "technology file {:?} has no such memory kind; it has: {}",
                    self.name,
                    known.join(", ")
                ),
            )
        })
    }

    /// At least one kind; each name lowercase letters, digits and `_`; each figure finite
    /// and above 0, refused naming `memory_kinds.<name>.<figure>`; `dram.kind` one of them.
    fn validate_memory_kinds(&self, file: &str) -> Result<()> {
        if self.memory_kinds.is_empty() {
            return Err(Error::invalid(
                file,
                "memory_kinds",
                "{}",
                "must list at least one memory kind",
            ));
        }
        for (name, kind) in &self.memory_kinds {
            let plain = |c: char| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_';
            if name.is_empty() || !name.chars().all(plain) {
                return Err(Error::invalid(
                    file,
                    "memory_kinds",
                    format!("{name:?}"),
                    "a kind's name must be lowercase letters, digits and '_' (gddr6)",
                ));
            }
            for (figure, x) in kind.figures() {
                if !(x.is_finite() && x > 0.0) {
                    return Err(Error::invalid(
                        file,
                        format!("memory_kinds.{name}.{figure}"),
                        x,
                        "must be a finite number above 0",
                    ));
                }
            }
        }
        self.memory_kind(self.dram.kind.name(), file, "dram.kind")
            .map(|_| ())
    }

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

    /// Every shipped technology file, parsed and validated, by file name.
    fn shipped() -> Vec<(String, Tech)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/tech");
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        files
            .iter()
            .map(|p| (p.display().to_string(), Tech::load(p).unwrap()))
            .collect()
    }

    /// Every shipped file prices DDR4, GDDR6, LPDDR5 and HBM2E (and HBM2, 7nm.json's
    /// `dram.kind`) alike: DRAM is off-chip, so the logic node does not change it.
    #[test]
    fn every_shipped_file_lists_the_memory_kinds_alike() {
        let files = shipped();
        assert!(
            files.len() >= 2,
            "{:?}",
            files.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        let first = &files[0].1.memory_kinds;
        for (file, t) in &files {
            for kind in ["ddr4", "gddr6", "lpddr5", "hbm2e", "hbm2"] {
                assert!(t.memory_kind(kind, file, "test").is_ok(), "{file}: {kind}");
            }
            assert_eq!(&t.memory_kinds, first, "{file}");
        }
        // The anchors: GDDR6 about 7.5 pJ/bit, HBM2E about 6.
        let k = &files[0].1.memory_kinds;
        assert_eq!(k["gddr6"].pj_per_bit_read, 7.5);
        assert_eq!(k["hbm2e"].pj_per_bit_read, 6.0);
    }

    /// The per-byte figure `dram` keeps for today's port model is the per-bit figure of the
    /// kind `dram.kind` names, so the two prices agree on a frame without row activations.
    #[test]
    fn the_per_byte_figure_is_its_kinds_per_bit_figure() {
        for (file, t) in shipped() {
            let k = t
                .memory_kind(t.dram.kind.name(), &file, "dram.kind")
                .unwrap();
            assert_eq!(k.pj_per_bit_read * 8.0, t.dram.pj_per_byte, "{file}");
            assert_eq!(k.pj_per_bit_written * 8.0, t.dram.pj_per_byte, "{file}");
        }
    }

    /// The activation energies are the controller presets' (DRAMsim3's IDD formula,
    /// `DramEnergy::from_idd`), and HBM2's is that formula by hand on DRAMsim3's
    /// HBM2_8Gb_x128.ini: 1.2 V x (65 x 48 - 55 x 34 - 40 x 14) mA ns = 828 pJ.
    #[test]
    fn activation_energies_are_the_controller_presets() {
        use crate::memory::dram::{ddr4_2400_x8, gddr6_16g_x16, lpddr5_6400_x16};
        let t = Tech::default_45nm();
        for (kind, preset) in [
            ("ddr4", ddr4_2400_x8()),
            ("gddr6", gddr6_16g_x16()),
            ("lpddr5", lpddr5_6400_x16()),
        ] {
            let file = t.memory_kinds[kind].pj_per_activation;
            let derived = preset.energy.activation_pj;
            assert!((file - derived).abs() < 0.05, "{kind}: {file} vs {derived}");
        }
        let hbm2 = 1.2 * (65.0 * 48.0 - 55.0 * 34.0 - 40.0 * 14.0);
        assert_eq!(t.memory_kinds["hbm2"].pj_per_activation, hbm2);
    }

    #[test]
    fn an_unknown_memory_kind_is_refused_naming_the_field_and_the_known_kinds() {
        let t = Tech::default_45nm();
        let e = t
            .memory_kind("gddr7", "arch.json", "memory.kind")
            .unwrap_err();
        assert!(
            matches!(&e, Error::Invalid { file, field, value, reason }
            if file == "arch.json" && field == "memory.kind" && value == "\"gddr7\""
                && reason.ends_with("it has: ddr4, gddr6, hbm2, hbm2e, lpddr5")),
            "{e}"
        );
        assert_eq!(e.exit_code(), 2);
        // dram.kind names a row of the table: a file without that row is refused by it.
        let e = refused(|v| {
            v["memory_kinds"].as_object_mut().unwrap().remove("ddr4");
        });
        assert!(
            matches!(&e, Error::Invalid { field, reason, .. }
            if field == "dram.kind" && reason.ends_with("it has: gddr6, hbm2, hbm2e, lpddr5")),
            "{e}"
        );
    }

    #[test]
    fn a_zero_negative_or_missing_memory_figure_is_refused_naming_it() {
        for (figure, x) in [
            ("pj_per_bit_read", 0.0),
            ("pj_per_bit_written", -7.5),
            ("pj_per_activation", 0.0),
        ] {
            let e = refused(|v| v["memory_kinds"]["gddr6"][figure] = x.into());
            let want = format!("memory_kinds.gddr6.{figure}");
            assert!(
                matches!(&e, Error::Invalid { field, .. } if *field == want),
                "{e}"
            );
        }
        let e = refused(|v| {
            v["memory_kinds"]["hbm2e"]
                .as_object_mut()
                .unwrap()
                .remove("pj_per_activation");
        });
        assert!(
            matches!(&e, Error::Parse { field, message, .. }
            if field == "memory_kinds.hbm2e" && message.contains("pj_per_activation")),
            "{e}"
        );
        let e = refused(|v| {
            v.as_object_mut().unwrap().remove("memory_kinds");
        });
        assert!(
            e.to_string().contains("missing field `memory_kinds`"),
            "{e}"
        );
        let e = refused(|v| v["memory_kinds"] = serde_json::json!({}));
        assert!(
            matches!(&e, Error::Invalid { field, .. } if field == "memory_kinds"),
            "{e}"
        );
        let e = refused(|v| {
            let k = v["memory_kinds"]["gddr6"].clone();
            v["memory_kinds"]["GDDR 6"] = k;
        });
        assert!(
            matches!(&e, Error::Invalid { field, value, .. }
            if field == "memory_kinds" && value == "\"GDDR 6\""),
            "{e}"
        );
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
