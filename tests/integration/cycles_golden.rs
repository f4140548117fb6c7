//! The timed model's cycle reports, every counter of every unit, kept as goldens: every
//! shipped scene (`traces/*.json`, `traces/extremes/*.json`) through the lembo path and the
//! triangle path (n = 2) on the three shipped architectures, and 200 seeded random
//! architectures on sphere24 through both paths. A change to the timed engine must
//! reproduce them exactly; a report that changes is a change of the model, to be explained.
//!
//! Recorded from the thread-per-unit runtime before the discrete-event executor replaced
//! it; the executor reproduces every shipped scene's report and 391 of the 400 random
//! ones exactly. The other 9 (random cases 018, 020, 035, 039, 074, 098, 132 and 143 on the
//! triangle path, 113 on the lembo path) were wrong before: the old runtime's deadlock
//! recovery let every unit holding the earliest held item take it, which is unsafe when a
//! unit frozen on a credit takes its next input before the credit's cycle (see
//! `pipeline::runtime::core::recover`); in case 098 Rop[2] took an item arriving at 377
//! before one arriving at 374. Their reports are now the ones the merge rule defines: the
//! same in any execution order and host partition (checked here), with every merge's items
//! taken in (arrival, port) order (checked on every run).
//!
//! Regenerate with `LEMBO_BLESS=1 cargo test --release --test integration cycles_golden::`
//! only after an intended change of the timing model.

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::discoid::run_discoid_timed;
use lembo_sim::pipeline::{run_timed, CycleReport, SimOptions, Source};
use lembo_sim::raster::Counts;
use lembo_sim::scene::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::support::golden;
use crate::support::{arch, scenes};

const SIDE: u32 = 128;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// One line per unit (name, busy, starved, blocked, items in, items out, most items in an
/// input FIFO) and one for the counts: everything a cycle report holds.
fn digest(cycles: &CycleReport, counts: &Counts) -> String {
    let mut s = format!(
        "total {} bottleneck {:?}\n",
        cycles.total, cycles.bottleneck
    );
    for u in &cycles.units {
        writeln!(
            s,
            "{} {} {} {} {} {} {}",
            u.name, u.busy, u.starved, u.blocked, u.items_in, u.items_out, u.max_fifo_occupancy
        )
        .unwrap();
    }
    s + &crate::support::counts_before_culling(counts)
}

/// The digest of one timed run of `scene` on `a` (lembo path, or triangle path at n = 2),
/// or its error.
fn run(scene: &Scene, a: &ArchConfig, triangles: bool) -> String {
    run_with(scene, a, triangles, &SimOptions::default())
}

fn run_with(scene: &Scene, a: &ArchConfig, triangles: bool, options: &SimOptions) -> String {
    let view = View::new(&scene.camera, scene.viewport);
    if scene.discoid_count() > 0 {
        return match run_discoid_timed(
            scene,
            &view,
            0.5,
            Datapath::F32,
            a,
            BlendMode::Rgba8,
            scene.discoid_threshold,
            options,
        ) {
            Ok(t) => digest(&t.cycles, &t.counts),
            Err(e) => format!("error: {e}"),
        };
    }
    let tess = triangles.then(|| Tessellation::new(scene.lembo_sets(), 2));
    let source = tess
        .as_ref()
        .map_or(Source::Lembos, |t| Source::Triangles(t));
    match run_timed(scene, &view, 0.5, Datapath::F32, a, source, options) {
        Ok(t) => digest(&t.cycles, &t.counts),
        Err(e) => format!("error: {e}"),
    }
}

/// Compares `got` with the golden file `name` of `tests/golden/cycles` (at least `min_cases`
/// cases, every run a frame of some cycles), or writes it when blessing.
fn check(name: &str, got: BTreeMap<String, String>, min_cases: usize) {
    golden::check(
        &root().join("tests/golden/cycles").join(name),
        got,
        "cycle reports",
        &golden::Expect {
            min_cases,
            expected_errors: &[],
            valid: &golden::cycles_above_zero,
        },
    );
}

/// Every shipped scene, at 128 x 128, each path, each shipped architecture.
#[test]
fn shipped_scenes_keep_their_cycle_reports() {
    let files = scenes::shipped_files();
    let archs = ["baseline.json", "minimal.json", "wide.json"].map(|n| (n, arch(n)));
    let mut got = BTreeMap::new();
    for (name, path) in &files {
        let mut scene = Scene::load(path).unwrap();
        scene.set_viewport(SIDE, SIDE).unwrap();
        let paths: &[bool] = if scene.discoid_count() > 0 {
            &[false]
        } else {
            &[false, true]
        };
        for (an, a) in &archs {
            for &triangles in paths {
                let path = if triangles { "triangle" } else { "lembo" };
                let digest = run(&scene, a, triangles);
                if *an == "baseline.json" {
                    let three = SimOptions {
                        host_threads: 3,
                        ..SimOptions::default()
                    };
                    assert_eq!(
                        run_with(&scene, a, triangles, &three),
                        digest,
                        "{name} {path} on three host threads"
                    );
                }
                got.insert(format!("{name} {an} {path}"), digest);
            }
        }
    }
    check("shipped.json", got, 150);
}

/// 200 seeded random architectures (unit counts 1-8, costs, FIFO depths 1-64, latencies,
/// tile sizes) on sphere24 at 40 x 40, both paths.
#[test]
fn random_architectures_keep_their_cycle_reports() {
    let s = scenes::trace("sphere24.json", Some(40));
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 200,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[11; 32]),
    );
    let unit = 1u32..=8;
    let cost = 1u64..=20;
    let depth = prop_oneof![Just(1u32), 2u32..=8, Just(64)];
    let strategy = (
        (unit.clone(), unit.clone(), unit.clone(), unit.clone(), unit),
        (cost.clone(), cost.clone(), cost.clone(), cost.clone(), cost),
        proptest::collection::vec((depth, 1u64..=6), 9),
        1u32..=16,
    );
    let got = std::cell::RefCell::new(BTreeMap::new());
    let case = std::cell::Cell::new(0);
    runner
        .run(
            &strategy,
            |((ns, nb, nr, np, nt), (c1, c2, c3, lat, ppc), links, tile)| {
                let mut a = ArchConfig::default();
                a.segmenter.count = ns;
                a.subsegmenter.count = nb;
                a.rasterizer.count = nr;
                a.rop.count = np;
                a.triangle_rasterizer.count = nt;
                a.segmenter.cycles_per_segment = c1;
                a.subsegmenter.cycles_per_subsegment = c2;
                a.interval_manager.cycles_per_scanline = c3;
                a.rasterizer.latency_cycles = lat;
                a.rop.latency_cycles = lat + 1;
                a.triangle_rasterizer.pixels_per_cycle = ppc;
                a.rop.tile_px = tile;
                for (c, (d, latency)) in a.links.all_mut().into_iter().zip(links) {
                    c.fifo_depth = d;
                    c.latency_cycles = latency;
                }
                a.validate("random").unwrap();
                let n = case.get();
                let mut got = got.borrow_mut();
                let lembo = run(&s, &a, false);
                let triangle = run(&s, &a, true);
                // The same reports whatever the host: units run in a seeded random order,
                // or partitioned at random over two to four host threads.
                let n64 = n as u64;
                let hosts = [
                    SimOptions {
                        perturb: Some(n64 + 1),
                        ..SimOptions::default()
                    },
                    SimOptions {
                        host_threads: 2 + n % 3,
                        partition_seed: Some(n64 + 7),
                        ..SimOptions::default()
                    },
                ];
                for o in &hosts {
                    prop_assert_eq!(&run_with(&s, &a, false, o), &lembo, "lembo path, {:?}", o);
                    prop_assert_eq!(
                        &run_with(&s, &a, true, o),
                        &triangle,
                        "triangle path, {:?}",
                        o
                    );
                }
                got.insert(format!("{n:03} lembo"), lembo);
                got.insert(format!("{n:03} triangle"), triangle);
                case.set(n + 1);
                Ok(())
            },
        )
        .unwrap();
    check("random.json", got.into_inner(), 400);
}
