//! Tests of the functional frame that reach both the rasterizer's internals and the ROP:
//! they sit here, above both.

use crate::camera::View;
use crate::datapath::Real;
use crate::raster::counts::Counts;
use crate::raster::driver::{self, Stages};
use crate::raster::triangle::{self, TrianglePath, TriangleSource};
use crate::rop::{FrameBuffer, RopSink};
use crate::scene::Scene;

/// The shipped scene at `path` (from the crate's root) on a `width` x `height` viewport,
/// and its view.
pub(super) fn shipped_at(path: &str, width: u32, height: u32) -> (Scene, View) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    let mut scene = Scene::load(&path).expect("a shipped scene");
    scene.set_viewport(width, height).expect("a valid viewport");
    let view = View::new(&scene.camera, scene.viewport);
    (scene, view)
}

/// The shipped scene at `path` on a 384x384 viewport, and its view.
fn shipped(path: &str) -> (Scene, View) {
    shipped_at(path, 384, 384)
}

/// The triangle path's rows as dispatched (compiled for AVX2 where the CPU has it) draw
/// the frame and counts of the rows compiled for the baseline instruction set, bit for
/// bit, through the functional ROP, for the bunny tessellated once and twice, in both
/// datapaths.
fn triangle_rows_as_compiled<R: Real>(level: u32) {
    if !crate::isa::avx2_comparable("the AVX2 triangle rows") {
        return;
    }
    // Under Miri, which checks the AVX2 call's unsafe block, the default scene (24 lembos)
    // on a small viewport suffices.
    let (scene, view, size) = match cfg!(miri) {
        true => {
            let (scene, view) = shipped_at("traces/default.json", 48, 48);
            (scene, view, 48)
        }
        false => {
            let (scene, view) = shipped("traces/bunny.json");
            (scene, view, 384)
        }
    };
    let tessellation = crate::lembo::tessellate::Tessellation::new(scene.lembo_sets(), level);
    let source: &dyn TriangleSource = &tessellation;
    let [dispatched, compiled] = [true, false].map(|dispatched| {
        let mut fb = FrameBuffer::new(size, size, [0; 3], false);
        let mut counts = Counts::default();
        let mut rop = RopSink::<R>::new(&mut fb, &scene.light, &view);
        let path = TrianglePath::new(source, &view);
        let all = 0..Stages::<R>::primitives(&path);
        let mut pieces = Vec::new();
        driver::set_up(
            &path,
            all,
            &mut Default::default(),
            &mut pieces,
            |_, _| {},
            &mut counts,
        );
        for st in &pieces {
            if dispatched {
                triangle::rasterize::rasterize_rows(st, 0, size, &mut rop, &mut counts);
            } else {
                triangle::rasterize::rasterize_rows_as_compiled(st, 0, size, &mut rop, &mut counts);
            }
        }
        (counts.fragments_passed_depth, counts.pixels_covered) = rop.finish();
        (fb, counts)
    });
    let least = if cfg!(miri) { 100 } else { 10_000 };
    assert!(dispatched.1.fragments > least, "{}", dispatched.1.fragments);
    assert_eq!(dispatched.1, compiled.1);
    let bits = |fb: &FrameBuffer| -> Vec<u32> { fb.depth.iter().map(|d| d.to_bits()).collect() };
    assert!(
        bits(&dispatched.0) == bits(&compiled.0),
        "the depths differ"
    );
    assert!(
        dispatched.0.primitive[..] == compiled.0.primitive[..],
        "the winners differ"
    );
    assert!(
        dispatched.0.color[..] == compiled.0.color[..],
        "the colours differ"
    );
}

#[test]
fn triangle_rows_compiled_for_avx2_give_the_same_bits() {
    for level in if cfg!(miri) { 1..=1 } else { 1..=2 } {
        triangle_rows_as_compiled::<f32>(level);
        triangle_rows_as_compiled::<f64>(level);
    }
}
