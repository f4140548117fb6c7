//! `--threads N` (frame::bands): a functional frame drawn on N host threads is the
//! single-threaded frame bit for bit (colour, depth, winner ids) with the same counts, on
//! every surface scene shipped and the extremes, both paths and both datapaths. And the
//! ROP's shading in batches of lanes (`rop::lanes`) gives the frame that shading one
//! fragment at a time gives (the probed run of `--reference` hands the ROP its fragments one
//! by one).

use lembo_sim::camera::View;
use lembo_sim::datapath::Datapath;
use lembo_sim::frame::{render_functional_on, Frame};
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::scene::Scene;
use lembo_sim::tolerance::PerspectiveTol;

use crate::support::scenes;

/// Every surface scene, at 203 x 157 (odd sizes: bands of unequal height, a last band of
/// one row) or at its own viewport.
fn scenes(small: bool) -> Vec<Scene> {
    scenes::shipped_files()
        .iter()
        .map(|(_, f)| Scene::load(f).unwrap_or_else(|e| panic!("{e}")))
        .filter(|s| s.discoid_count() == 0)
        .map(|mut s| {
            if small {
                s.set_viewport(203, 157).unwrap();
            }
            s
        })
        .collect()
}

fn same(a: &Frame, b: &Frame, what: &str) {
    assert_eq!(a.counts, b.counts, "{what}: counts");
    assert!(a.framebuffer.color == b.framebuffer.color, "{what}: colour");
    assert!(
        a.framebuffer.primitive == b.framebuffer.primitive,
        "{what}: winners"
    );
    let bits = |f: &Frame| {
        f.framebuffer
            .depth
            .iter()
            .map(|d| d.to_bits())
            .collect::<Vec<_>>()
    };
    assert!(bits(a) == bits(b), "{what}: depth");
}

#[test]
fn every_thread_count_draws_the_single_threaded_frame() {
    let scenes = scenes(true);
    assert!(scenes.len() > 15, "the shipped scenes and the extremes");
    for scene in &scenes {
        let view = View::new(&scene.camera, scene.viewport);
        let tol = PerspectiveTol::FollowK.with_k(0.5);
        let tess = Tessellation::new(scene.lembo_sets(), 2);
        for datapath in [Datapath::F32, Datapath::F64] {
            for triangles in [false, true] {
                let source = triangles.then_some(&tess as _);
                let draw = |n| {
                    render_functional_on(scene, &view, tol, source, datapath, false, n)
                        .unwrap_or_else(|e| panic!("{}: {e}", scene.name))
                };
                let one = draw(1);
                for n in [2, 3, 8] {
                    let what = format!(
                        "{} {datapath:?} triangles={triangles} threads={n}",
                        scene.name
                    );
                    same(&one, &draw(n), &what);
                }
            }
        }
    }
}

#[test]
fn shading_in_batches_draws_what_shading_one_fragment_at_a_time_draws() {
    // At their own viewports: at 203 x 157 no piece of a clipped triangle covers a pixel.
    for scene in &scenes(false) {
        let view = View::new(&scene.camera, scene.viewport);
        let tol = PerspectiveTol::FollowK.with_k(0.5);
        // Level 1: large triangles, which the near plane clips into pieces that cover
        // pixels (inside_mesh.json).
        let tess = [1, 2].map(|n| Tessellation::new(scene.lembo_sets(), n));
        for datapath in [Datapath::F32, Datapath::F64] {
            for source in [None, Some(&tess[0] as _), Some(&tess[1] as _)] {
                let triangles = source.is_some();
                let draw = |one_by_one| {
                    render_functional_on(scene, &view, tol, source, datapath, one_by_one, 1)
                        .unwrap_or_else(|e| panic!("{}: {e}", scene.name))
                };
                let (batched, alone) = (draw(false), draw(true));
                let what = format!("{} {datapath:?} triangles={triangles}", scene.name);
                assert!(alone.probe.is_some(), "{what}: the probed run");
                let mut alone = alone;
                alone.framebuffer.normal = None;
                alone.probe = None;
                same(&batched, &alone, &what);
            }
        }
    }
}
