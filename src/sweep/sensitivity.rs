//! What flips the answer (DESIGN.md §7, "Sensitivity"): a spec's `sensitivity` asks, one
//! parameter at a time, how the lembo path's speed-up at a fixed target error moves when
//! the parameter is scaled down and up (or set to a stated low and high value), every other
//! setting at the grid's.
//!
//! ```json
//! "sensitivity": {
//!   "target": {"psnr_db": 45},
//!   "factors": [0.5, 2],
//!   "params": ["arch.framebuffer.bytes_per_cycle",
//!              {"param": "arch.interval_manager.count", "path": "lembo"},
//!              {"param": "arch.rop.fragments_per_cycle", "low": 0.5, "high": 2}]
//! }
//! ```
//!
//! Each parameter adds two *variants* of every grid point of the paths it names (both by
//! default): the point with the parameter scaled by the low factor, and by the high one
//! (its value on the point's architecture times the factor, worked out when the plan loads
//! the architecture; a whole-number field must stay whole), or set to `low` and `high`.
//! A variant point carries the parameter `sensitivity` (`arch.rop.count x0.5`,
//! `arch.rop.fragments_per_cycle = 0.5`), which keeps its runs apart from the grid's: the
//! rest of the answer reads the grid's runs alone. At the target, the speed-up of a
//! variant uses the variant's runs of each path it has runs of, and the grid's runs of the
//! other path.

use super::curves::{Metric, METRICS};
use super::names::{ARCH, TECH};
use crate::error::{Error, Result};
use crate::job::PrimitivePath;
use serde::Deserialize;
use serde_json::Value;

/// The parameter that marks a variant point.
pub use super::names::SENSITIVITY as PARAM;

/// The default factors: halved and doubled.
pub const DEFAULT_FACTORS: [f64; 2] = [0.5, 2.0];

/// The largest factor accepted: a parameter scaled past it is another design, not a
/// sensitivity.
pub const MAX_FACTOR: f64 = 1e3;

/// `sensitivity` as the spec file writes it.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SensitivityFile {
    target: serde_json::Map<String, Value>,
    factors: Option<Vec<Value>>,
    params: Vec<Value>,
}

/// How one parameter is varied.
#[derive(Clone, Debug, PartialEq)]
pub enum Vary {
    /// Scaled by a low and a high factor.
    Factors(f64, f64),
    /// Set to a low and a high value.
    Values(Value, Value),
}

/// One parameter of the study.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Its sweep name (`arch.framebuffer.bytes_per_cycle`).
    pub name: String,
    /// The path whose points it varies; None for both.
    pub path: Option<PrimitivePath>,
    /// How.
    pub vary: Vary,
    /// Where in the spec (`sensitivity.params[2]`), for errors.
    pub field: String,
}

impl Param {
    /// The `sensitivity` value of its low and its high variant.
    pub fn tags(&self) -> [String; 2] {
        match &self.vary {
            Vary::Factors(lo, hi) => [lo, hi].map(|f| format!("{} x{f}", self.name)),
            Vary::Values(lo, hi) => [lo, hi].map(|v| format!("{} = {v}", self.name)),
        }
    }
    /// Its low and high as the tornado chart writes them (`x0.5`, `= 32`).
    pub fn ends(&self) -> [String; 2] {
        match &self.vary {
            Vary::Factors(lo, hi) => [lo, hi].map(|f| format!("x{f}")),
            Vary::Values(lo, hi) => [lo, hi].map(|v| format!("= {v}")),
        }
    }
    /// Whether it varies the points of `path`.
    pub fn applies(&self, path: PrimitivePath) -> bool {
        self.path.is_none_or(|p| p == path)
    }
}

/// A parsed `sensitivity`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensitivity {
    /// The metric and level at which the speed-up is read.
    pub target: (Metric, f64),
    /// The parameters, in the spec's order.
    pub params: Vec<Param>,
}

impl Sensitivity {
    /// Checks the file's fields; errors name `sensitivity.<field>` of `file`.
    pub(super) fn from_file(file: &str, f: &SensitivityFile) -> Result<Sensitivity> {
        let target = match f.target.iter().collect::<Vec<_>>()[..] {
            [(name, v)] => {
                let metric = METRICS
                    .iter()
                    .copied()
                    .find(|m| m.name() == name)
                    .ok_or_else(|| {
                        Error::invalid(
                            file,
                            format!("sensitivity.target.{name}"),
                            v,
                            format!(
                                "the target's metric must be one of {}",
                                METRICS.map(|m| m.name()).join(", ")
                            ),
                        )
                    })?;
                let field = format!("sensitivity.target.{name}");
                (metric, metric.parse_target(file, &field, v)?)
            }
            _ => {
                return Err(Error::invalid(
                    file,
                    "sensitivity.target",
                    Value::Object(f.target.clone()),
                    "must name one metric and its level, e.g. {\"psnr_db\": 45}",
                ))
            }
        };
        let factors = match &f.factors {
            None => DEFAULT_FACTORS,
            Some(list) => {
                let [lo, hi] = &list[..] else {
                    return Err(Error::invalid(
                        file,
                        "sensitivity.factors",
                        Value::Array(list.clone()),
                        "must be two factors, the low and the high",
                    ));
                };
                let mut out = [0.0; 2];
                for (i, v) in [lo, hi].into_iter().enumerate() {
                    out[i] = check_factor(file, &format!("sensitivity.factors[{i}]"), v)?;
                }
                out
            }
        };
        if f.params.is_empty() {
            return Err(super::names::empty_list(file, "sensitivity.params"));
        }
        let mut params: Vec<Param> = Vec::new();
        for (i, entry) in f.params.iter().enumerate() {
            let field = format!("sensitivity.params[{i}]");
            let param = param(file, &field, entry, factors)?;
            if params
                .iter()
                .any(|p| p.name == param.name && p.path == param.path)
            {
                return Err(Error::invalid(
                    file,
                    &field,
                    entry,
                    "names a parameter already in the list",
                ));
            }
            params.push(param);
        }
        Ok(Sensitivity { target, params })
    }

    /// The spec's `sensitivity` read back from its text (checked when the spec was parsed).
    pub(super) fn of_spec_text(spec_text: &[u8]) -> Option<Sensitivity> {
        let v: Value = serde_json::from_slice(spec_text).ok()?;
        let f: SensitivityFile = serde_json::from_value(v.get("sensitivity")?.clone()).ok()?;
        Sensitivity::from_file("spec", &f).ok()
    }
}

fn check_factor(file: &str, field: &str, v: &Value) -> Result<f64> {
    let x = super::names::number(file, field, v)?;
    if !(x.is_finite() && x > 0.0 && x <= MAX_FACTOR) {
        return Err(Error::invalid(
            file,
            field,
            v,
            format!("a factor must be above 0 and at most {MAX_FACTOR}"),
        ));
    }
    Ok(x)
}

fn param(file: &str, field: &str, entry: &Value, factors: [f64; 2]) -> Result<Param> {
    let (name, path, vary) = match entry {
        Value::String(name) => (name.clone(), None, Vary::Factors(factors[0], factors[1])),
        Value::Object(map) => {
            for key in map.keys() {
                if !["param", "path", "low", "high", "factors"].contains(&key.as_str()) {
                    return Err(Error::Parse {
                        file: file.into(),
                        field: format!("{field}.{key}"),
                        message: format!(
                            "unknown field `{key}`; expected param, path, low and high, or factors"
                        ),
                    });
                }
            }
            let name = map
                .get("param")
                .and_then(Value::as_str)
                .ok_or_else(|| Error::Parse {
                    file: file.into(),
                    field: format!("{field}.param"),
                    message: "expected the parameter's name".into(),
                })?
                .to_string();
            let path = match map.get("path") {
                None => None,
                Some(Value::String(s)) if s == "lembo" => Some(PrimitivePath::Lembo),
                Some(Value::String(s)) if s == "triangle" => Some(PrimitivePath::Triangle),
                Some(other) => {
                    return Err(Error::invalid(
                        file,
                        format!("{field}.path"),
                        other,
                        "must be \"lembo\" or \"triangle\"",
                    ))
                }
            };
            let vary = match (map.get("low"), map.get("high"), map.get("factors")) {
                (None, None, None) => Vary::Factors(factors[0], factors[1]),
                (None, None, Some(Value::Array(list))) if list.len() == 2 => Vary::Factors(
                    check_factor(file, &format!("{field}.factors[0]"), &list[0])?,
                    check_factor(file, &format!("{field}.factors[1]"), &list[1])?,
                ),
                (Some(lo), Some(hi), None) => Vary::Values(lo.clone(), hi.clone()),
                _ => return Err(Error::invalid(
                    file,
                    field,
                    entry,
                    "give both `low` and `high`, or two `factors`, or neither (the spec's factors)",
                )),
            };
            (name, path, vary)
        }
        other => {
            return Err(Error::Parse {
                file: file.into(),
                field: field.into(),
                message: format!("expected a parameter's name or an object, found {other}"),
            })
        }
    };
    if !name.starts_with(ARCH) && !name.starts_with(TECH) {
        return Err(Error::invalid(
            file,
            field,
            &name,
            "a sensitivity parameter is an architecture field (`arch.<field>`) or a technology figure (`tech.<field>`)",
        ));
    }
    Ok(Param {
        name,
        path,
        vary,
        field: field.to_string(),
    })
}

/// The value of `base` scaled by `factor`: a whole number stays a whole number where the
/// product is whole, else it becomes a fraction, which the architecture accepts only in a
/// field that takes fractions (checked when the architecture is read back). The error
/// says why, for the caller to name the field.
pub fn scaled(base: &Value, factor: f64) -> std::result::Result<Value, String> {
    if let Some(n) = base.as_u64() {
        let x = n as f64 * factor;
        if x.fract() == 0.0 && x >= 0.0 && x <= u64::MAX as f64 {
            return Ok(Value::from(x as u64));
        }
        return Ok(Value::from(x));
    }
    match base.as_f64() {
        Some(x) => Ok(Value::from(x * factor)),
        None => Err(format!("is not a number ({base}), so it cannot be scaled")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Sensitivity> {
        let f: SensitivityFile = serde_json::from_str(text).unwrap();
        Sensitivity::from_file("s.json", &f)
    }

    fn field(e: Error) -> String {
        match e {
            Error::Invalid { field, .. } | Error::Parse { field, .. } => field,
            other => other.to_string(),
        }
    }

    #[test]
    fn a_study_names_its_target_factors_and_parameters() {
        let s = parse(
            r#"{"target": {"psnr_db": 45},
                "params": ["arch.framebuffer.bytes_per_cycle",
                           {"param": "arch.interval_manager.count", "path": "lembo"},
                           {"param": "arch.rop.count", "low": 2, "high": 8}]}"#,
        )
        .unwrap();
        assert_eq!(s.target, (Metric::Psnr, 45.0));
        assert_eq!(
            s.params[0].tags(),
            [
                "arch.framebuffer.bytes_per_cycle x0.5",
                "arch.framebuffer.bytes_per_cycle x2"
            ]
        );
        assert!(s.params[1].applies(PrimitivePath::Lembo));
        assert!(!s.params[1].applies(PrimitivePath::Triangle));
        assert_eq!(s.params[2].ends(), ["= 2", "= 8"]);
    }

    #[test]
    fn bad_studies_are_refused_naming_the_field() {
        for (text, want) in [
            (
                r#"{"target": {"psnr_db": 45}, "factors": [0, 2], "params": ["arch.rop.count"]}"#,
                "sensitivity.factors[0]",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "factors": [0.5, -2], "params": ["arch.rop.count"]}"#,
                "sensitivity.factors[1]",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "factors": [0.5], "params": ["arch.rop.count"]}"#,
                "sensitivity.factors",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "params": []}"#,
                "sensitivity.params",
            ),
            (
                r#"{"target": {"flip_mean": 3}, "params": ["arch.rop.count"]}"#,
                "sensitivity.target.flip_mean",
            ),
            (
                r#"{"target": {"colour": 3}, "params": ["arch.rop.count"]}"#,
                "sensitivity.target.colour",
            ),
            (
                r#"{"target": {}, "params": ["arch.rop.count"]}"#,
                "sensitivity.target",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "params": ["k"]}"#,
                "sensitivity.params[0]",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "params": [{"param": "arch.rop.count", "low": 2}]}"#,
                "sensitivity.params[0]",
            ),
            (
                r#"{"target": {"psnr_db": 45}, "params": ["arch.rop.count", "arch.rop.count"]}"#,
                "sensitivity.params[1]",
            ),
        ] {
            assert_eq!(field(parse(text).unwrap_err()), want, "{text}");
        }
    }

    #[test]
    fn whole_numbers_stay_whole_where_the_product_is() {
        assert_eq!(scaled(&Value::from(4u64), 0.5), Ok(Value::from(2u64)));
        assert_eq!(scaled(&Value::from(1u64), 0.5), Ok(Value::from(0.5)));
        assert_eq!(scaled(&Value::from(64.0), 2.0), Ok(Value::from(128.0)));
        assert!(scaled(&Value::from("memory"), 2.0).is_err());
    }
}
