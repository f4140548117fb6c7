//! Multisampling (`--samples`, DESIGN.md §2): both paths draw the sample grid at
//! Direct3D's standard positions and resolve it; the image is anti-aliased and measured
//! against the area-averaged reference; cycles, scan-line work, frame-buffer bytes and
//! energy grow as documented; triangles are shaded once per pixel, lembo fragments per
//! sample. samples = 1 is today's path bit for bit (the golden tests).

use lembo_sim::camera::{Samples, View};
use lembo_sim::config::ArchConfig;
use lembo_sim::datapath::Datapath;
use lembo_sim::job::{render_reference, run_path, Mode, Model, PathRun, PrimitivePath, RenderJob};
use lembo_sim::reference::oracle::ReferenceImage;
use lembo_sim::rop::FrameBuffer;
use lembo_sim::scene::Scene;

use crate::support::{render_job, scenes};

/// The side of the test scenes \[pixels\].
const SIDE: u32 = 128;

/// A render of `path` with `samples` per pixel, measured against the reference: the lembo
/// path at k = 0.1 px, the triangle path at level 16 (both within a tenth of a pixel of the
/// surface at this size, so that the silhouette's stair-steps are the larger error).
fn job(path: PrimitivePath, samples: u32, mode: Mode) -> RenderJob {
    RenderJob {
        trace: Default::default(),
        path,
        tess: (path == PrimitivePath::Triangle).then_some(16),
        samples: Samples::new(samples).unwrap(),
        mode,
        reference: true,
        ..render_job(0.1, Datapath::F32)
    }
}

/// Runs `job` on `scene` against the reference a run of its samples is measured against.
fn run(job: &RenderJob, scene: &Scene, arch: Option<&ArchConfig>) -> (PathRun, ReferenceImage) {
    let view = View::new(&scene.camera, scene.viewport);
    let reference = render_reference(scene, &view, job.reference_supersample(), job.samples);
    let run = run_path(
        job,
        scene,
        &view,
        Model::new(arch),
        Some((&reference.0, 0.0)),
    )
    .unwrap();
    (run, reference.0)
}

/// PSNR of `image` against `colours` \[dB\].
fn psnr(image: &FrameBuffer, colours: &[[u8; 3]]) -> f64 {
    let se: f64 = image
        .color
        .iter()
        .zip(colours)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] as f64 - b[k] as f64).powi(2)))
        .sum();
    10.0 * (255.0f64.powi(2) / (se / (3 * colours.len()) as f64)).log10()
}

/// Mean absolute channel difference of `image` against `reference`'s colours over the
/// pixels its true silhouette crosses (between 5 and 95 % of its sub-samples covered).
fn silhouette_error(image: &FrameBuffer, reference: &ReferenceImage) -> f64 {
    let coverage = reference.coverage.as_ref().expect("supersampled");
    let (mut sum, mut n) = (0.0, 0usize);
    for (k, &c) in coverage.iter().enumerate() {
        if c > 0.05 && c < 0.95 {
            let (a, b) = (image.color[k], reference.color[k]);
            sum += (0..3)
                .map(|i| (a[i] as f64 - b[i] as f64).abs())
                .sum::<f64>()
                / 3.0;
            n += 1;
        }
    }
    assert!(n > 100, "{n} silhouette pixels");
    sum / n as f64
}

#[test]
fn multisample_four_samples_anti_alias_both_paths_against_the_area_averaged_reference() {
    let scene = scenes::trace("sphere24.json", Some(SIDE));
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let (one, _) = run(&job(path, 1, Mode::Functional), &scene, None);
        let (four, reference) = run(&job(path, 4, Mode::Functional), &scene, None);
        // The reference of a multisampled run: area-averaged colours (8x8 by default), the
        // hits at the first sample row's sample.
        assert_eq!(reference.supersample, 8);
        assert_eq!(
            reference.color,
            reference.color_supersampled.clone().unwrap()
        );
        assert_eq!(reference.hits_offset_px, [-2.0 / 16.0, -6.0 / 16.0]);
        let a4 = four.report.accuracy.clone().unwrap();
        // Its report's PSNR is the image's against those colours, and it beats the one-sample
        // image's against the same colours by a margin: the silhouette's stair-steps are
        // what differed.
        let p4 = psnr(&four.framebuffer, &reference.color);
        assert!(
            (a4.psnr_db - p4).abs() < 1e-9,
            "{path:?}: {} {p4}",
            a4.psnr_db
        );
        let p1 = psnr(&one.framebuffer, &reference.color);
        assert!(
            p4 > p1 + 3.0,
            "{path:?}: 4 samples {p4:.2} dB, 1 sample {p1:.2} dB"
        );
        // Where the true silhouette crosses a pixel, the resolve blends it with the
        // background as the area average does; one sample picks one side.
        let e1 = silhouette_error(&one.framebuffer, &reference);
        let e4 = silhouette_error(&four.framebuffer, &reference);
        assert!(
            e4 < 0.5 * e1,
            "{path:?}: silhouette error {e1:.2} -> {e4:.2} a channel"
        );
        // The geometric metrics stay point-sampled and as small as one sample's.
        let a1 = one.report.accuracy.clone().unwrap();
        assert!(
            a4.silhouette_max_px < 0.75 && a1.silhouette_max_px < 0.75,
            "{a1:?} {a4:?}"
        );
        assert_eq!(four.report.settings.samples, 4);
        assert_eq!(four.report.settings.supersample, 8);
        if path == PrimitivePath::Lembo {
            // The scan-line guarantee, in pixels: the sample rows' deviation over 4.
            let d = a4.max_scanline_deviation_px.unwrap();
            assert!(d <= 0.5 + 1e-3, "{d}");
        }
    }
}

#[test]
fn multisample_cycles_scanlines_bytes_and_energy_grow_with_the_samples_on_both_paths() {
    let scene = scenes::trace("sphere24.json", Some(SIDE));
    let arch = ArchConfig::baseline();
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        let runs: Vec<PathRun> = [1, 2, 4, 8]
            .iter()
            .map(|&n| {
                let job = RenderJob {
                    trace: Default::default(),
                    reference: false,
                    ..job(path, n, Mode::Timed)
                };
                let view = View::new(&scene.camera, scene.viewport);
                run_path(&job, &scene, &view, Model::new(Some(&arch)), None).unwrap()
            })
            .collect();
        let total = |r: &PathRun| r.report.cycles.as_ref().unwrap().total;
        let cost = |r: &PathRun| r.report.cost.clone().unwrap();
        for pair in runs.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            assert!(
                total(b) > total(a),
                "{path:?}: cycles {} -> {}",
                total(a),
                total(b)
            );
            assert!(cost(b).energy_pj > cost(a).energy_pj, "{path:?}: energy");
            assert!(
                cost(b).framebuffer_bytes > cost(a).framebuffer_bytes,
                "{path:?}: frame-buffer bytes"
            );
        }
        let (one, four) = (&runs[0], &runs[2]);
        let (c1, c4) = (one.report.counts, four.report.counts);
        // A fragment is a sample: four samples a pixel, about four times the fragments.
        let ratio = c4.fragments as f64 / c1.fragments as f64;
        assert!((3.8..4.2).contains(&ratio), "{path:?}: fragments x{ratio}");
        if path == PrimitivePath::Lembo {
            // The scan-line stages walk every sample row.
            let rows = c4.scanlines as f64 / c1.scanlines as f64;
            assert!((3.8..4.2).contains(&rows), "scanlines x{rows}");
        }
        // The frame-buffer bytes as documented: per sample tested and written, plus the
        // resolve's five RGB8 planes (four samples read, the pixel written).
        let fb = &arch.framebuffer;
        let want = |c: &lembo_sim::raster::Counts, resolve: u64| {
            c.fragments * fb.bytes_per_fragment_tested
                + c.fragments_passed_depth * fb.bytes_per_fragment_written
                + resolve
        };
        let pixels = (SIDE * SIDE) as u64;
        assert_eq!(cost(one).framebuffer_bytes, want(&c1, 0));
        assert_eq!(cost(four).framebuffer_bytes, want(&c4, 5 * 3 * pixels));
        // The port's busy cycles include the resolve's.
        let port = |r: &PathRun| {
            r.report
                .cycles
                .as_ref()
                .unwrap()
                .units
                .iter()
                .find(|u| u.name.starts_with("FrameBuffer"))
                .unwrap()
                .busy
        };
        assert!(port(four) >= port(one) + 5 * 3 * pixels / fb.bytes_per_cycle);
        // The frame buffer holds every sample and the resolved image.
        assert_eq!(
            four.report.memory.framebuffer_bytes,
            4 * FrameBuffer::stored_bytes(SIDE, SIDE) + 3 * pixels
        );
    }
}

#[test]
fn multisample_triangles_are_shaded_once_per_pixel_and_lembo_fragments_per_sample() {
    let scene = scenes::trace("sphere24.json", Some(SIDE));
    let arch = ArchConfig::baseline();
    // The ROPs' multiplies (a triangle's attributes at the pixel centre and its shading; a
    // lembo fragment's normal, depth and shading) with 8 samples over 2: the same pixels
    // shaded, or four times the fragments.
    let rop_muls = |path, n| {
        let job = RenderJob {
            trace: Default::default(),
            reference: false,
            // Large triangles: few pixels where several meet.
            tess: (path == PrimitivePath::Triangle).then_some(1),
            ..job(path, n, Mode::Timed)
        };
        let view = View::new(&scene.camera, scene.viewport);
        let run = run_path(&job, &scene, &view, Model::new(Some(&arch)), None).unwrap();
        let cost = run.report.cost.unwrap();
        cost.ops.iter().find(|k| k.kind == "Rop").unwrap().ops.mul as f64
    };
    let triangle = rop_muls(PrimitivePath::Triangle, 8) / rop_muls(PrimitivePath::Triangle, 2);
    let lembo = rop_muls(PrimitivePath::Lembo, 8) / rop_muls(PrimitivePath::Lembo, 2);
    assert!(
        (0.95..1.1).contains(&triangle),
        "triangle ROP multiplies x{triangle}"
    );
    assert!((3.8..4.2).contains(&lembo), "lembo ROP multiplies x{lembo}");
}

#[test]
fn multisample_the_timed_image_equals_the_functional_one_on_any_host_split() {
    // run_path checks the timed image against the functional one (an internal error if they
    // differ); here on two host threads and with the ROPs' tiles smaller than a pixel's
    // sample rows.
    let scene = scenes::trace("bunny.json", Some(96));
    let mut arch = ArchConfig::baseline();
    arch.rop.tile_px = 2;
    for path in [PrimitivePath::Lembo, PrimitivePath::Triangle] {
        for n in [2, 8] {
            let job = RenderJob {
                trace: Default::default(),
                host_threads: 2,
                ..job(path, n, Mode::Timed)
            };
            let (run, _) = run(&job, &scene, Some(&arch));
            assert_eq!(run.framebuffer.width, 96);
        }
    }
}
