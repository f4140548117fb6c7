//! The architecture configuration of the timed pipeline (DESIGN.md §3): how many instances of
//! each unit of Martinelli 2006 Figure 5 there are, what each costs per item, and the depth and
//! latency of the FIFOs between them. Files live in `sim/arch/*.json`; `sim/arch/README.md`
//! states each unit's cost model in words and holds the table of every field, its default
//! and what it accepts, generated from the declarations here ([`fields_table`]). The units
//! and the links between them are the unit graph's ([`crate::graph`]); each section here
//! says which kind it configures.
//!
//! Each section is declared once (the `section!` macro, in `sections.rs`): its fields'
//! docs, types, defaults and rules, from which its struct, `Default`, checks and table rows
//! are written.
//!
//! Every unit has a `latency_cycles` (an output is ready that long after the operation that
//! produces it issues) and one or more `cycles_per_*` initiation intervals (how long the
//! unit is busy per item before it can take the next). Every stage boundary has one
//! [`LinkConfig`](crate::graph::LinkConfig), shared by every link of the crossbar between the two stages.
//!
//! A file is parsed with `#[serde(default, deny_unknown_fields)]`, so a file may state only
//! what it changes; unknown fields are refused with [`Error::Parse`] naming their path
//! (`segmenter.cnt`), and values outside what the simulator accepts with [`Error::Invalid`]
//! naming the dotted field path (`links.rasterizer_to_rop.fifo_depth`). A validated
//! configuration is not re-checked downstream.
//!
//! Not modelled here: clock domains (one clock for every unit), per-link overrides within a
//! crossbar, and DRAM timing beyond a bandwidth-limited port.

use crate::error::{read_text_file, Error, Result};
use crate::graph::{self, PrimitivePath, UnitInstance, UnitKind};

mod declare;
mod links;
mod memory;
mod ratio;
mod rules;
mod sections;
mod table;
use crate::json::parse_strict;
pub use declare::Row;
pub use links::LinksConfig;
pub use memory::{DramPreset, MemoryConfig, MemoryModel, BYTES_PER_PIXEL};
pub use ratio::Ratio;
pub use rules::{
    MAX_ACCESS_CYCLES, MAX_BATCH, MAX_BYTES, MAX_CLOCK_MHZ, MAX_CYCLES, MAX_FIFO_DEPTH,
    MAX_FRAGMENTS_PER_CYCLE, MAX_NAME_CHARS, MAX_TILE_PX, MAX_UNIT_COUNT, MAX_VERTEX_CACHE,
};
// Every section's type, so that a new section needs no line here.
pub use sections::*;
use std::path::Path;

/// The embedded `sim/arch/baseline.json`.
const BASELINE_JSON: &str = include_str!("../../sim/arch/baseline.json");

impl ArchConfig {
    /// Reads, parses and validates an architecture file. A file without a `"name"` is named
    /// by its file name (`my_arch` for `my_arch.json`), not the default `baseline`: it is a
    /// different architecture, and every output labels it.
    pub fn load(path: &Path) -> Result<ArchConfig> {
        let text = read_text_file(path)?;
        let mut config = ArchConfig::from_json(&text, &path.display().to_string())?;
        let named =
            serde_json::from_str::<serde_json::Value>(&text).is_ok_and(|v| v.get("name").is_some());
        if !named {
            if let Some(stem) = path.file_stem() {
                config.name = stem.to_string_lossy().into_owned();
            }
        }
        Ok(config)
    }

    /// Parses and validates an architecture from JSON text; `file` is the name used in
    /// error messages. Fields the text leaves out keep their defaults.
    pub fn from_json(text: &str, file: &str) -> Result<ArchConfig> {
        let config: ArchConfig = parse_strict(text, file)?;
        config.validate(file)?;
        config.check_memory(file)?;
        Ok(config)
    }

    /// This architecture with the fields `sets` (dotted path, value) set, validated as an
    /// architecture file is; an error names `flag` and the field (`--set`).
    pub fn with_fields(
        &self,
        sets: &[(String, serde_json::Value)],
        flag: &str,
    ) -> Result<ArchConfig> {
        if sets.is_empty() {
            return Ok(self.clone());
        }
        let mut value = serde_json::to_value(self).expect("the architecture serialises");
        for (path, v) in sets {
            crate::json::set_field(&mut value, path, v.clone(), "architecture").map_err(
                |message| Error::Parse {
                    file: crate::error::COMMAND_LINE.into(),
                    field: format!("{flag} {path}"),
                    message,
                },
            )?;
        }
        let config: ArchConfig =
            serde_path_to_error::deserialize(value).map_err(|e| Error::Parse {
                file: crate::error::COMMAND_LINE.into(),
                field: format!("{flag} {}", e.path()),
                message: e.into_inner().to_string(),
            })?;
        let file = format!("{} ({flag})", crate::error::COMMAND_LINE);
        config.validate(&file)?;
        config.check_memory(&file)?;
        Ok(config)
    }

    /// The memory fields' checks across fields and sections ([`MemoryConfig::check`]); with
    /// the DRAM model a ROP interleave tile must hold whole 8x8 memory tiles, so that no two
    /// ROPs' caches share a sector.
    pub fn check_memory(&self, file: &str) -> Result<()> {
        self.memory.check(file)?;
        let tile = crate::memory::tiles::TILE_PX;
        if self.memory.model == MemoryModel::Dram && !self.rop.tile_px.is_multiple_of(tile) {
            return Err(Error::invalid(
                file,
                "rop.tile_px",
                self.rop.tile_px,
                format!("must be a multiple of {tile} with memory.model \"dram\" (a ROP owns whole memory tiles)"),
            ));
        }
        Ok(())
    }

    /// The embedded `sim/arch/baseline.json`, equal to [`ArchConfig::default`].
    pub fn baseline() -> ArchConfig {
        // The text is part of the binary and checked by a unit test, so failing here is a
        // build defect, not bad input.
        ArchConfig::from_json(BASELINE_JSON, "sim/arch/baseline.json (embedded)")
            .expect("the embedded baseline architecture is valid")
    }

    /// The units `path` instantiates on this architecture, in dataflow order, with their
    /// latencies \[cycles\].
    pub fn instances(&self, path: PrimitivePath) -> Vec<(UnitInstance, u64)> {
        self.instances_with(path, false)
    }

    /// [`ArchConfig::instances`], with the units a scene with discoids adds when `discoids`
    /// ([`graph::DISCOID_KINDS`]).
    pub fn instances_with(&self, path: PrimitivePath, discoids: bool) -> Vec<(UnitInstance, u64)> {
        graph::instances(
            &graph::kinds(path, self.tessellation.source, discoids),
            |k| self.unit(k).0,
        )
        .into_iter()
        .map(|u| {
            let latency = self.unit(u.kind).1;
            (u, latency)
        })
        .collect()
    }

    /// Unit instances of the lembo path (saturating, so that an unvalidated configuration
    /// cannot overflow).
    pub fn units(&self) -> u32 {
        graph::instance_count(PrimitivePath::Lembo, self.tessellation.source, |k| {
            self.unit(k).0
        })
    }

    /// The FIFO entries of every link `units` instantiate: each boundary's crossbar has one
    /// link per (producer, consumer) pair, each `fifo_depth` entries deep; a boundary
    /// between kinds absent from `units` has no links. Item sizes are not modelled, so this
    /// counts entries, not bytes \[entries\].
    pub fn fifo_entries(&self, units: &[UnitInstance]) -> u64 {
        let count = |kind: UnitKind| units.iter().filter(|u| u.kind == kind).count() as u64;
        let kinds: Vec<UnitKind> = units.iter().map(|u| u.kind).collect();
        self.links
            .boundaries()
            .filter(|(b, _)| {
                b.wired_in(
                    &kinds,
                    self.tessellation.source,
                    self.memory.model == MemoryModel::Dram,
                )
            })
            .map(|(b, link)| count(b.from) * count(b.to) * link.fifo_depth as u64)
            .sum()
    }
}

/// Every field of an architecture file with its default and what it accepts, as the
/// Markdown table `sim/arch/README.md` holds (a unit test keeps the README's copy equal).
pub fn fields_table() -> String {
    table::markdown(&ArchConfig::rows())
}

#[cfg(test)]
mod tests;
