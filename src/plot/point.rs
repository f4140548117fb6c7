//! What the plots read from a sweep's records: a record as a [`Point`], the value a run used
//! for a parameter its point left at the default (also the value `results.csv` writes), the
//! parameters that vary, and the Pareto front.

use super::chart::{fmt_num, fmt_value};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};

/// Indices of the points that no other point dominates, minimising both coordinates (q
/// dominates p when q is no larger in both and smaller in one). Equal points do not dominate
/// each other, so duplicates on the front are all returned. The indices come in ascending x
/// (ties by ascending y, then index), the order a step line through the front takes. Points
/// with a NaN coordinate are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan())
        .collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0)
            .then(pa.1.total_cmp(&pb.1))
            .then(a.cmp(&b))
    });
    let mut front: Vec<usize> = Vec::new();
    for i in order {
        // Every earlier point has x no larger; it dominates this one unless this one has a
        // smaller y than all of them, or it is the last front point again.
        let keep = match front.last() {
            None => true,
            Some(&last) => points[i].1 < points[last].1 || points[i] == points[last],
        };
        if keep {
            front.push(i);
        }
    }
    front
}

/// The scene a sweep record's figures belong to: its scene's name, and where its point
/// sets a viewport (a sweep over viewports), the viewport too (`bunny 1024x768`), so that
/// the plots and the answer keep each viewport's runs apart.
pub fn scene_label(record: &Value) -> Option<String> {
    let name = record
        .get("scene")
        .and_then(Value::as_str)
        .or_else(|| record.pointer("/report/scene/name").and_then(Value::as_str))?;
    Some(
        match record.pointer("/params/viewport").and_then(Value::as_str) {
            Some(v) => format!("{name} {v}"),
            None => name.to_string(),
        },
    )
}

/// One sweep point, as far as the plots use it.
pub(super) struct Point {
    pub(super) index: u64,
    pub(super) scene: String,
    /// `lembo` or `triangle` (`report.settings.path`).
    pub(super) path: String,
    /// Tolerance k \[px\]; lembo path only.
    pub(super) k_px: Option<f64>,
    /// Tessellation level n; triangle path only.
    pub(super) tess: Option<u64>,
    /// The sweep's parameters of this point; a parameter another point has and this one
    /// lacks counts as null.
    pub(super) params: BTreeMap<String, Value>,
    /// Frame time \[cycles\]; `None` in functional mode.
    pub(super) cycles: Option<u64>,
    pub(super) units: Vec<UnitTime>,
    /// RMS colour error 255·10^(−PSNR/20) [0-255]; `None` without a reference.
    pub(super) rms_error: Option<f64>,
    /// Mean FLIP [0, 1] (report.json `accuracy.flip_mean`); `None` without a reference, or
    /// for a report from before FLIP was measured.
    pub(super) flip_mean: Option<f64>,
    /// The run's report, for the value of a parameter its point left at the default.
    pub(super) report: Value,
    /// The frame's energy \[pJ\]; `None` without a cost section.
    pub(super) energy_pj: Option<f64>,
    /// The unit's area \[mm²\]; `None` without a cost section.
    pub(super) area_mm2: Option<f64>,
}

/// One unit's cycle accounting; busy + starved + blocked = the frame's cycles.
pub(super) struct UnitTime {
    pub(super) name: String,
    pub(super) busy: u64,
    pub(super) starved: u64,
    pub(super) blocked: u64,
}

impl Point {
    pub(super) fn from_record(record: &Value) -> Option<Point> {
        let report = record.get("report")?;
        let settings = report.get("settings")?;
        let path = settings.get("path")?.as_str()?.to_string();
        let scene = scene_label(record)?;
        let params = record
            .get("params")
            .and_then(Value::as_object)
            .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        let cycles = report.pointer("/cycles/total").and_then(Value::as_u64);
        let units = report
            .pointer("/cycles/units")
            .and_then(Value::as_array)
            .map(|units| {
                units
                    .iter()
                    .filter_map(|u| {
                        Some(UnitTime {
                            name: u.get("name")?.as_str()?.to_string(),
                            busy: u.get("busy")?.as_u64()?,
                            starved: u.get("starved")?.as_u64()?,
                            blocked: u.get("blocked")?.as_u64()?,
                        })
                    })
                    .collect()
            })
            .unwrap_or_default();
        let rms_error = report
            .pointer("/accuracy/psnr_db")
            .and_then(Value::as_f64)
            .map(|psnr| 255.0 * 10f64.powf(-psnr / 20.0))
            .filter(|e| e.is_finite() && *e > 0.0);
        Some(Point {
            index: record.get("index").and_then(Value::as_u64).unwrap_or(0),
            scene,
            path,
            k_px: settings.get("k_px").and_then(Value::as_f64),
            tess: settings.get("tess").and_then(Value::as_u64),
            params,
            cycles: cycles.filter(|&c| c > 0),
            units,
            rms_error,
            flip_mean: report
                .pointer("/accuracy/flip_mean")
                .and_then(Value::as_f64)
                .filter(|e| e.is_finite() && *e > 0.0),
            report: report.clone(),
            energy_pj: report.pointer("/cost/energy_pj").and_then(Value::as_f64),
            area_mm2: report.pointer("/cost/area_mm2").and_then(Value::as_f64),
        })
    }

    /// The swept level of detail: `k=0.5` or `n=4`.
    pub(super) fn level(&self) -> String {
        match (self.k_px, self.tess) {
            (Some(k), _) => format!("k={}", fmt_num(k)),
            (None, Some(n)) => format!("n={n}"),
            (None, None) => format!("#{}", self.index),
        }
    }

    /// The point's value of parameter `key`, or the value its run used by default (as its
    /// report echoes it); null where the parameter does not apply.
    pub(super) fn param(&self, key: &str) -> &Value {
        static NULL: Value = Value::Null;
        self.params
            .get(key)
            .or_else(|| used(&self.report, key))
            .unwrap_or(&NULL)
    }
}

/// The parameters whose value is not the same at every point (a missing one counts as null).
pub(super) fn varying(points: &[&Point]) -> Vec<String> {
    let keys: BTreeSet<&String> = points.iter().flat_map(|p| p.params.keys()).collect();
    keys.into_iter()
        .filter(|k| {
            let values: BTreeSet<String> = points.iter().map(|p| p.param(k).to_string()).collect();
            values.len() > 1
        })
        .cloned()
        .collect()
}

/// The value most of `points` have for `key` (the first met among equals) and the others
/// as common.
pub(super) fn most_common(points: &[&Point], key: &str) -> (Value, Vec<Value>) {
    let mut tally: Vec<(Value, usize)> = Vec::new();
    for p in points {
        let v = p.param(key);
        match tally.iter_mut().find(|(seen, _)| seen == v) {
            Some((_, n)) => *n += 1,
            None => tally.push((v.clone(), 1)),
        }
    }
    let best = tally.iter().map(|(_, n)| *n).max().unwrap_or(0);
    let mut top = tally
        .into_iter()
        .filter(|(_, n)| *n == best)
        .map(|(v, _)| v);
    let first = top.next().unwrap_or(Value::Null);
    (first, top.collect())
}

/// `key=value, ...` for the given parameters of a point.
pub(super) fn assignment(p: &Point, keys: &[String]) -> String {
    keys.iter()
        .map(|k| format!("{k}={}", fmt_value(p.param(k))))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The value a run used for parameter `name` that its point did not set (the default), as
/// its report echoes it; None where the parameter does not apply to the run (k on the
/// triangle path) or the report does not say.
pub(crate) fn used<'a>(report: &'a Value, name: &str) -> Option<&'a Value> {
    let pointer = match name {
        "path" => "/settings/path".to_string(),
        "k" => "/settings/k_px".to_string(),
        "samples" => "/settings/samples".to_string(),
        "perspective_tol" => "/settings/perspective_tol".to_string(),
        "tess" => "/settings/tess".to_string(),
        "datapath" => "/settings/datapath".to_string(),
        "blend" => "/blend/mode".to_string(),
        "threshold" => "/blend/threshold".to_string(),
        // The one technology figure a report echoes; the others are left empty.
        "tech.dram.pj_per_byte" => "/cost/tech/dram_pj_per_byte".to_string(),
        arch => format!("/arch/{}", arch.strip_prefix("arch.")?.replace('.', "/")),
    };
    report.pointer(&pointer).filter(|v| !v.is_null())
}
