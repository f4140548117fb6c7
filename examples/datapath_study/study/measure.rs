//! One case measured: its renders in both datapaths against the exact reference.

use super::*;
use lembo_sim::camera::View;
use lembo_sim::datapath::Datapath;
use lembo_sim::frame::render_functional;
use lembo_sim::job::{measure_frame, render_reference, PrimitivePath};
use lembo_sim::reference::PixelsPerDegree;
use lembo_sim::rop::FrameBuffer;
use lembo_sim::scene::Scene;
use rayon::prelude::*;
use serde::Serialize;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::Instant;

/// What one render of a case measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// The case's family.
    pub family: Family,
    /// Its index within the family.
    pub index: u32,
    /// The study seed it was drawn from.
    pub seed: u64,
    /// The datapath rendered in.
    pub datapath: Datapath,
    /// The segmenter's k \[pixels\].
    pub k_px: f64,
    /// `ok`, or the error or panic message: a refused scene, an `Error` from the renderer,
    /// or a panic (a defect).
    pub status: String,
    /// Lembos culled (behind the eye, outside, degenerate) of the case's two.
    pub lembos_culled: u64,
    /// Fragments generated.
    pub fragments: u64,
    /// The probe's largest |y(u, v) − (j + 0.5)| over the fragments \[pixels\]; 0 without
    /// fragments.
    pub max_scanline_deviation_px: f64,
    /// `max_scanline_deviation_px − k` \[pixels\]; None without fragments.
    pub slack_px: Option<f64>,
    /// Pixel centres the reference covers \[pixels\].
    pub reference_covered_px: u64,
    /// Largest |x| or |y| of the case's projected points \[pixels\]: the magnitude of the
    /// screen coordinates the datapath works with.
    pub max_screen_coordinate_px: f64,
    /// Pixels covered by the render and not the reference \[pixels\].
    pub false_positive_px: u64,
    /// Pixels covered by the reference and not the render \[pixels\].
    pub false_negative_px: u64,
    /// False positives over `max(reference_covered_px, 1)`.
    pub false_positive_frac: f64,
    /// False negatives over `max(reference_covered_px, 1)`.
    pub false_negative_frac: f64,
    /// Pixels whose winning lembo (or none) differs from the f64 render's at the same k
    /// \[pixels\] (0 for f64).
    pub winner_diff_vs_f64_px: u64,
    /// Largest difference of a colour channel from the f64 render's at the same k, over
    /// the pixels with the same winner: the shading's share of f32 [0-255] (0 for f64).
    pub shade_diff_vs_f64_max: u64,
    /// Domain-edge roots the interval manager could not pair (0 when sound).
    pub unpaired_roots: u64,
    /// Holes inside the reference's coverage (the accuracy metric) \[pixels\].
    pub crack_pixels: u64,
    /// Pixels written twice along the pair's shared edge \[pixels\].
    pub double_hit_pixels: u64,
    /// PSNR against the reference \[dB\].
    pub psnr_db: f64,
    /// Wall time of the render with the probe \[seconds\] (host-dependent).
    pub render_seconds: f64,
}

/// What a run of the study measured, case by case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// The case's family.
    pub family: Family,
    /// Its index within the family.
    pub index: u32,
    /// Wall time of the exact reference \[seconds\] (host-dependent).
    pub reference_seconds: f64,
    /// One per datapath and k: f64 then f32, k in the given order.
    pub measurements: Vec<Measurement>,
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}

/// A measurement of `case` at `datapath` and `k` with every figure zero: what a run that
/// could not measure records, with its `status`.
fn blank(case: &Case, datapath: Datapath, k: f64, status: String) -> Measurement {
    Measurement {
        family: case.family,
        index: case.index,
        seed: case.seed,
        datapath,
        k_px: k,
        status,
        lembos_culled: 0,
        fragments: 0,
        max_scanline_deviation_px: 0.0,
        slack_px: None,
        reference_covered_px: 0,
        max_screen_coordinate_px: 0.0,
        false_positive_px: 0,
        false_negative_px: 0,
        false_positive_frac: 0.0,
        false_negative_frac: 0.0,
        winner_diff_vs_f64_px: 0,
        shade_diff_vs_f64_max: 0,
        unpaired_roots: 0,
        crack_pixels: 0,
        double_hit_pixels: 0,
        psnr_db: 0.0,
        render_seconds: 0.0,
    }
}

/// Against the f64 render's winners and colours: the pixels won by another primitive,
/// and the largest channel difference where the same primitive won; (0, 0) without one.
fn diff_vs_f64(fb: &FrameBuffer, f64_image: Option<&(Vec<u32>, Vec<[u8; 3]>)>) -> (u64, u64) {
    match f64_image {
        Some((winner64, color64)) => {
            let same = |i: &usize| fb.primitive[*i] == winner64[*i];
            let n = fb.primitive.len();
            (
                (0..n).filter(|i| !same(i)).count() as u64,
                (0..n)
                    .filter(same)
                    .flat_map(|i| {
                        fb.color[i]
                            .iter()
                            .zip(color64[i])
                            .map(|(a, b)| a.abs_diff(b) as u64)
                    })
                    .max()
                    .unwrap_or(0),
            )
        }
        None => (0, 0),
    }
}

/// Renders one case against the exact reference in both datapaths at every k. A refused
/// scene, a renderer error or a panic is recorded in the measurements' `status`, not
/// propagated: the study goes on and reports it.
pub fn measure_case(case: &Case, ks: &[f64]) -> CaseResult {
    let blank = |datapath: Datapath, k: f64, status: String| blank(case, datapath, k, status);
    let all = |status: String| -> Vec<Measurement> {
        [Datapath::F64, Datapath::F32]
            .into_iter()
            .flat_map(|d| ks.iter().map(move |&k| (d, k)))
            .map(|(d, k)| blank(d, k, status.clone()))
            .collect()
    };
    let file = format!("datapath study {} {}", case.family.name(), case.index);
    let scene = match Scene::from_json(&case.scene_json, &file, Path::new(".")) {
        Ok(s) => s,
        Err(e) => {
            return CaseResult {
                family: case.family,
                index: case.index,
                reference_seconds: 0.0,
                measurements: all(format!("error: scene refused: {e}")),
            }
        }
    };
    let view = View::new(&scene.camera, scene.viewport);
    let max_screen_coordinate_px = scene
        .lembos()
        .flat_map(|(l, _)| l.points)
        .map(|p| view.project(p))
        .map(|s| s.x.abs().max(s.y.abs()))
        .fold(0.0, f64::max);
    let reference = match catch_unwind(AssertUnwindSafe(|| {
        render_reference(&scene, &view, 1, lembo_sim::camera::Samples::ONE)
    })) {
        Ok(r) => r,
        Err(p) => {
            return CaseResult {
                family: case.family,
                index: case.index,
                reference_seconds: 0.0,
                measurements: all(format!("panic in the reference: {}", panic_message(p))),
            }
        }
    };
    let (reference, reference_seconds) = reference;
    let covered = reference.hits.iter().filter(|h| h.is_some()).count() as u64;
    let mut measurements = Vec::new();
    for &k in ks {
        // The f64 render's winning primitives and colours, to compare f32's with.
        let mut f64_image: Option<(Vec<u32>, Vec<[u8; 3]>)> = None;
        for datapath in [Datapath::F64, Datapath::F32] {
            let t = Instant::now();
            let run = catch_unwind(AssertUnwindSafe(|| {
                render_functional(&scene, &view, k, datapath, true)
            }));
            let seconds = t.elapsed().as_secs_f64();
            let frame = match run {
                Ok(Ok(frame)) => frame,
                Ok(Err(e)) => {
                    measurements.push(blank(datapath, k, format!("error: {e}")));
                    continue;
                }
                Err(p) => {
                    measurements.push(blank(datapath, k, format!("panic: {}", panic_message(p))));
                    continue;
                }
            };
            let probe = frame.probe.unwrap_or_default();
            let a = measure_frame(
                &scene,
                &view,
                &frame,
                &reference,
                PrimitivePath::Lembo,
                1,
                PixelsPerDegree::default(),
            );
            let fb = &frame.framebuffer;
            let (winner_diff, shade_diff) = diff_vs_f64(fb, f64_image.as_ref());
            if datapath == Datapath::F64 {
                f64_image = Some((fb.primitive.to_vec(), fb.color.to_vec()));
            }
            let c = &frame.counts;
            let denominator = covered.max(1) as f64;
            measurements.push(Measurement {
                status: "ok".into(),
                lembos_culled: c.lembos_culled_behind_eye
                    + c.lembos_culled_outside
                    + c.lembos_degenerate,
                fragments: probe.fragments,
                max_scanline_deviation_px: probe.max_scanline_deviation_px,
                slack_px: (probe.fragments > 0).then_some(probe.max_scanline_deviation_px - k),
                reference_covered_px: covered,
                max_screen_coordinate_px,
                false_positive_px: a.coverage_false_positive,
                false_negative_px: a.coverage_false_negative,
                false_positive_frac: a.coverage_false_positive as f64 / denominator,
                false_negative_frac: a.coverage_false_negative as f64 / denominator,
                winner_diff_vs_f64_px: winner_diff,
                shade_diff_vs_f64_max: shade_diff,
                unpaired_roots: c.unpaired_roots,
                crack_pixels: a.crack_pixels,
                double_hit_pixels: a.double_hit_pixels,
                psnr_db: a.psnr_db,
                render_seconds: seconds,
                ..blank(datapath, k, String::new())
            });
        }
    }
    CaseResult {
        family: case.family,
        index: case.index,
        reference_seconds,
        measurements,
    }
}

/// What a study run draws and measures.
#[derive(Clone, Debug, Serialize)]
pub struct StudySettings {
    /// Cases (pairs of lembos) per family.
    pub cases_per_family: u32,
    /// The study seed: the same seed draws the same cases.
    pub seed: u64,
    /// The segmenter's k values \[pixels\].
    pub ks: Vec<f64>,
    /// The families drawn, in report order.
    pub families: Vec<Family>,
}

/// Draws and measures every case of `settings`, in parallel on rayon's pool; the results are
/// in (family, index) order whatever the thread count.
pub fn run(settings: &StudySettings) -> Vec<CaseResult> {
    let cases: Vec<Case> = settings
        .families
        .iter()
        .flat_map(|&f| (0..settings.cases_per_family).map(move |i| case(f, settings.seed, i)))
        .collect();
    cases
        .par_iter()
        .map(|c| measure_case(c, &settings.ks))
        .collect()
}
