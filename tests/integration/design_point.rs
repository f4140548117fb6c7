//! Area is the architecture's (DESIGN.md §12): the committed design point
//! (`src/cost/design_point.json`) is what its calibration set measures, one architecture
//! has one area whatever is drawn on it, and a unit's area follows its own configuration.
//!
//! The calibration set, at the embedded baseline's rates, at 128 x 128 and at the shipped
//! scenes' own 512 x 512:
//! - the surface scenes sphere24, cylinder24, surface96, bunny and terrain320: the lembo
//!   path at k = 2, 0.5 and 0.1, samples 1 and 4 in `f32`, samples 1 in `f64`; the
//!   triangle path at n = 1, 2, 4, 8 and 16 (terrain320: 1 and 2, its n = 16 alone takes
//!   a minute), from memory and tessellated on chip, samples 1 and 4, in `f32` with the
//!   reciprocal per quad, and samples 1 in `f64`; samples 1 from memory with the
//!   reciprocal per pixel;
//! - the discoid scenes (every shipped scene with discoids), each blend mode, in `f32`
//!   and `f64`.
//!
//! Regenerate the file with `LEMBO_BLESS=1 cargo test --release --test integration
//! design_point` after an intended change of what a unit computes or of the baseline's
//! rates (then re-bless what carries area: the cycle goldens and the committed sweeps).

use crate::support::golden::blessing;
use crate::support::{arch, render_job, scenes};
use lembo_sim::camera::Samples;
use lembo_sim::config::{ArchConfig, Reciprocal};
use lembo_sim::cost::design_point::{self, DesignEntry, DesignPointFile};
use lembo_sim::cost::model::CostReport;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::graph::TessSource;
use lembo_sim::job::{run_render, Mode, PrimitivePath, RenderJob};
use std::collections::BTreeMap;
use std::path::Path;

/// One frame of a set: what is drawn, how, and on which architecture file.
#[derive(Clone, Debug)]
struct Case {
    scene: String,
    viewport: u32,
    path: PrimitivePath,
    k: f64,
    tess: u32,
    samples: u32,
    datapath: Datapath,
    blend: BlendMode,
    source: TessSource,
    reciprocal: Reciprocal,
    /// Whether the scene has discoids (its name then says the blend mode).
    discoid: bool,
}

impl Case {
    fn surface(scene: &str, viewport: u32) -> Case {
        Case {
            scene: scene.to_string(),
            viewport,
            path: PrimitivePath::Lembo,
            k: 0.5,
            tess: 1,
            samples: 1,
            datapath: Datapath::F32,
            blend: BlendMode::Rgba8,
            source: TessSource::Memory,
            reciprocal: Reciprocal::Quad,
            discoid: false,
        }
    }

    fn name(&self) -> String {
        let what = match self.path {
            PrimitivePath::Lembo => format!("lembo k={}", self.k),
            PrimitivePath::Triangle => format!(
                "triangle n={} {} reciprocal={}",
                self.tess,
                match self.source {
                    TessSource::Memory => "memory",
                    TessSource::OnChip => "onchip",
                },
                match self.reciprocal {
                    Reciprocal::Quad => "quad",
                    Reciprocal::Pixel => "pixel",
                }
            ),
        };
        let blend = if self.discoid {
            format!(" blend={}", self.blend.name())
        } else {
            String::new()
        };
        format!(
            "{} {}x{} {what} samples={} {}{blend}",
            self.scene,
            self.viewport,
            self.viewport,
            self.samples,
            self.datapath.name()
        )
    }

    /// The case's report cost on `base` (its source and reciprocal applied), rendered
    /// into `dir`.
    fn cost(&self, base: &ArchConfig, dir: &Path) -> CostReport {
        let mut a = base.clone();
        a.tessellation.source = self.source;
        a.triangle_rasterizer.reciprocal = self.reciprocal;
        std::fs::create_dir_all(dir).unwrap();
        let arch_file = dir.join("arch.json");
        std::fs::write(&arch_file, serde_json::to_string(&a).unwrap()).unwrap();
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let job = RenderJob {
            trace: Default::default(),
            scene: Some(root.join(format!("traces/{}.json", self.scene))),
            out: Some(dir.join("out")),
            k: self.k,
            datapath: self.datapath,
            samples: Samples::new(self.samples).unwrap(),
            viewport: Some((self.viewport, self.viewport)),
            mode: Mode::Timed,
            arch: Some(arch_file),
            path: self.path,
            tess: (self.path == PrimitivePath::Triangle).then_some(self.tess),
            blend: self.blend,
            no_memory_check: true,
            ..render_job(self.k, self.datapath)
        };
        let out = run_render(&job).unwrap_or_else(|e| panic!("{}: {e}", self.name()));
        out.report.cost.expect("a timed run is priced")
    }
}

/// The calibration set (the module's text), in a fixed order.
fn calibration_set() -> Vec<Case> {
    let mut out = Vec::new();
    for viewport in [128, 512] {
        for scene in ["sphere24", "cylinder24", "surface96", "bunny", "terrain320"] {
            let c = Case::surface(scene, viewport);
            for k in [2.0, 0.5, 0.1] {
                for (samples, datapath) in
                    [(1, Datapath::F32), (4, Datapath::F32), (1, Datapath::F64)]
                {
                    out.push(Case {
                        k,
                        samples,
                        datapath,
                        ..c.clone()
                    });
                }
            }
            let levels: &[u32] = if scene == "terrain320" {
                &[1, 2]
            } else {
                &[1, 2, 4, 8, 16]
            };
            for &tess in levels {
                let t = Case {
                    path: PrimitivePath::Triangle,
                    tess,
                    ..c.clone()
                };
                for source in [TessSource::Memory, TessSource::OnChip] {
                    for samples in [1, 4] {
                        out.push(Case {
                            source,
                            samples,
                            ..t.clone()
                        });
                    }
                    out.push(Case {
                        source,
                        datapath: Datapath::F64,
                        ..t.clone()
                    });
                }
                out.push(Case {
                    reciprocal: Reciprocal::Pixel,
                    ..t.clone()
                });
            }
        }
    }
    for (name, path) in scenes::shipped_files() {
        let Some(name) = name
            .strip_prefix("traces/")
            .and_then(|n| n.strip_suffix(".json"))
            .filter(|n| !n.contains('/'))
        else {
            continue;
        };
        let scene = lembo_sim::scene::Scene::load(&path).unwrap();
        if scene.discoid_count() == 0 {
            continue;
        }
        for datapath in [Datapath::F32, Datapath::F64] {
            for blend in BlendMode::ALL {
                out.push(Case {
                    datapath,
                    blend,
                    discoid: true,
                    ..Case::surface(name, 512)
                });
            }
        }
    }
    out
}

/// Each case's cost on `base`, in the cases' order, over two host threads.
fn costs(cases: &[Case], base: &ArchConfig, tag: &str) -> Vec<CostReport> {
    let dir = std::env::temp_dir().join(format!("lembo-design-{tag}-{}", std::process::id()));
    let threads = 2;
    let mut out: Vec<Option<CostReport>> = vec![None; cases.len()];
    std::thread::scope(|s| {
        let chunks: Vec<_> = out.chunks_mut(cases.len().div_ceil(threads)).collect();
        for (t, chunk) in chunks.into_iter().enumerate() {
            let dir = dir.join(t.to_string());
            let first = t * cases.len().div_ceil(threads);
            s.spawn(move || {
                for (i, slot) in chunk.iter_mut().enumerate() {
                    *slot = Some(cases[first + i].cost(base, &dir));
                }
            });
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
    out.into_iter().map(Option::unwrap).collect()
}

/// The design point of `cases`: each key's largest operations per busy cycle, and the
/// first case that reached it.
fn measure(cases: &[Case]) -> DesignPointFile {
    let costs = costs(cases, &ArchConfig::baseline(), "calibration");
    let mut entries: BTreeMap<String, DesignEntry> = BTreeMap::new();
    for (case, cost) in cases.iter().zip(&costs) {
        for (key, &rate) in &cost.per_busy_cycle {
            let e = entries.entry(key.clone()).or_insert(DesignEntry {
                per_busy_cycle: 0.0,
                at: String::new(),
            });
            if rate > e.per_busy_cycle {
                *e = DesignEntry {
                    per_busy_cycle: rate,
                    at: case.name(),
                };
            }
        }
    }
    DesignPointFile {
        about: "Each unit kind's operations of each class per busy cycle at the design \
                point its datapath is sized for: the largest over the calibration set, at \
                the embedded baseline architecture's rates (DESIGN.md §12, \
                src/cost/design_point.rs). Generated: do not edit."
            .into(),
        regenerate: "LEMBO_BLESS=1 cargo test --release --test integration design_point".into(),
        calibration: "tests/integration/design_point.rs: the surface scenes sphere24, \
                      cylinder24, surface96, bunny, terrain320 at 128x128 and 512x512; \
                      lembo path k = 2, 0.5, 0.1, samples 1 and 4 (f32), samples 1 (f64); \
                      triangle path n = 1, 2, 4, 8, 16 (terrain320: 1, 2), memory and onchip, \
                      samples 1 and 4 (f32, reciprocal per quad) and samples 1 (f64); \
                      samples 1 from memory with the reciprocal per pixel; the discoid scenes at 512x512 \
                      in each blend mode, f32 and f64."
            .into(),
        entries,
    }
}

/// The committed design point is what the calibration set measures with the code as it
/// is: a change of what a unit computes per busy cycle (its operations, its rate, the
/// baseline) names every entry it moves. `LEMBO_BLESS=1` rewrites the file.
///
/// The whole set takes over a minute on two cores, so every test run measures only the
/// cases that decide an entry (about a fifth of it): each committed entry must be what its
/// named case measures and no other of them exceeds it (the subset keeps the set's order,
/// so the first case to reach an entry's figure is the same), which catches a change of
/// what a unit computes wherever those cases draw. That a case outside them now exceeds an
/// entry, the whole set checks, with `LEMBO_FULL_CHECKS=1` and when blessing.
#[test]
fn design_point_is_what_the_calibration_set_measures() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/cost/design_point.json");
    let want = design_point::embedded();
    let whole = blessing() || crate::support::full_checks();
    let set = calibration_set();
    let cases: Vec<Case> = if whole {
        set
    } else {
        let deciding: std::collections::BTreeSet<&str> =
            want.entries.values().map(|e| e.at.as_str()).collect();
        let cases: Vec<Case> = set
            .into_iter()
            .filter(|c| deciding.contains(c.name().as_str()))
            .collect();
        assert_eq!(
            cases.len(),
            deciding.len(),
            "a committed entry names a case the calibration set no longer has"
        );
        cases
    };
    let got = measure(&cases);
    assert!(got.entries.len() > 100, "{} entries", got.entries.len());
    let mut moved = Vec::new();
    for key in got.entries.keys().chain(want.entries.keys()) {
        match (want.entries.get(key), got.entries.get(key)) {
            // serde_json reads a float back within an ulp or two of what it wrote.
            (Some(w), Some(g))
                if w.at != g.at
                    || (w.per_busy_cycle - g.per_busy_cycle).abs()
                        > 1e-12 * w.per_busy_cycle.abs() =>
            {
                moved.push(format!(
                    "{key}: committed {} ({}), measured {} ({})",
                    w.per_busy_cycle, w.at, g.per_busy_cycle, g.at
                ))
            }
            (None, Some(g)) => moved.push(format!("{key}: new, measured {g:?}")),
            (Some(_), None) => moved.push(format!("{key}: no longer measured")),
            _ => {}
        }
    }
    moved.dedup();
    let stale =
        moved.is_empty() && (want.about != got.about || want.calibration != got.calibration);
    if blessing() {
        eprintln!("design point: {} entries moved", moved.len());
        for m in moved.iter().take(40) {
            eprintln!("  {m}");
        }
        let text = serde_json::to_string_pretty(&got).unwrap() + "\n";
        std::fs::write(&path, text).unwrap();
        return;
    }
    assert!(
        moved.is_empty() && !stale,
        "src/cost/design_point.json is stale ({} entries moved; regenerate with {}):\n{}",
        moved.len(),
        got.regenerate,
        moved.join("\n")
    );
}

/// The frames the one-area test draws: four shipped surface scenes at 128 x 128 (not
/// terrain320, whose 204 800 lembos take most of a minute over these frames and add no
/// other kind of frame), the lembo path at several k, the triangle path at several n (from
/// memory and on chip), samples 1 and 4.
fn varied_frames() -> Vec<Case> {
    let mut out = Vec::new();
    for scene in ["sphere24", "cylinder24", "surface96", "bunny"] {
        let c = Case::surface(scene, 128);
        for samples in [1, 4] {
            for k in [2.0, 0.25] {
                out.push(Case {
                    k,
                    samples,
                    ..c.clone()
                });
            }
            for tess in [1, 2, 8] {
                for source in [TessSource::Memory, TessSource::OnChip] {
                    out.push(Case {
                        path: PrimitivePath::Triangle,
                        tess,
                        samples,
                        source,
                        ..c.clone()
                    });
                }
            }
        }
    }
    out
}

/// Each unit's area and functional units, and the total, as text.
fn areas(c: &CostReport) -> String {
    let mut t = format!("total {}\n", c.area_mm2);
    for u in &c.units {
        t += &format!("{} {} {:?}\n", u.name, u.area_mm2, u.functional_units);
    }
    t
}

/// One architecture, one area: the embedded baseline and `sim/arch/gpu.json` each have
/// exactly one area (the total and every unit's, with its functional units) per path and
/// triangle source, whatever the scene, k, n and sample count; only its energy follows the
/// frame.
#[test]
fn design_point_one_architecture_has_one_area() {
    let frames = varied_frames();
    for (name, base) in [
        ("baseline", ArchConfig::baseline()),
        ("gpu", arch("gpu.json")),
    ] {
        let costs = costs(&frames, &base, name);
        let mut seen: BTreeMap<String, (String, String)> = BTreeMap::new();
        let mut energies = Vec::new();
        for (case, cost) in frames.iter().zip(&costs) {
            let chip = match case.path {
                PrimitivePath::Lembo => "lembo".to_string(),
                PrimitivePath::Triangle => format!("triangle {:?}", case.source),
            };
            let got = areas(cost);
            match seen.get(&chip) {
                None => {
                    seen.insert(chip, (got, case.name()));
                }
                Some((first, at)) => assert_eq!(
                    first,
                    &got,
                    "{name}: {chip}'s area at {at}, then at {}",
                    case.name()
                ),
            }
            energies.push(cost.energy_pj);
        }
        assert_eq!(seen.len(), 3, "{name}: {:?}", seen.keys());
        energies.sort_by(f64::total_cmp);
        energies.dedup();
        assert!(
            energies.len() > frames.len() / 2,
            "{name}: energy follows the frame"
        );
    }
}

/// A unit's area is its configuration's: one more Segmenter adds exactly one Segmenter's
/// area and leaves every other unit's; halving its cycles per segment (twice the rate)
/// doubles its functional units, rounded up, and changes no other unit's.
#[test]
fn design_point_a_units_count_and_rate_set_its_area() {
    let case = Case::surface("bunny", 128);
    let base = ArchConfig::baseline();
    let mut more = base.clone();
    more.segmenter.count += 1;
    let mut faster = base.clone();
    faster.segmenter.cycles_per_segment /= 2;
    let b = &costs(std::slice::from_ref(&case), &base, "count-rate-base")[0];
    let m = &costs(std::slice::from_ref(&case), &more, "count-rate-more")[0];
    let f = &costs(std::slice::from_ref(&case), &faster, "count-rate-faster")[0];
    let seg = |c: &CostReport| {
        c.units
            .iter()
            .filter(|u| u.name.starts_with("Segmenter["))
            .cloned()
            .collect::<Vec<_>>()
    };
    let one = &seg(b)[0];
    assert_eq!(seg(m).len(), seg(b).len() + 1);
    // The new instance's FIFOs: one link from each interval manager, as the others'.
    assert!(seg(m).iter().all(|u| u.area_mm2 == one.area_mm2));
    let others = |c: &CostReport| -> Vec<(String, f64)> {
        c.units
            .iter()
            .filter(|u| !u.name.starts_with("Segmenter[") && !u.name.starts_with("Subsegmenter["))
            .map(|u| (u.name.clone(), u.area_mm2))
            .collect()
    };
    // The subsegmenters' FIFOs have one link more (one a segmenter): that is theirs.
    assert_eq!(others(m), others(b));
    assert!(
        (m.area_mm2 - b.area_mm2 - one.area_mm2 - sub_fifo_growth(b, m)).abs() < 1e-12,
        "{} -> {}",
        b.area_mm2,
        m.area_mm2
    );
    // Twice the rate: each class's units are the design point's times 2, rounded up.
    let d = design_point::embedded();
    let key = |op: &str| format!("f32 surface Segmenter {op}");
    let fu = |c: &CostReport| seg(c)[0].functional_units.to_array();
    for (i, op) in lembo_sim::datapath::OPS.iter().enumerate() {
        let Some(e) = d.entries.get(&key(op.name())) else {
            assert_eq!(fu(b)[i], 0);
            continue;
        };
        assert_eq!(fu(b)[i], e.per_busy_cycle.ceil() as u64, "{op:?}");
        assert_eq!(fu(f)[i], (2.0 * e.per_busy_cycle).ceil() as u64, "{op:?}");
    }
    assert!(seg(f)[0].area_mm2 > one.area_mm2);
    assert_eq!(others(f), others(b));
}

/// How much the subsegmenters' FIFO area grew from `b` to `m` (one link more from the added
/// segmenter).
fn sub_fifo_growth(b: &CostReport, m: &CostReport) -> f64 {
    let sub = |c: &CostReport| -> f64 {
        c.units
            .iter()
            .filter(|u| u.name.starts_with("Subsegmenter["))
            .map(|u| u.area_mm2)
            .sum()
    };
    sub(m) - sub(b)
}
