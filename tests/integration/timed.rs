//! The timed pipeline against its contract (DESIGN.md §3, issue 3): timing never changes
//! pixels, results do not depend on the host schedule, every cycle is accounted once, and
//! deeper FIFOs and more units never make a frame slower where they should help.

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::frame::render_functional;
use lembo_sim::pipeline::SimOptions;
use lembo_sim::pipeline::{run_timed, Source, TimedFrame, UnitKind};
use lembo_sim::scene::Scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use crate::support::{arch, scenes};
use scenes::trace as scene;

fn timed(scene: &Scene, arch: &ArchConfig, options: &SimOptions) -> TimedFrame {
    let view = View::new(&scene.camera, scene.viewport);
    run_timed(
        scene,
        &view,
        0.5,
        Datapath::F32,
        arch,
        Source::Lembos,
        options,
    )
    .expect("timed run")
}

/// Every link of `a` set to `depth`.
fn with_depth(mut a: ArchConfig, depth: u32) -> ArchConfig {
    for c in a.links.all_mut() {
        c.fifo_depth = depth;
    }
    a
}

fn counts(a: &mut ArchConfig, ns: u32, nb: u32, nr: u32, np: u32) {
    a.segmenter.count = ns;
    a.subsegmenter.count = nb;
    a.rasterizer.count = nr;
    a.rop.count = np;
}

/// The configurations of the equivalence matrix: unit counts 1..8, FIFO depths 1..64.
fn matrix() -> Vec<ArchConfig> {
    let mut odd = with_depth(ArchConfig::default(), 7);
    counts(&mut odd, 3, 5, 2, 3);
    odd.links
        .get_mut(UnitKind::FragmentRasterizer, UnitKind::Rop)
        .fifo_depth = 2;
    let mut narrow_wide = with_depth(ArchConfig::default(), 1);
    counts(&mut narrow_wide, 1, 8, 1, 8);
    let mut wide_narrow = with_depth(ArchConfig::default(), 64);
    counts(&mut wide_narrow, 8, 1, 8, 1);
    wide_narrow.rop.tile_px = 3;
    vec![
        arch("baseline.json"),
        arch("minimal.json"),
        arch("wide.json"),
        odd,
        narrow_wide,
        wide_narrow,
    ]
}

fn assert_accounting(t: &TimedFrame) {
    for u in &t.cycles.units {
        assert_eq!(
            u.busy + u.starved + u.blocked,
            t.cycles.total,
            "busy + starved + blocked of {}",
            u.name
        );
    }
}

#[test]
fn timed_image_equals_functional_across_architectures() {
    for name in ["sphere24.json", "bunny.json"] {
        let s = scene(name, None);
        let view = View::new(&s.camera, s.viewport);
        let f = render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap();
        for a in matrix() {
            let t = timed(&s, &a, &SimOptions::default());
            assert!(
                t.framebuffer.color == f.framebuffer.color,
                "{name} on {}: image differs",
                a.name
            );
            assert_eq!(t.framebuffer.depth, f.framebuffer.depth, "{name} depth");
            assert_eq!(t.counts.fragments, f.counts.fragments);
            assert_eq!(t.counts.subsegments, f.counts.subsegments);
            assert_eq!(t.counts.intervals, f.counts.intervals);
            assert_accounting(&t);
            let units = a.units() as usize;
            assert_eq!(t.units.len(), units);
            let deepest = a
                .links
                .all()
                .iter()
                .map(|(_, l)| l.fifo_depth)
                .max()
                .unwrap();
            for u in &t.cycles.units {
                assert!(u.max_fifo_occupancy <= deepest as u64, "{}", u.name);
            }
        }
    }
}

#[test]
fn timed_results_do_not_depend_on_the_host_schedule() {
    let s = scene("sphere24.json", Some(256));
    let a = arch("wide.json");
    let first = timed(&s, &a, &SimOptions::default());
    // Units run in seeded random orders, or partitioned over 2 to 6 host threads, in
    // contiguous runs or at random.
    let runs = (1..=5)
        .map(|seed| SimOptions {
            perturb: Some(seed),
            ..SimOptions::default()
        })
        .chain((2..=6).map(|threads| SimOptions {
            host_threads: threads,
            ..SimOptions::default()
        }))
        .chain((1..=5).map(|seed| SimOptions {
            host_threads: 2 + seed as usize % 3,
            partition_seed: Some(seed),
            perturb: Some(seed),
            ..SimOptions::default()
        }));
    for options in runs {
        let t = timed(&s, &a, &options);
        assert_eq!(t.cycles, first.cycles, "cycles with {options:?}");
        assert_eq!(t.counts, first.counts);
        assert!(t.framebuffer.color == first.framebuffer.color);
    }
}

#[test]
fn one_entry_fifos_are_slower_than_deep_ones() {
    let s = scene("sphere24.json", Some(256));
    let shallow = timed(
        &s,
        &with_depth(ArchConfig::default(), 1),
        &SimOptions::default(),
    );
    let deep = timed(
        &s,
        &with_depth(ArchConfig::default(), 64),
        &SimOptions::default(),
    );
    // Strictly: one-entry FIFOs stall the sphere's bursts of intervals and spans, so a
    // model that ignored the depth would fail here.
    assert!(
        shallow.cycles.total > deep.cycles.total,
        "depth 1: {} cycles, depth 64: {}",
        shallow.cycles.total,
        deep.cycles.total
    );
}

#[test]
fn more_segmenters_help_when_the_segmenter_is_the_bottleneck() {
    let s = scene("sphere24.json", Some(256));
    let mut slow = ArchConfig::default();
    slow.segmenter.cycles_per_segment = 60;
    slow.segmenter.count = 1;
    let one = timed(&s, &slow, &SimOptions::default());
    assert_eq!(one.cycles.bottleneck.as_deref(), Some("Segmenter[0]"));
    slow.segmenter.count = 4;
    let four = timed(&s, &slow, &SimOptions::default());
    assert!(
        four.cycles.total < one.cycles.total,
        "4 segmenters: {}, 1: {}",
        four.cycles.total,
        one.cycles.total
    );
}

#[test]
fn a_timeline_is_written_on_request_and_bounded() {
    let s = scene("sphere24.json", Some(128));
    let options = SimOptions {
        trace: true,
        trace_event_cap: 2000,
        ..SimOptions::default()
    };
    let t = timed(&s, &ArchConfig::default(), &options);
    let v: serde_json::Value = serde_json::from_str(t.trace.as_deref().unwrap()).unwrap();
    let events = v["traceEvents"].as_array().unwrap();
    let x = events.iter().filter(|e| e["ph"] == "X").count();
    assert!(x > 0 && x <= 2000, "{x} events");
    assert_eq!(v["otherData"]["total_cycles"], t.cycles.total.0);
}

/// 200 random valid configurations (seeded) all finish, with the functional image.
#[test]
fn random_architectures_all_terminate_with_the_same_image() {
    let s = scene("sphere24.json", Some(40));
    let view = View::new(&s.camera, s.viewport);
    let f = render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap();
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 200,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[3; 32]),
    );
    let unit = 1u32..=8;
    let cost = 1u64..=20;
    let depth = prop_oneof![Just(1u32), 2u32..=8, Just(64)];
    let strategy = (
        (unit.clone(), unit.clone(), unit.clone(), unit),
        (cost.clone(), cost.clone(), cost.clone(), cost),
        proptest::collection::vec((depth, 1u64..=6), 7),
        1u32..=16,
    );
    runner
        .run(
            &strategy,
            |((ns, nb, nr, np), (c1, c2, c3, lat), links, tile)| {
                let mut a = ArchConfig::default();
                counts(&mut a, ns, nb, nr, np);
                a.segmenter.cycles_per_segment = c1;
                a.subsegmenter.cycles_per_subsegment = c2;
                a.interval_manager.cycles_per_scanline = c3;
                a.rasterizer.latency_cycles = lat;
                a.rop.tile_px = tile;
                // The lembo path's seven links come first in the graph's order.
                for (c, (d, latency)) in a.links.all_mut().into_iter().zip(links) {
                    c.fifo_depth = d;
                    c.latency_cycles = latency;
                }
                a.validate("random").unwrap();
                let t = timed(&s, &a, &SimOptions::default());
                prop_assert!(t.framebuffer.color == f.framebuffer.color);
                for u in &t.cycles.units {
                    prop_assert_eq!(u.busy + u.starved + u.blocked, t.cycles.total);
                }
                Ok(())
            },
        )
        .unwrap();
}

/// A replicated front end (MinMax and IntervalManager counts above 1) draws the same pixels
/// as the functional model, deals whole lembos round-robin (each instance takes every n-th
/// piece, so their item counts differ by at most one), names its instances `Kind[i]`, and
/// on a scene bound by the single interval manager (the bunny) takes fewer cycles.
#[test]
fn a_replicated_front_end_deals_whole_lembos_and_draws_the_same_pixels() {
    let bunny = scene("bunny.json", None);
    let view = View::new(&bunny.camera, bunny.viewport);
    let functional = render_functional(&bunny, &view, 0.5, Datapath::F32, false).unwrap();
    let options = SimOptions::default();
    let mut last = u64::MAX;
    for n in [1, 2, 4] {
        let mut a = ArchConfig::default();
        a.minmax.count = n.min(2);
        a.interval_manager.count = n;
        let t = timed(&bunny, &a, &options);
        assert!(
            t.framebuffer.color == functional.framebuffer.color,
            "n = {n}"
        );
        let ims: Vec<_> = t
            .cycles
            .units
            .iter()
            .filter(|u| u.kind == UnitKind::IntervalManager)
            .collect();
        assert_eq!(ims.len() as u32, n);
        let names: Vec<&str> = ims.iter().map(|u| u.name.as_str()).collect();
        if n == 1 {
            assert_eq!(names, ["IntervalManager"]);
        } else {
            assert_eq!(names[1], "IntervalManager[1]");
        }
        let (lo, hi) = ims.iter().fold((u64::MAX, 0), |(lo, hi), u| {
            (lo.min(u.items_in), hi.max(u.items_in))
        });
        assert!(hi - lo <= 1, "n = {n}: {lo}..{hi}");
        assert!(
            t.cycles.total.0 < last,
            "n = {n}: {} cycles",
            t.cycles.total
        );
        last = t.cycles.total.0;
    }
}

/// `counts` without `fragments_passed_depth`, which depends on the order fragments reach a
/// pixel (DESIGN.md §3: the image does not).
fn order_free(counts: &lembo_sim::raster::Counts) -> lembo_sim::raster::Counts {
    lembo_sim::raster::Counts {
        fragments_passed_depth: 0,
        ..*counts
    }
}

/// Replicated setup engines (`setup.count`, `triangle_setup.count`), each dealt batches of
/// primitives in submission order, draw the functional model's pixels with the same counts
/// on both paths whatever the count and batch; each triangle engine is busy exactly one
/// cycle for each triangle of its batches, and where setup bounds the frame (the triangle
/// path at n = 4) more engines take fewer cycles.
#[test]
fn replicated_setup_engines_deal_batches_and_draw_the_same_pixels() {
    use lembo_sim::frame::render_functional_triangles;
    use lembo_sim::lembo::tessellate::Tessellation;
    let s = scene("bunny.json", Some(256));
    let view = View::new(&s.camera, s.viewport);
    let options = SimOptions::default();
    // The lembo path.
    let functional = render_functional(&s, &view, 0.5, Datapath::F32, false).unwrap();
    let mut base = None;
    for (n, batch) in [(1, 32), (2, 32), (3, 1), (4, 7)] {
        let mut a = ArchConfig::default();
        a.setup.count = n;
        a.setup.batch = batch;
        a.validate("setup engines").unwrap();
        let t = timed(&s, &a, &options);
        assert!(
            t.framebuffer.color == functional.framebuffer.color,
            "lembo, {n} setups"
        );
        assert_eq!(t.framebuffer.depth, functional.framebuffer.depth);
        assert_eq!(t.counts.fragments, functional.counts.fragments);
        assert_eq!(t.counts.lembos, s.lembos().count() as u64);
        let base = base.get_or_insert(t.counts);
        assert_eq!(
            order_free(&t.counts),
            order_free(base),
            "lembo path counts, {n} setups, batch {batch}"
        );
        assert_accounting(&t);
        let setups: Vec<_> = t
            .cycles
            .units
            .iter()
            .filter(|u| u.kind == UnitKind::Setup)
            .collect();
        assert_eq!(setups.len() as u32, n);
        if n > 1 {
            assert_eq!(setups[1].name, "Setup[1]");
        }
    }
    // The triangle path: setup is the bottleneck at n = 4 with one engine.
    let tess = Tessellation::new(s.lembo_sets(), 4);
    let functional = render_functional_triangles(&s, &view, &tess, Datapath::F32, false);
    let run = |a: &ArchConfig| {
        run_timed(
            &s,
            &view,
            0.5,
            Datapath::F32,
            a,
            Source::Triangles(&tess),
            &options,
        )
        .expect("timed triangles")
    };
    let mut one = ArchConfig::default();
    one.triangle_rasterizer.count = 4;
    // A port wide enough for the mesh's reads, so that the engines bound the frame.
    one.framebuffer.bytes_per_cycle = 256;
    let single = run(&one);
    assert_eq!(single.cycles.bottleneck.as_deref(), Some("TriangleSetup"));
    for (n, batch) in [(2, 32), (4, 32), (4, 16), (3, 100)] {
        let mut a = one.clone();
        a.triangle_setup.count = n;
        a.triangle_setup.batch = batch;
        a.validate("triangle setup engines").unwrap();
        let t = run(&a);
        assert!(
            t.framebuffer.color == functional.framebuffer.color,
            "triangles, {n} setups"
        );
        assert_eq!(t.framebuffer.depth, functional.framebuffer.depth);
        assert_eq!(
            order_free(&t.counts),
            order_free(&single.counts),
            "triangle counts, {n} setups, batch {batch}"
        );
        assert_accounting(&t);
        let setups: Vec<_> = t
            .cycles
            .units
            .iter()
            .filter(|u| u.kind == UnitKind::TriangleSetup)
            .collect();
        assert_eq!(setups.len() as u32, n);
        assert_eq!(setups[0].name, "TriangleSetup[0]");
        // Every triangle is set up by exactly one engine, each its own batches.
        assert_eq!(t.counts.triangles_clipped, 0);
        let triangles = tess.lembos() as u64 * tess.triangles_per_lembo();
        let batches = triangles.div_ceil(batch as u64);
        for (i, u) in setups.iter().enumerate() {
            let mine = (0..batches)
                .filter(|b| b % n as u64 == i as u64)
                .map(|b| (triangles - b * batch as u64).min(batch as u64))
                .sum::<u64>();
            // One cycle a triangle, culled or not (nothing is clipped here).
            assert_eq!(u.busy.0, mine, "{}", u.name);
        }
        // Setup divides among the engines until it is no longer what bounds the frame.
        let setup_bound = t
            .cycles
            .bottleneck
            .as_deref()
            .is_some_and(|b| b.starts_with("TriangleSetup"));
        assert!(
            !setup_bound || t.cycles.total.0 * n as u64 <= single.cycles.total.0 * 105 / 100,
            "{n} setups: {} cycles against {} with one",
            t.cycles.total,
            single.cycles.total
        );
        // Beyond that the memory port bounds it (the ROPs' spans, a cycle each at least,
        // and the mesh's reads): about two thirds of the single engine's frame.
        assert!(
            t.cycles.total.0 * 10 <= single.cycles.total.0 * 7,
            "{n} setups: {}",
            t.cycles.total
        );
    }
}

/// The triangle path's two sources (DESIGN.md §5): a mesh in memory read through the
/// setup engines' vertex caches, and the lembos tessellated on chip by Tessellator and
/// DomainEval units, draw the same pixels with the same counts. The fetch reads 12 bytes
/// a triangle and 24 a vertex miss from memory, 144 a lembo on chip; the on-chip units
/// are busy for each lembo's n² triangles and (n + 1)(n + 2)/2 points; the memory port
/// is busy for the fetch's reads as well as the ROPs'.
#[test]
fn both_triangle_sources_draw_the_same_pixels_and_account_their_work() {
    use lembo_sim::graph::TessSource;
    use lembo_sim::lembo::tessellate::Tessellation;
    let s = scene("bunny.json", Some(128));
    let view = View::new(&s.camera, s.viewport);
    let n = 3u64;
    let tess = Tessellation::new(s.lembo_sets(), n as u32);
    let lembos = tess.lembos() as u64;
    let triangles = tess.len();
    let run = |a: &ArchConfig| {
        run_timed(
            &s,
            &view,
            0.5,
            Datapath::F32,
            a,
            Source::Triangles(&tess),
            &SimOptions::default(),
        )
        .expect("timed triangles")
    };
    let busy = |t: &TimedFrame, kind: UnitKind| -> u64 {
        t.cycles
            .units
            .iter()
            .filter(|u| u.kind == kind)
            .map(|u| u.busy.0)
            .sum()
    };
    let memory = run(&ArchConfig::default());
    let fetch = memory.fetch.unwrap();
    assert_eq!(fetch.source, "memory");
    let cache = fetch.vertex_cache.unwrap();
    assert_eq!(cache.hits + cache.misses, 3 * triangles);
    assert!(
        cache.misses >= tess.vertex_count(),
        "each vertex missed once at least"
    );
    assert_eq!(fetch.bytes, 12 * triangles + 24 * cache.misses);
    // A larger cache misses less, down to the mesh's own vertices.
    let mut big = ArchConfig::default();
    big.tessellation.vertex_cache_entries = 4096;
    let big = run(&big).fetch.unwrap().vertex_cache.unwrap();
    assert!(big.misses < cache.misses, "{big:?} against {cache:?}");
    for onchip in [1, 3] {
        let mut a = ArchConfig::default();
        a.tessellation.source = TessSource::OnChip;
        a.tessellator.count = onchip;
        a.domain_eval.count = onchip;
        a.triangle_setup.count = 2;
        a.validate("on chip").unwrap();
        let t = run(&a);
        assert!(
            t.framebuffer.color == memory.framebuffer.color,
            "{onchip} units"
        );
        assert_eq!(t.framebuffer.depth, memory.framebuffer.depth);
        assert_eq!(order_free(&t.counts), order_free(&memory.counts));
        assert_accounting(&t);
        let fetch = t.fetch.unwrap();
        assert_eq!((fetch.source, fetch.bytes), ("onchip", 144 * lembos));
        assert!(fetch.vertex_cache.is_none());
        assert_eq!(busy(&t, UnitKind::Tessellator), lembos * n * n);
        // Each patch's points, spent over its batches (at least a cycle each).
        let points = lembos * (n + 1) * (n + 2) / 2;
        let evaluated = busy(&t, UnitKind::DomainEval);
        assert!(
            (points..=points + lembos).contains(&evaluated),
            "{evaluated} cycles for {points} points"
        );
        assert_eq!(
            t.cycles
                .units
                .iter()
                .filter(|u| u.kind == UnitKind::Tessellator)
                .count(),
            onchip as usize
        );
        // One memory port.
        assert!(
            busy(&t, UnitKind::FrameBuffer) >= busy(&t, UnitKind::GeometryFetch),
            "the port's busy cycles include the fetch's"
        );
        assert!(t.cycles.total.0 >= busy(&t, UnitKind::FrameBuffer));
    }
}

/// Issue 35's target: the bunny at n = 16 (512x512) on `sim/arch/gpu.json` (4 triangle
/// setup engines culling 2 triangles a cycle, 4 triangle rasterizers, the lembos
/// tessellated on chip by 4 Tessellators and 4 DomainEvals) takes at most a third of the
/// 940 570 cycles one setup engine took with the mesh free, and setup does not bound it.
#[test]
fn on_chip_tessellation_frees_the_triangle_front_end() {
    use lembo_sim::lembo::tessellate::Tessellation;
    let s = scene("bunny.json", Some(512));
    let view = View::new(&s.camera, s.viewport);
    let tess = Tessellation::new(s.lembo_sets(), 16);
    let gpu = arch("gpu.json");
    let t = run_timed(
        &s,
        &view,
        0.5,
        Datapath::F32,
        &gpu,
        Source::Triangles(&tess),
        &SimOptions::default(),
    )
    .unwrap();
    assert!(
        t.cycles.total.0 * 3 <= 940_570,
        "{} cycles, bottleneck {:?}",
        t.cycles.total,
        t.cycles.bottleneck
    );
    let bottleneck = t.cycles.bottleneck.unwrap();
    assert!(!bottleneck.starts_with("TriangleSetup"), "{bottleneck}");
}
