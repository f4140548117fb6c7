//! What a sweep record says for bracketing ([`Measured`]): its scene, path and accuracy
//! knob ([`Knob`]: k or n), its cost and error, and the keys of its group and series.

use serde_json::Value;
use std::collections::BTreeMap;

/// The accuracy knob of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Knob {
    /// The lembo path's k \[px\].
    K(f64),
    /// The triangle path's tessellation level n.
    Tess(u32),
}

impl Knob {
    /// Finer first: k ascending, n descending.
    pub(super) fn fineness(self) -> f64 {
        match self {
            Knob::K(k) => -k,
            Knob::Tess(n) => n as f64,
        }
    }
    /// `k = 0.25` or `n = 16`.
    pub fn label(self) -> String {
        match self {
            Knob::K(k) => format!("k = {k}"),
            Knob::Tess(n) => format!("n = {n}"),
        }
    }
    /// The parameter's name in a spec.
    pub fn param(self) -> &'static str {
        match self {
            Knob::K(_) => "k",
            Knob::Tess(_) => "tess",
        }
    }
    /// The parameter's canonical value.
    pub fn value(self) -> Value {
        match self {
            Knob::K(k) => Value::from(k),
            Knob::Tess(n) => Value::from(n),
        }
    }
}

/// What the answer and the refinement read of one record.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The run's index in the sweep.
    pub index: usize,
    /// The scene's name, with the viewport where the point sets one
    /// ([`crate::plot::scene_label`]).
    pub scene: String,
    /// `lembo` or `triangle`.
    pub path: &'static str,
    /// Its knob, as the run used it.
    pub knob: Knob,
    /// Its parameters, as the record holds them.
    pub params: BTreeMap<String, Value>,
    /// Frame time \[cycles\]; None in functional mode.
    pub cycles: Option<u64>,
    /// Energy of the frame \[µJ\].
    pub energy_uj: Option<f64>,
    /// The unit's area \[mm²\].
    pub area_mm2: Option<f64>,
    /// The unit that bounds the frame.
    pub bottleneck: Option<String>,
    /// PSNR against the exact reference \[dB\].
    pub psnr_db: Option<f64>,
    /// Mean FLIP \[0-1\].
    pub flip_mean: Option<f64>,
    /// The largest distance of a misplaced pixel from the true outline \[px\].
    pub silhouette_max_px: Option<f64>,
    /// The architecture the run used, as its report echoes it (null in functional mode).
    pub arch: Value,
    /// The scene's lembos (a triangle run's triangles over n²).
    pub lembos: Option<u64>,
}

impl Measured {
    /// The record's figures; None for a record of a discoid scene or without settings.
    pub fn of(record: &Value) -> Option<Measured> {
        let report = &record["report"];
        let settings = &report["settings"];
        if !report["blend"].is_null() {
            return None;
        }
        let (path, knob) = match settings["path"].as_str()? {
            "triangle" => (
                "triangle",
                Knob::Tess(u32::try_from(settings["tess"].as_u64()?).ok()?),
            ),
            _ => ("lembo", Knob::K(settings["k_px"].as_f64()?)),
        };
        let params = record["params"]
            .as_object()
            .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        let acc = &report["accuracy"];
        Some(Measured {
            index: record["index"].as_u64()? as usize,
            scene: crate::plot::scene_label(record)?,
            path,
            knob,
            params,
            cycles: report["cycles"]["total"].as_u64(),
            energy_uj: report["cost"]["energy_pj"].as_f64().map(|e| e * 1e-6),
            area_mm2: report["cost"]["area_mm2"].as_f64(),
            bottleneck: report["cycles"]["bottleneck"].as_str().map(str::to_string),
            psnr_db: acc["psnr_db"].as_f64(),
            flip_mean: acc["flip_mean"].as_f64(),
            silhouette_max_px: acc["silhouette_max_px"].as_f64(),
            arch: report["arch"].clone(),
            lembos: report["primitives"]["count"].as_u64().map(|c| match knob {
                Knob::Tess(n) => c / (n as u64 * n as u64).max(1),
                Knob::K(_) => c,
            }),
        })
    }

    /// Whether the run is a sensitivity variant (`super::sensitivity`), not one of the
    /// grid's.
    pub fn is_variant(&self) -> bool {
        self.params.contains_key(crate::sweep::names::SENSITIVITY)
    }

    /// Whether the unit fits `budget` (every run fits no budget).
    pub fn within(&self, budget: Option<f64>) -> bool {
        match (budget, self.area_mm2) {
            (None, _) => true,
            (Some(b), Some(a)) => a <= b,
            (Some(_), None) => false,
        }
    }

    /// The parameters without the knob and the path, as `name=value` joined by `|`: one
    /// architecture of a series.
    pub fn group(&self) -> String {
        self.params_without(|name| name == "path" || name == self.knob.param())
    }

    /// The parameters that can change the image (not `arch.*`), without the knob, and
    /// the value of `by` (the spec's `by`: each value's runs are series of their own, so
    /// that each is refined and bracketed apart): the series.
    pub fn series_key(&self, by: Option<&str>) -> String {
        let key = self.params_without(|name| {
            name == "path"
                || name == self.knob.param()
                || name.starts_with(crate::sweep::names::ARCH)
        });
        match by.and_then(|b| Some((b, b.strip_prefix(crate::sweep::names::ARCH)?))) {
            Some((name, path)) => {
                let value = self.params.get(name).cloned().unwrap_or_else(|| {
                    path.split('.')
                        .try_fold(&self.arch, |at, part| at.get(part))
                        .cloned()
                        .unwrap_or(Value::Null)
                });
                let by = format!("{name}={value}");
                if key.is_empty() {
                    by
                } else {
                    format!("{key}|{by}")
                }
            }
            None => key,
        }
    }

    fn params_without(&self, drop: impl Fn(&str) -> bool) -> String {
        self.params
            .iter()
            .filter(|(name, _)| !drop(name))
            .map(|(name, value)| format!("{name}={value}"))
            .collect::<Vec<_>>()
            .join("|")
    }
}
