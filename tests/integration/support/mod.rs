//! What several test modules share: running the binary, golden files, the shipped scenes and
//! architectures, a render job to vary, a fragment count per pixel and the triangle path's
//! fan count.

pub mod binary;
pub mod golden;
pub mod scenes;

use lembo_sim::camera::View;
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::{Datapath, Real};
use lembo_sim::discoid::blend::BlendMode;
use lembo_sim::job::{Mode, PrimitivePath, RenderJob};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::raster::fragment::FragmentSink;
use lembo_sim::raster::setup::ScreenLembo;
use lembo_sim::raster::subsegmenter::Subsegment;
use lembo_sim::raster::triangle::{setup, TriangleSource};
use lembo_sim::scene::Scene;
use std::path::Path;

/// The shipped architecture `sim/arch/<name>`.
pub fn arch(name: &str) -> ArchConfig {
    ArchConfig::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("sim/arch")
            .join(name),
    )
    .unwrap()
}

/// A functional render of the embedded default scene at `k` on `datapath`: the lembo path,
/// no reference, one host thread, every other setting at its default. A test sets what it
/// varies over this with `..render_job(k, datapath)`.
pub fn render_job(k: f64, datapath: Datapath) -> RenderJob {
    RenderJob {
        trace: Default::default(),
        scene: None,
        out: None,
        k,
        perspective_tol: Default::default(),
        datapath,
        reference: false,
        supersample: 1,
        samples: Default::default(),
        flip_ppd: Default::default(),
        viewport: None,
        mode: Mode::Functional,
        arch: None,
        arch_set: Vec::new(),
        trace_out: None,
        tech: None,
        path: PrimitivePath::Lembo,
        tess: None,
        blend: BlendMode::Rgba8,
        threshold: None,
        host_threads: 1,
        threads: None,
        given: Default::default(),
        no_memory_check: false,
    }
}

/// Counts every fragment per pixel of a frame, before any depth test.
pub struct Hits {
    width: u32,
    /// Fragments per pixel, row by row.
    pub count: Vec<u32>,
}

impl Hits {
    /// No fragment yet on a `width` x `height` frame.
    pub fn new(width: u32, height: u32) -> Self {
        Hits {
            width,
            count: vec![0; (width * height) as usize],
        }
    }
}

impl<R: Real> FragmentSink<R> for Hits {
    fn fragment(
        &mut self,
        _: &ScreenLembo<R>,
        _: &Subsegment<R>,
        i: u32,
        j: u32,
        _: R,
        _: R,
        _: R,
    ) {
        self.count[(j * self.width + i) as usize] += 1;
    }
}

/// Triangles in the fans of the scene's clipped triangles at tessellation level `n`.
pub fn fans<R: Real>(s: &Scene, n: u32, view: &View) -> u64 {
    let t = Tessellation::new(s.lembo_sets(), n);
    let (mut tris, mut pieces, mut fan) = (Vec::new(), Vec::new(), 0);
    for c in 0..t.chunks() {
        t.chunk(c, &mut tris);
        for (k, tr) in tris.iter().enumerate() {
            let id = t.id(c, k);
            let o = setup::<R>(id, &tr.positions, &tr.normals, tr.color, view, &mut pieces);
            fan += o.fan as u64;
        }
    }
    fan
}

/// Whether the long checks run (`LEMBO_FULL_CHECKS=1`): the full answer sweep and the
/// whole design-point calibration set, too long for every test run (README.md, "Tests").
pub fn full_checks() -> bool {
    std::env::var_os("LEMBO_FULL_CHECKS").is_some_and(|v| v == "1")
}

/// A part of a test that this machine cannot run, said on standard error; under CI (`CI`
/// set, as `.ci/run` sets it) the test fails instead, since CI's machines can run it.
pub fn skip_part(what: &str) {
    assert!(
        std::env::var_os("CI").is_none(),
        "{what}: CI's machines can run this part, so it fails here instead of skipping"
    );
    eprintln!("skipped {what}");
}

/// The step of .ci/run that sets `LEMBO_EXPECT_DEBUG_ASSERTIONS=1` runs with debug
/// assertions on (the `debug_assert!`s of the runtime and the stages are compiled in), as
/// it says; the release suite, which does not set it, compiles them out.
#[test]
// The assertion is constant per build: that is what it checks.
#[allow(clippy::assertions_on_constants)]
fn debug_assertions_are_on_where_ci_expects_them() {
    if std::env::var_os("LEMBO_EXPECT_DEBUG_ASSERTIONS").is_some_and(|v| v == "1") {
        assert!(
            cfg!(debug_assertions),
            "this step was built without debug assertions"
        );
    }
}

/// `counts` as JSON without the back-face culling counters when they are 0: the goldens
/// were recorded before culling was modelled, and a run that culls nothing (culling off)
/// must still match them exactly.
pub fn counts_before_culling(counts: &impl serde::Serialize) -> String {
    // On the text, so that the fields keep their order.
    serde_json::to_string(counts)
        .unwrap()
        .replace(",\"lembos_culled_backface\":0", "")
        .replace(",\"triangles_culled_backface\":0", "")
}

/// Removes the back-face culling counters from a report's `counts` object when they are 0.
pub fn strip_zero_culling(counts: &mut serde_json::Value) {
    let map = counts.as_object_mut().expect("counts are an object");
    for key in ["lembos_culled_backface", "triangles_culled_backface"] {
        if map.get(key).and_then(|v| v.as_u64()) == Some(0) {
            map.remove(key);
        }
    }
}

/// An architecture file's text that turns back-face culling off on both paths, for runs
/// that must reproduce what was recorded before culling was modelled.
pub const NO_CULLING: &str =
    r#"{"minmax": {"cull_backfaces": "off"}, "triangle_setup": {"cull_backfaces": "off"}}"#;
