//! The memory a run is estimated to need, and the refusal, before any work, of a run larger
//! than the memory available (`--no-memory-check` runs it anyway).

use super::validate::{Mode, PrimitivePath, RenderJob};
use crate::error::{Error, Result, COMMAND_LINE};
use crate::scene::Scene;

/// Bytes a run holds per pixel, measured as peak resident memory over pixels on the bunny
/// at 2048x2048 and 4096x4096 (2026-11-25), rounded up: the functional model's frame buffer
/// and image; the timed pipeline's shared frame buffer and FIFOs besides; the exact
/// reference's image, supersampled colours and metrics; a discoid scene's accumulation
/// target and kept fragments (measured on bunny_discoids at 512x512). FLIP's working
/// images add 52 bytes a pixel to the reference's (sphere24 at 2048x2048, functional with
/// `--reference`, 2026-11-27: 466 MB peak before FLIP, 676 MB with it).
const BYTES_PER_PIXEL_FUNCTIONAL: f64 = 17.0;

const BYTES_PER_PIXEL_TIMED: f64 = 25.0;

const BYTES_PER_PIXEL_REFERENCE: f64 = 175.0 + 55.0;

const BYTES_PER_PIXEL_DISCOIDS: f64 = 160.0;

/// What a run holds whatever its size: the binary, the thread stacks, the functional
/// frame's window of set-up pieces (`frame::bands::WINDOW_PRIMITIVES`).
const BYTES_FIXED: f64 = 96.0 * 1024.0 * 1024.0;

/// Bytes a run holds per lembo besides what the scene holds ([`Scene::lembo_bytes`]): the
/// growth of peak resident memory from 125 000 to 500 000 lembos (terrain250 and
/// terrain500 at 256x256, 2026-11-27: 100 bytes a lembo, both modes) less the terrain's
/// mesh (36), rounded up. A lembo is made when a stage reaches it and its set-up form lives
/// while an item in flight points at it, so what remains is loading's peak (the weld's
/// sorted cells, the edges' sides).
const BYTES_PER_LEMBO: f64 = 80.0;

/// Bytes per lembo of a run measured against the exact reference, besides
/// [`BYTES_PER_LEMBO`]: the reference keeps each lembo's id in the tiles it meets and makes
/// a span of tiles' lembos at a time (`reference::oracle`), the probe and the see-through
/// check keep 32 bytes for each edge of each lembo while they match edges. Measured as
/// [`BYTES_PER_LEMBO`] with `--reference` (terrain500 to terrain1000 at 256x256,
/// 2026-11-28: 223 bytes a lembo in all, against 100 without), rounded up. Held whole, the
/// reference took 1 550 bytes a lembo.
const BYTES_PER_LEMBO_REFERENCE: f64 = 160.0;

/// Bytes per lembo of the triangle path: the indexed mesh's vertex numbering that the
/// geometry fetch's vertex caches read (keys of every distinct corner and edge; measured as
/// [`BYTES_PER_LEMBO`] at tessellation level 1: 630 a lembo in all).
const BYTES_PER_LEMBO_TRIANGLES: f64 = 600.0;

/// The memory `job` on `scene` is estimated to need \[bytes\], plus `extra_per_pixel`.
pub fn memory_estimate(job: &RenderJob, scene: &Scene, extra_per_pixel: f64) -> f64 {
    let (pixels, primitives) = estimate(job, scene, extra_per_pixel);
    BYTES_FIXED + pixels + primitives
}

/// The estimate's two parts \[bytes\]: what grows with the pixels (frame buffers, the
/// reference's image), and what grows with the lembos (the scene, the reference's
/// acceleration structure, the triangle path's vertex numbering).
fn estimate(job: &RenderJob, scene: &Scene, extra_per_pixel: f64) -> (f64, f64) {
    let pixels = scene.viewport.width as f64 * scene.viewport.height as f64;
    // Multisampled, the models' frame buffers hold every sample; the resolved frame is one
    // more image beside them, and the reference is traced twice (the area-averaged colours,
    // the hits at a sample), each counted as a whole reference. These are the measured
    // per-pixel figures scaled by what a multisampled run holds, not measured themselves.
    let samples = job.samples.get() as f64;
    let mut per_pixel = match job.mode {
        Mode::Functional => BYTES_PER_PIXEL_FUNCTIONAL,
        Mode::Timed => BYTES_PER_PIXEL_TIMED,
    } * samples
        + extra_per_pixel;
    if samples > 1.0 {
        per_pixel += BYTES_PER_PIXEL_FUNCTIONAL;
    }
    let lembos = scene.lembo_count() as f64;
    let mut per_lembo = BYTES_PER_LEMBO;
    if job.reference {
        per_pixel += BYTES_PER_PIXEL_REFERENCE * if samples > 1.0 { 2.0 } else { 1.0 };
        per_lembo += BYTES_PER_LEMBO_REFERENCE;
    }
    if scene.discoid_count() > 0 {
        per_pixel += BYTES_PER_PIXEL_DISCOIDS;
    }
    if job.path == PrimitivePath::Triangle {
        per_lembo += BYTES_PER_LEMBO_TRIANGLES;
    }
    (
        pixels * per_pixel,
        scene.lembo_bytes() as f64 + lembos * per_lembo,
    )
}

/// Hands the memory the allocator holds freed back to the system (glibc's `malloc_trim`;
/// elsewhere nothing). A functional frame drawn in bands frees its set-up pieces in its
/// threads' arenas, which the accuracy metrics' allocations do not reuse: without this a
/// measured run's peak resident memory grows by what they held (terrain500 at 1024x1024,
/// functional with `--reference` on the 2-core VM, 2026-11-29: 392 MB peak without it, 276
/// MB with it, the median of 5 runs). Nothing under Miri, which runs no foreign function.
pub(super) fn return_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu", not(miri)))]
    // SAFETY: malloc_trim only releases free memory the allocator holds; no live
    // allocation is touched, and it is safe to call from any thread at any time.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// The environment variable that, when set, replaces the memory the system reports as
/// available \[bytes\]: a user setting, not a test hook (DESIGN.md §8), for a run whose
/// allowance is not what /proc/meminfo says (a cgroup's memory limit, a shared host); a
/// machine of any size can also be asked how a smaller one refuses, which is how the tests
/// check the refusal on every machine.
pub const MEMORY_AVAILABLE_ENV: &str = "LEMBO_MEMORY_AVAILABLE";

/// The memory a run may count on \[bytes\]: [`MEMORY_AVAILABLE_ENV`] when set (a positive
/// whole number of bytes, else refused naming it), else what the system can give a new
/// allocation without swapping (`MemAvailable` of /proc/meminfo); None where neither says.
fn memory_available() -> Result<Option<f64>> {
    match std::env::var(MEMORY_AVAILABLE_ENV) {
        Ok(v) => match v.trim().parse::<u64>() {
            Ok(bytes) if bytes > 0 => Ok(Some(bytes as f64)),
            _ => Err(Error::invalid(
                "environment",
                MEMORY_AVAILABLE_ENV,
                format!("{v:?}"),
                "must be a positive whole number of bytes (or unset, to read /proc/meminfo)",
            )),
        },
        Err(_) => Ok(system_memory_available()),
    }
}

/// The memory the system can give a new allocation without swapping \[bytes\]
/// (`MemAvailable` of /proc/meminfo); None where it cannot be read.
fn system_memory_available() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// Refuses, before any work, a run estimated to need more memory than is available,
/// naming the estimate and what makes it large: `--viewport`, or the scene when its lembos
/// weigh more than its pixels; `--no-memory-check` runs it anyway. A run estimated
/// at over 1 GiB says so on standard error before it starts.
pub fn check_memory(job: &RenderJob, scene: &Scene, extra_per_pixel: f64) -> Result<()> {
    let size = format!("{}x{}", scene.viewport.width, scene.viewport.height);
    let (pixels, primitives) = estimate(job, scene, extra_per_pixel);
    let need = BYTES_FIXED + pixels + primitives;
    if primitives > pixels {
        let lembos = scene.lembo_count();
        let advice = if job.reference {
            "render a scene of fewer lembos, or without --reference (which adds about 160 bytes a lembo)"
        } else {
            "render a scene of fewer lembos"
        };
        return check_available(
            need,
            job.no_memory_check,
            ("SCENE", &scene.source_name()),
            &format!("{lembos} lembos at {size} px: this run"),
            advice,
        );
    }
    check_available(
        need,
        job.no_memory_check,
        ("--viewport", &size),
        &format!("{size} px: this run"),
        "render a smaller viewport",
    )
}

/// Refuses work estimated at `need` bytes when the system has less available, naming
/// `flag` = value (`(flag, value)`) with `advice`, unless `insist` (`--no-memory-check`);
/// `what` needs it, as the note above 1 GiB says.
pub fn check_available(
    need: f64,
    insist: bool,
    (flag, value): (&str, &str),
    what: &str,
    advice: &str,
) -> Result<()> {
    const GIB: f64 = (1u64 << 30) as f64;
    let have = memory_available()?;
    if need > GIB {
        eprintln!(
            "lembo-sim: {what} needs about {:.1} GiB of memory (estimate{})",
            need / GIB,
            have.map(|h| format!("; {:.1} GiB available", h / GIB))
                .unwrap_or_default()
        );
    }
    match have {
        Some(have) if need > have && !insist => Err(Error::invalid(
            COMMAND_LINE,
            flag,
            value,
            format!(
                "{what} would need about {:.1} GiB (estimate), more than the {:.1} GiB of memory available; {advice}, or pass --no-memory-check to run anyway",
                need / GIB,
                have / GIB
            ),
        )),
        _ => Ok(()),
    }
}
