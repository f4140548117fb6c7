//! Back-face culling (DESIGN.md §5, "Back-face culling"), both paths: on every shipped
//! scene the default architecture culls (`auto`: closed, consistently oriented meshes, whole
//! beyond the near plane), the image is the one drawn with culling off, bit for bit, and the
//! frame costs fewer cycles and fragments; the culls are counted in report.json; culling
//! asked of a discoid scene is refused naming the field.

use crate::support::binary::run;
use crate::support::scenes::shipped_files;
use crate::support::{render_job, NO_CULLING};
use lembo_sim::camera::{Samples, View};
use lembo_sim::config::{ArchConfig, CullBackfaces};
use lembo_sim::datapath::Datapath;
use lembo_sim::job::{render_reference, run_path, Mode, Model, PathRun, PrimitivePath, RenderJob};
use lembo_sim::scene::Scene;

/// A timed run of `scene` on `path` (the triangle path at n = 2) on `arch`.
fn timed(scene: &Scene, path: PrimitivePath, arch: &ArchConfig) -> PathRun {
    let job = RenderJob {
        trace: Default::default(),
        mode: Mode::Timed,
        path,
        tess: (path == PrimitivePath::Triangle).then_some(2),
        ..render_job(0.5, Datapath::F32)
    };
    let view = View::new(&scene.camera, scene.viewport);
    run_path(&job, scene, &view, Model::Timed(arch), None).unwrap()
}

/// Where culling changed an image, it made it more accurate: the culled frame is closer to
/// the exact reference (PSNR and mean FLIP) than the unculled one, because what it dropped
/// was back faces showing through, not visible surface.
fn closer_with_culling(scene: &Scene, path: PrimitivePath, what: &str) {
    let view = View::new(&scene.camera, scene.viewport);
    let (reference, wall) = render_reference(scene, &view, 1, Samples::ONE);
    let accuracy = |arch: &ArchConfig| {
        let job = RenderJob {
            trace: Default::default(),
            mode: Mode::Timed,
            path,
            tess: (path == PrimitivePath::Triangle).then_some(2),
            reference: true,
            ..render_job(0.5, Datapath::F32)
        };
        let run = run_path(
            &job,
            scene,
            &view,
            Model::Timed(arch),
            Some((&reference, wall)),
        );
        let a = run.unwrap().report.accuracy.expect("measured");
        (a.psnr_db, a.flip_mean)
    };
    let (on, off) = (
        accuracy(&ArchConfig::default()),
        accuracy(&without_culling()),
    );
    assert!(
        on.0 > off.0 && on.1 < off.1,
        "{what}: culling changed the image away from the reference: (PSNR, FLIP) {on:?} \
         culled, {off:?} not"
    );
}

fn without_culling() -> ArchConfig {
    let mut arch = ArchConfig::default();
    arch.minmax.cull_backfaces = CullBackfaces::Off;
    arch.triangle_setup.cull_backfaces = CullBackfaces::Off;
    arch
}

/// Every shipped surface scene, both paths, at 160 x 160: where the default (`auto`) culls,
/// the image equals the unculled one bit for bit, something was culled, and the frame took
/// fewer cycles and fragments; where it does not, the run is the unculled one exactly.
/// The closed shipped meshes are culled (cylinder24 is an open tube, so not). The one
/// known exception, capped_cylinder's lembo surface (18 of 25 600 pixels), changes towards
/// the exact reference: there the unculled frame lets back-facing patches win depth ties
/// at the flat caps' rims ([`closer_with_culling`]).
#[test]
fn culling_back_faces_leaves_every_shipped_image_unchanged() {
    let (on, off) = (ArchConfig::default(), without_culling());
    let (mut culled, mut changed) = (Vec::new(), Vec::new());
    for (name, file) in shipped_files() {
        let mut scene = Scene::load(&file).unwrap();
        if scene.discoid_count() > 0 {
            continue;
        }
        scene.set_viewport(160, 160).unwrap();
        for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
            let (a, b) = (timed(&scene, path, &on), timed(&scene, path, &off));
            let what = format!("{name} {path:?}");
            let setting = a.report.settings.culling.clone().unwrap();
            assert_eq!(setting.switch, "auto", "{what}");
            if a.framebuffer.color != b.framebuffer.color {
                let (ia, ib) = (a.framebuffer.to_image(), b.framebuffer.to_image());
                let differ = ia.pixels().zip(ib.pixels()).filter(|(p, q)| p != q).count();
                changed.push(format!("{what}: {differ} pixels"));
                closer_with_culling(&scene, path, &what);
                continue;
            }
            let (ca, cb) = (a.report.counts, b.report.counts);
            let back = ca.lembos_culled_backface + ca.triangles_culled_backface;
            assert_eq!(
                cb.lembos_culled_backface + cb.triangles_culled_backface,
                0,
                "{what}"
            );
            let (ta, tb) = (
                a.report.cycles.as_ref().unwrap().total,
                b.report.cycles.as_ref().unwrap().total,
            );
            if setting.culled && back == 0 {
                // Coordinates of 1e7 leave no patch beyond the test's margin: culling on,
                // nothing culled, MinMax's test paid for.
                assert_eq!(ca.fragments, cb.fragments, "{what}");
            } else if setting.culled {
                assert!(ta < tb, "{what}: {ta:?} cycles culled, {tb:?} not");
                assert!(ca.fragments < cb.fragments, "{what}");
                culled.push(what);
            } else {
                assert_eq!(back, 0, "{what}");
                assert_eq!(ca, cb, "{what}");
                assert_eq!(ta, tb, "{what}");
            }
        }
    }
    eprintln!("culled: {culled:?}");
    // Known: the creased mesh's lembo surface, changed towards the reference (DESIGN.md §5).
    let known = ["traces/capped_cylinder.json Lembo"];
    let unexpected: Vec<&String> = changed
        .iter()
        .filter(|c| !known.iter().any(|k| c.starts_with(k)))
        .collect();
    eprintln!("images changed by culling: {changed:?}");
    assert!(unexpected.is_empty(), "culling changed images: {changed:?}");
    for want in [
        "traces/sphere24.json Lembo",
        "traces/sphere24.json Triangle",
        "traces/bevel_cube.json Lembo",
        "traces/bunny.json Lembo",
        "traces/bunny.json Triangle",
    ] {
        assert!(
            culled.iter().any(|c| c == want),
            "{want} not culled: {culled:?}"
        );
    }
}

/// "on" culls an open mesh too (front counter-clockwise), and may change its image; the
/// camera inside a closed mesh keeps `auto` from culling (the near plane cuts it open).
#[test]
fn culling_on_and_auto_are_what_they_say() {
    let scene = |f: &str| {
        let mut s = crate::support::scenes::trace(f, Some(96));
        s.set_viewport(96, 96).unwrap();
        s
    };
    let mut arch = ArchConfig::default();
    arch.minmax.cull_backfaces = CullBackfaces::On;
    arch.triangle_setup.cull_backfaces = CullBackfaces::On;
    let inside = scene("inside_mesh.json");
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let auto = timed(&inside, path, &ArchConfig::default());
        let s = auto.report.settings.culling.unwrap();
        assert!(s.closed_outward.is_some() && !s.culled, "{s:?}");
        assert_eq!(s.beyond_near_plane, Some(false));
        let forced = timed(&inside, path, &arch);
        let s = forced.report.settings.culling.unwrap();
        assert!(s.culled, "{s:?}");
        let c = forced.report.counts;
        assert!(
            c.lembos_culled_backface + c.triangles_culled_backface > 0,
            "{c:?}"
        );
    }
}

/// report.json carries the resolved setting and both counters.
#[test]
fn culling_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("off.json"), NO_CULLING).unwrap();
    let sphere = concat!(env!("CARGO_MANIFEST_DIR"), "/traces/sphere24.json");
    for (extra, culled) in [(&[][..], true), (&["--arch", "off.json"][..], false)] {
        for path in ["lembo", "triangle"] {
            let args = [
                &[
                    "render",
                    sphere,
                    "--viewport",
                    "128x128",
                    "--path",
                    path,
                    "--out",
                    "o",
                ][..],
                extra,
            ]
            .concat();
            let out = run(&args, dir.path());
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let report: serde_json::Value =
                serde_json::from_slice(&std::fs::read(dir.path().join("o/report.json")).unwrap())
                    .unwrap();
            let s = &report["settings"]["culling"];
            assert_eq!(s["culled"], culled, "{s}");
            // Asked only by a switch that reads it: `auto` here, not `off`.
            let closed = if culled {
                "ccw".into()
            } else {
                serde_json::Value::Null
            };
            assert_eq!(s["closed_outward"], closed, "{s}");
            if culled {
                assert_eq!(
                    (s["switch"].as_str(), s["front"].as_str()),
                    (Some("auto"), Some("ccw"))
                );
            } else {
                assert_eq!(s["switch"], "off");
            }
            let key = format!("{}s_culled_backface", path);
            let n = report["counts"][&key]
                .as_u64()
                .expect("the counter is reported");
            assert_eq!(n > 0, culled, "{key} = {n}");
        }
    }
}

/// Culling asked of a discoid scene is refused, exit status 2, naming the field and
/// writing nothing; `auto` there culls nothing.
#[test]
fn culling_a_discoid_scene_is_refused() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/traces/discoid_sphere20.json");
    for field in ["minmax", "triangle_setup"] {
        let dir = tempfile::tempdir().unwrap();
        let arch = format!(r#"{{"{field}": {{"cull_backfaces": "on"}}}}"#);
        std::fs::write(dir.path().join("a.json"), arch).unwrap();
        let out = run(
            &[
                "render",
                scene,
                "--viewport",
                "64x64",
                "--arch",
                "a.json",
                "--out",
                "o",
            ],
            dir.path(),
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{field}.cull_backfaces")), "{err}");
        assert!(!dir.path().join("o").exists(), "nothing written");
    }
}
