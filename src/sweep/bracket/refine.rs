//! The spec's `refine` settings (DESIGN.md §7, "Bracketing"): how far refinement rounds
//! take each series' knob, as the spec file writes them ([`RefineFile`]) and checked
//! ([`Refine`]).

use crate::error::{Error, Result};
use crate::tolerance::check_k;
use serde::Deserialize;
use serde_json::Value;

/// Default `refine.margin_db`: a refinement that gains less PSNR than this ends its series.
pub const DEFAULT_MARGIN_DB: f64 = 0.5;
/// Default `refine.k_floor` \[px\].
pub const DEFAULT_K_FLOOR: f64 = 0.01;
/// Default `refine.tess_cap`.
pub const DEFAULT_TESS_CAP: u32 = 64;
/// The widest margin accepted \[dB\].
pub const MAX_MARGIN_DB: f64 = 60.0;
/// Default `refine.k_ceiling` \[px\]: the coarsest k refinement runs.
pub const DEFAULT_K_CEILING: f64 = 16.0;
/// Default `refine.cost_margin`: a coarser level that saves less than this fraction of the
/// fewest cycles and of the least energy of the level finer than it ends the coarse side.
pub const DEFAULT_COST_MARGIN: f64 = 0.02;

/// `refine` as the spec file writes it.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RefineFile {
    margin_db: Option<f64>,
    k_floor: Option<f64>,
    tess_cap: Option<u32>,
    cycle_cap: Option<u64>,
    k_ceiling: Option<f64>,
    cost_margin: Option<f64>,
}

/// How far refinement goes (`refine` in a spec).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refine {
    /// A series stops when its finest level gained less than this over its best coarser
    /// one \[dB of PSNR\].
    pub margin_db: f64,
    /// The finest k refinement runs \[px\].
    pub k_floor: f64,
    /// The largest n refinement runs.
    pub tess_cap: u32,
    /// A series stops once a run of it took more cycles than this; None for no cap.
    pub cycle_cap: Option<u64>,
    /// The coarsest k refinement runs \[px\].
    pub k_ceiling: f64,
    /// A coarser level saving less than this fraction of the cost of the level finer than
    /// it ends a series' coarse side.
    pub cost_margin: f64,
}

impl Default for Refine {
    fn default() -> Refine {
        Refine {
            margin_db: DEFAULT_MARGIN_DB,
            k_floor: DEFAULT_K_FLOOR,
            tess_cap: DEFAULT_TESS_CAP,
            cycle_cap: None,
            k_ceiling: DEFAULT_K_CEILING,
            cost_margin: DEFAULT_COST_MARGIN,
        }
    }
}

impl Refine {
    /// Checks the file's values; errors name `refine.<field>` of `file`.
    pub(crate) fn from_file(file: &str, f: &RefineFile) -> Result<Refine> {
        let d = Refine::default();
        let margin_db = f.margin_db.unwrap_or(d.margin_db);
        if !(margin_db.is_finite() && (0.0..=MAX_MARGIN_DB).contains(&margin_db)) {
            return Err(Error::invalid(
                file,
                "refine.margin_db",
                margin_db,
                format!("must be a PSNR gain in [0, {MAX_MARGIN_DB}] dB"),
            ));
        }
        let k_floor = f.k_floor.unwrap_or(d.k_floor);
        check_k(k_floor).map_err(|why| Error::invalid(file, "refine.k_floor", k_floor, why))?;
        let tess_cap = f.tess_cap.unwrap_or(d.tess_cap);
        crate::job::check_tess_range(tess_cap)
            .map_err(|e| crate::sweep::names::reword(e, file, "refine.tess_cap"))?;
        if f.cycle_cap == Some(0) {
            return Err(Error::invalid(
                file,
                "refine.cycle_cap",
                0,
                "must be a number of cycles above 0 (leave it out for no cap)",
            ));
        }
        let k_ceiling = f.k_ceiling.unwrap_or(d.k_ceiling.max(k_floor));
        check_k(k_ceiling)
            .map_err(|why| Error::invalid(file, "refine.k_ceiling", k_ceiling, why))?;
        if k_ceiling < k_floor {
            return Err(Error::invalid(
                file,
                "refine.k_ceiling",
                k_ceiling,
                format!("must be at least refine.k_floor ({k_floor})"),
            ));
        }
        let cost_margin = f.cost_margin.unwrap_or(d.cost_margin);
        if !(cost_margin.is_finite() && (0.0..1.0).contains(&cost_margin)) {
            return Err(Error::invalid(
                file,
                "refine.cost_margin",
                cost_margin,
                "must be a fraction of a cost in [0, 1)",
            ));
        }
        Ok(Refine {
            margin_db,
            k_floor,
            tess_cap,
            cycle_cap: f.cycle_cap,
            k_ceiling,
            cost_margin,
        })
    }

    /// The spec's `refine` read back from its text (checked when the spec was parsed);
    /// None when it has none.
    pub(crate) fn of_spec_text(spec_text: &[u8]) -> Option<Refine> {
        let v: Value = serde_json::from_slice(spec_text).ok()?;
        let f: RefineFile = serde_json::from_value(v.get("refine")?.clone()).ok()?;
        Refine::from_file("spec", &f).ok()
    }
}
