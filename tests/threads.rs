//! `--threads N` (raster::parallel): a functional frame drawn on N host threads is the
//! single-threaded frame bit for bit (colour, depth, winner ids) with the same counts, on
//! every surface scene shipped and the extremes, both paths and both datapaths.

use lembo_sim::camera::View;
use lembo_sim::datapath::Datapath;
use lembo_sim::lembo::tessellate::Tessellation;
use lembo_sim::raster::{render_functional_on, Frame, PerspectiveTol};
use lembo_sim::scene::Scene;
use std::path::Path;

fn scenes() -> Vec<Scene> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("traces");
    let mut files: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .chain(std::fs::read_dir(root.join("extremes")).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .filter(|p| p.file_name().is_some_and(|n| n != "expect.json"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| Scene::load(f).unwrap_or_else(|e| panic!("{e}")))
        .filter(|s| s.discoid_count() == 0)
        .map(|mut s| {
            // Odd sizes: bands of unequal height, a last band of one row.
            s.set_viewport(203, 157).unwrap();
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
    let scenes = scenes();
    assert!(scenes.len() > 15, "the shipped scenes and the extremes");
    for scene in &scenes {
        let view = View::new(&scene.camera, scene.viewport);
        let tol = PerspectiveTol::FollowK.with_k(0.5);
        let tess = Tessellation::new(scene, 2);
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
