//! Tests of bracketing: when a series ends and why, the next round's runs, the coarse
//! side, and the `refine` settings' checks.

use super::*;
use crate::error::Error;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// A measured run of `path` on scene `s` at `knob`, its architecture `arch`.
fn run(index: usize, knob: Knob, arch: u64, cycles: u64, uj: f64, psnr: f64) -> Measured {
    let path = match knob {
        Knob::K(_) => "lembo",
        Knob::Tess(_) => "triangle",
    };
    let mut params = BTreeMap::new();
    params.insert("path".to_string(), json!(path));
    params.insert(knob.param().to_string(), knob.value());
    params.insert("arch.rop.count".to_string(), json!(arch));
    Measured {
        index,
        scene: "s".into(),
        path,
        knob,
        params,
        cycles: Some(cycles),
        energy_uj: Some(uj),
        area_mm2: Some(arch as f64),
        bottleneck: None,
        psnr_db: Some(psnr),
        flip_mean: None,
        silhouette_max_px: None,
        arch: Value::Null,
        lembos: Some(1000),
    }
}

fn limits(refine: Option<Refine>, budget: Option<f64>) -> Limits<'static> {
    Limits {
        refine,
        budget,
        triangle_ok: &|_, n| n <= 64,
        by: None,
    }
}

#[test]
fn a_series_ends_after_two_steps_under_the_margin_not_one() {
    let refine = Some(Refine::default());
    // 40 -> 40.2 (a plateau) -> 45: one small step is not the end.
    let mut runs = vec![
        run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
        run(1, Knob::K(0.5), 1, 110, 1.0, 40.2),
    ];
    let s = series(&runs, &limits(refine, None));
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].stop, Stop::Next(Knob::K(0.25)));
    runs.push(run(2, Knob::K(0.25), 1, 120, 1.0, 45.0));
    runs.push(run(3, Knob::K(0.125), 1, 130, 1.0, 45.3));
    let s = series(&runs, &limits(refine, None));
    assert_eq!(s[0].stop, Stop::Next(Knob::K(0.0625)));
    // A level that loses counts as a gain under the margin (against the best before).
    runs.push(run(4, Knob::K(0.0625), 1, 140, 1.0, 44.0));
    let s = series(&runs, &limits(refine, None));
    match s[0].stop {
        Stop::Converged { gains_db: [a, b] } => {
            assert!((a - 0.3).abs() < 1e-9 && (b + 1.3).abs() < 1e-9, "{a} {b}")
        }
        ref other => panic!("{other:?}"),
    }
    assert!(s[0].stop.bracketed(0.5));
    assert_eq!(s[0].best_psnr(), Some(45.3));
}

#[test]
fn floors_caps_cycle_caps_and_the_triangle_budget_end_a_series_unbracketed() {
    let r = Refine {
        k_floor: 0.25,
        tess_cap: 16,
        cycle_cap: Some(1_000),
        ..Refine::default()
    };
    let l = limits(Some(r), None);
    // k halves down to the floor, not past it.
    let runs = [
        run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
        run(1, Knob::K(0.4), 1, 100, 1.0, 45.0),
    ];
    assert_eq!(series(&runs, &l)[0].stop, Stop::Next(Knob::K(0.25)));
    let runs = [
        run(0, Knob::K(0.5), 1, 100, 1.0, 40.0),
        run(1, Knob::K(0.25), 1, 100, 1.0, 45.0),
    ];
    let s = &series(&runs, &l)[0];
    assert_eq!(s.stop, Stop::Floor);
    assert!(!s.stop.bracketed(0.5));
    assert!(s.stop.describe(0.5, s.finest()).contains("unbracketed"));
    // n doubles up to the cap.
    let runs = [
        run(0, Knob::Tess(4), 1, 100, 1.0, 40.0),
        run(1, Knob::Tess(12), 1, 100, 1.0, 45.0),
    ];
    assert_eq!(series(&runs, &l)[0].stop, Stop::Next(Knob::Tess(16)));
    let runs = [
        run(0, Knob::Tess(8), 1, 100, 1.0, 40.0),
        run(1, Knob::Tess(16), 1, 100, 1.0, 45.0),
    ];
    assert_eq!(series(&runs, &l)[0].stop, Stop::Cap);
    // A run over the cycle cap ends it.
    let runs = [
        run(0, Knob::Tess(2), 1, 100, 1.0, 40.0),
        run(1, Knob::Tess(4), 1, 1_001, 1.0, 45.0),
    ];
    assert_eq!(series(&runs, &l)[0].stop, Stop::CycleCap { cycles: 1_001 });
    // The next n beyond the scene's triangle budget (64 here).
    let l = limits(Some(Refine::default()), None);
    let runs = [
        run(0, Knob::Tess(32), 1, 100, 1.0, 40.0),
        run(1, Knob::Tess(48), 1, 100, 1.0, 45.0),
    ];
    assert_eq!(
        series(
            &runs,
            &Limits {
                triangle_ok: &|_, n| n <= 48,
                ..l
            }
        )[0]
        .stop,
        Stop::TriangleBudget { next: 64 }
    );
}

#[test]
fn a_grid_without_refinement_is_flagged_where_it_stops_early() {
    let l = limits(None, None);
    let early = [
        run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
        run(1, Knob::K(0.5), 1, 100, 1.0, 44.0),
        run(2, Knob::K(0.25), 1, 100, 1.0, 47.0),
    ];
    let s = &series(&early, &l)[0];
    assert!(!s.stop.bracketed(0.5));
    let said = s.stop.describe(0.5, s.finest());
    assert!(
        said.contains("unbracketed") && said.contains("k = 0.25"),
        "{said}"
    );
    let settled = [
        run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
        run(1, Knob::K(0.5), 1, 100, 1.0, 40.1),
        run(2, Knob::K(0.25), 1, 100, 1.0, 40.2),
    ];
    assert!(series(&settled, &l)[0].stop.bracketed(0.5));
}

#[test]
fn the_next_round_runs_the_fastest_and_most_frugal_architecture_within_the_budget() {
    let l = limits(Some(Refine::default()), Some(3.0));
    let runs = [
        run(0, Knob::Tess(1), 1, 500, 1.0, 30.0),
        run(1, Knob::Tess(1), 2, 300, 2.0, 30.0),
        run(2, Knob::Tess(1), 4, 100, 0.5, 30.0),
        run(3, Knob::Tess(2), 1, 900, 1.5, 35.0),
        run(4, Knob::Tess(2), 2, 600, 3.0, 35.0),
        // Over the budget: not a leader, not in the series.
        run(5, Knob::Tess(2), 4, 200, 0.5, 35.0),
    ];
    let next = next_round(&runs, &l);
    // Fastest at n = 2 within 3 mm²: arch 2 (run 4); most frugal: arch 1 (run 3).
    assert_eq!(next, [(4, Knob::Tess(4)), (3, Knob::Tess(4))]);
    // Images do not depend on the architecture: one series, whatever the counts.
    assert_eq!(series(&runs, &l).len(), 1);
}

/// A triangle series whose grid starts above n = 1 and whose coarsest level still
/// saves goes on to half its n, down to n = 1, where nothing coarser exists.
#[test]
fn the_coarse_side_halves_n_down_to_one() {
    let l = limits(Some(Refine::default()), None);
    let mut runs = vec![
        run(0, Knob::Tess(4), 1, 500, 1.0, 40.0),
        run(1, Knob::Tess(8), 1, 1000, 2.0, 44.0),
    ];
    assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::Tess(2)));
    runs.push(run(2, Knob::Tess(2), 1, 300, 0.6, 35.0));
    assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::Tess(1)));
    runs.push(run(3, Knob::Tess(1), 1, 200, 0.5, 30.0));
    let s = &series(&runs, &l)[0];
    assert_eq!(s.coarse, Coarse::Natural);
    assert!(s.coarse.bracketed());
}

#[test]
fn the_coarse_side_doubles_k_until_a_coarser_level_saves_under_the_margin() {
    let l = limits(Some(Refine::default()), None);
    // k = 2 saves 10% of k = 1's cycles: a coarser k might reach a target for less.
    let mut runs = vec![
        run(0, Knob::K(2.0), 1, 900, 1.0, 40.0),
        run(1, Knob::K(2.0), 2, 950, 0.9, 40.0),
        run(2, Knob::K(1.0), 1, 1000, 1.0, 44.0),
    ];
    let s = &series(&runs, &l)[0];
    assert_eq!(s.coarse, Coarse::Next(Knob::K(4.0)));
    assert!(!s.coarse.bracketed());
    // On the coarsest level's fastest (run 0) and most frugal (run 1) architectures,
    // after the finer level's runs.
    let next = next_round(&runs, &l);
    assert_eq!(
        &next[next.len() - 2..],
        [(0, Knob::K(4.0)), (1, Knob::K(4.0))]
    );
    // k = 4 saves 1% of the cycles and 0% of the energy: settled.
    runs.push(run(3, Knob::K(4.0), 1, 891, 1.0, 35.0));
    runs.push(run(4, Knob::K(4.0), 2, 940, 0.9, 35.0));
    let s = &series(&runs, &l)[0];
    match s.coarse {
        Coarse::Settled { saving } => assert!((saving - 0.01).abs() < 1e-9, "{saving}"),
        ref other => panic!("{other:?}"),
    }
    assert!(s.coarse.bracketed());
    assert_eq!(s.coarsest(), Knob::K(4.0));
    // One saving under the margin is not enough: both cycles and energy must be.
    runs[4].energy_uj = Some(0.5);
    assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::K(8.0)));
    // The ceiling ends it unbracketed; n = 1 and the largest k are the natural ends.
    let r = Refine {
        k_ceiling: 4.0,
        ..Refine::default()
    };
    let s = &series(&runs, &limits(Some(r), None))[0];
    assert_eq!(s.coarse, Coarse::Ceiling);
    assert!(s
        .coarse
        .describe(0.02, s.coarsest())
        .contains("unbracketed"));
    let ends = [
        run(0, Knob::Tess(1), 1, 10, 1.0, 30.0),
        run(1, Knob::K(K_RANGE.1), 1, 10, 1.0, 30.0),
    ];
    for s in series(&ends, &l) {
        assert_eq!(s.coarse, Coarse::Natural);
    }
    // Without refinement, the grid's coarse end is reported, not extended.
    let grid = [
        run(0, Knob::K(2.0), 1, 500, 1.0, 40.0),
        run(1, Knob::K(1.0), 1, 1000, 1.0, 44.0),
    ];
    assert_eq!(
        series(&grid, &limits(None, None))[0].coarse,
        Coarse::GridEnd
    );
}

#[test]
fn refine_settings_are_checked_naming_their_field() {
    let check = |text: &str| -> std::result::Result<Refine, String> {
        let f: RefineFile = serde_json::from_str(text).unwrap();
        Refine::from_file("s.json", &f).map_err(|e| match e {
            Error::Invalid { field, .. } | Error::Parse { field, .. } => field,
            other => other.to_string(),
        })
    };
    assert_eq!(check("{}"), Ok(Refine::default()));
    for (text, field) in [
        (r#"{"margin_db": -1}"#, "refine.margin_db"),
        (r#"{"margin_db": 100}"#, "refine.margin_db"),
        (r#"{"k_floor": 0}"#, "refine.k_floor"),
        (r#"{"k_floor": 100}"#, "refine.k_floor"),
        (r#"{"tess_cap": 0}"#, "refine.tess_cap"),
        (r#"{"tess_cap": 5000}"#, "refine.tess_cap"),
        (r#"{"cycle_cap": 0}"#, "refine.cycle_cap"),
        (r#"{"k_ceiling": 100}"#, "refine.k_ceiling"),
        (r#"{"k_floor": 1, "k_ceiling": 0.5}"#, "refine.k_ceiling"),
        (r#"{"cost_margin": 1}"#, "refine.cost_margin"),
        (r#"{"cost_margin": -0.1}"#, "refine.cost_margin"),
    ] {
        assert_eq!(check(text), Err(field.to_string()), "{text}");
    }
}
