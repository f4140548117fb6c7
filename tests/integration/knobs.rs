//! The sensitivity study's knobs (issue 48, item 7): each one halved and doubled moves the
//! cycles, bytes or energy it models by the amount its cost model says, on a small case,
//! and never a pixel. Their defaults reproducing today's figures exactly is the golden
//! tests' part (`cycles_golden`, `golden`).

use lembo_sim::camera::View;
use lembo_sim::config::{ArchConfig, Ratio};
use lembo_sim::datapath::Datapath;
use lembo_sim::graph::TessSource;
use lembo_sim::job::{run_path, Mode, Model, PrimitivePath, RenderJob};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::pipeline::{run_timed, SimOptions, Source, TimedFrame, UnitKind};
use lembo_sim::scene::Scene;

use crate::support::{render_job, scenes};

fn ratio(x: f64) -> Ratio {
    serde_json::from_value(serde_json::json!(x)).unwrap()
}

fn sphere() -> Scene {
    scenes::trace("sphere24.json", Some(64))
}

fn busy(t: &TimedFrame, kind: UnitKind) -> u64 {
    t.cycles
        .units
        .iter()
        .filter(|u| u.kind == kind)
        .map(|u| u.busy.0)
        .sum()
}

fn lembos(s: &Scene, a: &ArchConfig) -> TimedFrame {
    let a = checked(a);
    let view = View::new(&s.camera, s.viewport);
    run_timed(
        s,
        &view,
        0.5,
        Datapath::F32,
        &a,
        Source::Lembos,
        &SimOptions::default(),
    )
    .expect("timed lembos")
}

fn triangles(s: &Scene, tess: &Tessellation, a: &ArchConfig) -> TimedFrame {
    let a = checked(a);
    let view = View::new(&s.camera, s.viewport);
    run_timed(
        s,
        &view,
        0.5,
        Datapath::F32,
        &a,
        Source::Triangles(tess),
        &SimOptions::default(),
    )
    .expect("timed triangles")
}

fn checked(a: &ArchConfig) -> ArchConfig {
    a.validate("knob").unwrap();
    a.clone()
}

fn same_image(a: &TimedFrame, b: &TimedFrame, what: &str) {
    assert!(a.framebuffer.color == b.framebuffer.color, "{what}");
    assert_eq!(a.framebuffer.depth, b.framebuffer.depth, "{what}");
}

/// `rop.fragments_per_cycle`: a span of n fragments costs ceil(n / rate), so at the
/// default 1 the ROPs are busy a cycle a fragment, at 0.5 exactly two, at 2 about half.
#[test]
fn knob_rop_rate_halved_and_doubled() {
    let s = sphere();
    let base = lembos(&s, &ArchConfig::default());
    let fragments = base.counts.fragments;
    assert!(fragments > 100);
    assert_eq!(busy(&base, UnitKind::Rop), fragments);
    let mut half = ArchConfig::default();
    half.rop.fragments_per_cycle = ratio(0.5);
    let half = lembos(&s, &half);
    same_image(&half, &base, "half rate");
    assert_eq!(busy(&half, UnitKind::Rop), 2 * fragments);
    assert!(half.cycles.total > base.cycles.total);
    let mut double = ArchConfig::default();
    double.rop.fragments_per_cycle = ratio(2.0);
    let double = lembos(&s, &double);
    same_image(&double, &base, "double rate");
    let rop = busy(&double, UnitKind::Rop);
    assert!(
        (fragments / 2..fragments).contains(&rop),
        "{rop} cycles for {fragments} fragments"
    );
}

/// `tessellator.cycles_per_triangle` and `domain_eval.cycles_per_vertex` on chip at n = 3:
/// a lembo's 9 triangles take ceil(9 c) cycles and its 10 points (one batch of 32
/// triangles holds the lembo) ceil(10 c).
#[test]
fn knob_onchip_rates_halved_and_doubled() {
    let s = sphere();
    let tess = Tessellation::new(s.lembo_sets(), 3);
    let lembos = tess.lembos() as u64;
    let mut a = ArchConfig::default();
    a.tessellation.source = TessSource::OnChip;
    let base = triangles(&s, &tess, &a);
    assert_eq!(busy(&base, UnitKind::Tessellator), 9 * lembos);
    assert_eq!(busy(&base, UnitKind::DomainEval), 10 * lembos);
    for (c, per_lembo) in [(0.5, (5, 5)), (2.0, (18, 20))] {
        let mut b = a.clone();
        b.tessellator.cycles_per_triangle = ratio(c);
        b.domain_eval.cycles_per_vertex = ratio(c);
        let t = triangles(&s, &tess, &b);
        same_image(&t, &base, "on-chip rates");
        assert_eq!(busy(&t, UnitKind::Tessellator), per_lembo.0 * lembos, "{c}");
        assert_eq!(busy(&t, UnitKind::DomainEval), per_lembo.1 * lembos, "{c}");
    }
}

/// `fetch.bytes_per_lembo`: the fetch reads that many bytes a lembo, in batches of
/// `setup.batch` at 64 bytes a cycle; the report's `primitives.bytes` and the cost's
/// `geometry_bytes` are the same bytes, and the fetch's DRAM energy moves with them.
#[test]
fn knob_lembo_bytes_halved_and_doubled() {
    let s = sphere();
    let n = s.lembos().count() as u64;
    let job = RenderJob {
        trace: Default::default(),
        mode: Mode::Timed,
        path: PrimitivePath::Lembo,
        ..render_job(0.5, Datapath::F32)
    };
    let view = View::new(&s.camera, s.viewport);
    let mut energy = Vec::new();
    for bytes in [72, 144, 288] {
        let mut a = ArchConfig::default();
        a.fetch.bytes_per_lembo = bytes;
        let t = lembos(&s, &a);
        assert_eq!(t.fetch.unwrap().bytes, n * bytes);
        let batches = (0..n).step_by(32).map(|f| (n - f).min(32));
        let want: u64 = batches.map(|k| (k * bytes).div_ceil(64)).sum();
        assert_eq!(busy(&t, UnitKind::GeometryFetch), want, "{bytes} bytes");
        let run = run_path(&job, &s, &view, Model::Timed(&a), None).unwrap();
        assert_eq!(run.report.primitives.bytes, n * bytes);
        let cost = run.report.cost.unwrap();
        assert_eq!(cost.geometry_bytes, n * bytes);
        let fetch = cost
            .units
            .iter()
            .find(|u| u.name == "GeometryFetch")
            .unwrap();
        energy.push((fetch.energy_pj, cost.geometry_bytes));
    }
    // The fetch's energy grows with its bytes (its FIFO traffic is the same batches).
    assert!(energy.windows(2).all(|w| w[0].0 < w[1].0), "{energy:?}");
}

/// `fetch.bytes_per_vertex`, `fetch.index_bytes_per_triangle` and
/// `tessellation.vertex_cache_entries` on a mesh in memory: the fetch reads each
/// triangle's indices and each vertex its cache misses at those sizes; a smaller cache
/// misses more, a larger one less.
#[test]
fn knob_mesh_bytes_and_vertex_cache_halved_and_doubled() {
    let s = sphere();
    let tess = Tessellation::new(s.lembo_sets(), 4);
    let tris = tess.len();
    let base = triangles(&s, &tess, &ArchConfig::default());
    let misses = base.fetch.unwrap().vertex_cache.unwrap().misses;
    assert_eq!(base.fetch.unwrap().bytes, 12 * tris + 24 * misses);
    for (vertex, index) in [(12, 6), (48, 24)] {
        let mut a = ArchConfig::default();
        a.fetch.bytes_per_vertex = vertex;
        a.fetch.index_bytes_per_triangle = index;
        let t = triangles(&s, &tess, &a);
        same_image(&t, &base, "mesh bytes");
        let fetch = t.fetch.unwrap();
        assert_eq!(fetch.vertex_cache.unwrap().misses, misses);
        assert_eq!(fetch.bytes, index * tris + vertex * misses);
    }
    let mut by_entries = Vec::new();
    for entries in [16, 32, 64] {
        let mut a = ArchConfig::default();
        a.tessellation.vertex_cache_entries = entries;
        let t = triangles(&s, &tess, &a);
        same_image(&t, &base, "vertex cache");
        let fetch = t.fetch.unwrap();
        let cache = fetch.vertex_cache.unwrap();
        assert_eq!(cache.entries, entries);
        assert_eq!(fetch.bytes, 12 * tris + 24 * cache.misses);
        by_entries.push(cache.misses);
    }
    assert_eq!(by_entries[1], misses);
    assert!(
        by_entries[0] > by_entries[1] && by_entries[1] >= by_entries[2],
        "{by_entries:?}"
    );
}

/// `framebuffer.access_cycles`: halved, a small access takes half a cycle and two share a
/// cycle; doubled, every access takes two cycles at least. The port's busy cycles move
/// accordingly, the bytes do not, and neither does a pixel.
#[test]
fn knob_port_access_cost_halved_and_doubled() {
    let s = sphere();
    let base = lembos(&s, &ArchConfig::default());
    let port = |t: &TimedFrame| busy(t, UnitKind::FrameBuffer);
    let at = |slot: f64| {
        let mut a = ArchConfig::default();
        a.framebuffer.access_cycles = ratio(slot);
        lembos(&s, &a)
    };
    let (half, double) = (at(0.5), at(2.0));
    for t in [&half, &double] {
        same_image(t, &base, "access cycles");
        assert_eq!(t.fetch.unwrap().bytes, base.fetch.unwrap().bytes);
        assert_eq!(t.counts.fragments, base.counts.fragments);
        assert!(t.cycles.total.0 >= port(t));
    }
    assert!(port(&half) < port(&base), "{} {}", port(&half), port(&base));
    assert!(
        port(&double) > port(&base),
        "{} {}",
        port(&double),
        port(&base)
    );
    // Every access (the fetch's batches and the ROPs' bursts) takes whole two-cycle slots.
    assert_eq!(port(&double) % 2, 0);
    // Each access's whole slots: ceil(b / 128) two-cycle slots are at most twice
    // ceil(b / 64) cycles, and ceil(b / 32) half-cycle slots at least half of them.
    assert!(port(&double) <= 2 * port(&base));
    assert!(2 * port(&half) >= port(&base));
}
