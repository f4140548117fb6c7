//! One functional frame on several host threads (`--threads N`), bit-identical to the
//! single-threaded render for every N.
//!
//! The frame is drawn in windows of [`WINDOW_PRIMITIVES`] primitives, one after the other,
//! so that the set-up pieces held at once are a window's, not the scene's (`draw_frame`).
//! A window's threads are the calling thread and N - 1 scoped ones, started for the window
//! and joined at its end (`draw_window`, `on_threads`); they take work by number from shared
//! counters, so none waits on a scheduler, and meet once, when the window's setup is done,
//! waiting running rather than asleep (`wait_until`). Setup runs in tasks of up to 64 primitives
//! (`SetupTasks`; a lembo's triangles in one task), kept in primitive order, keeping every set-up piece with its rows (lembos: minmax's scanline
//! range; triangles: the bounding box) and a rough cost of drawing each of them
//! (`RowSpan`). The frame's rows are then cut into bands of an even number of rows (so no
//! 2x2 quad straddles two) by that estimate, shrinking from top to bottom (`bands`), and
//! the threads take the bands in order as they come free: the last ones are small, so the
//! threads finish together however wrong the estimate (`Bands`). A band walks the pieces that meet
//! its rows, in drawing order, through the scan-line stages of its own rows only, into its
//! own rows of the frame buffer (`FrameBuffer::bands_mut`, `Rop::band`), which its thread
//! also clears in the first window. Windows follow drawing order, so a pixel meets its
//! fragments in the same order whatever the windows.
//!
//! Every stage after setup works on one scanline (one row pair for a quad) and a pixel is
//! only ever written by fragments of its own row, so each pixel meets the same fragments in
//! the same order as in the single-threaded render: the same depth tests, the same shading,
//! the same winner. The counts are setup's plus the sum of the bands' (each counts only its
//! rows, covered pixels included), and equal the single-threaded ones; the first error (a
//! segment cap) is the smallest (piece, scanline) any band met, the one the single-threaded
//! walk meets first. Which thread sets up a task or draws a band changes nothing in it.
//!
//! The lembo path's analysed frame (`--reference`) is drawn the same way, each band's
//! fragments measured before its ROP by a probe over its own rows of one
//! [`ProbeBoard`] (`render_probed_in_bands`). The triangle path's analysed frame and the
//! counting runs of the cost model stay single-threaded.

use super::functional::Frame;
use crate::camera::View;
use crate::datapath::Real;
use crate::error::{Error, Result};
use crate::raster::counts::Counts;
use crate::raster::driver::{self, Draw, Placed, Stages};
use crate::raster::lembo_path::LemboPath;
use crate::raster::probe::ProbeBoard;
use crate::raster::screen::ScreenLembo;
use crate::raster::triangle::ScreenTriangle;
use crate::rop::framebuffer::FrameRows;
use crate::rop::{FrameBuffer, RopSink};
use crate::scene::Scene;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

/// Rough costs of the work a band does, in nanoseconds of one core (measured on the bunny
/// and sphere24 frames at 1024x1024): they only weigh rows against each other, and a wrong
/// one costs balance, never pixels.
mod cost {
    /// A lembo scanline: its intervals, segments and subsegments.
    pub const LEMBO_SCANLINE: f32 = 160.0;
    /// A triangle's row: its span and the quads' bookkeeping.
    pub const TRIANGLE_ROW: f32 = 40.0;
    /// A fragment: its depth test, attributes and shading.
    pub const FRAGMENT: f32 = 18.0;
    /// Clearing a pixel of a fresh frame (page faults included).
    pub const CLEAR: f64 = 2.0;
}

/// What drawing one row of a set-up piece costs, roughly, to weigh the frame's rows
/// against each other when cutting it into bands.
pub trait RowCost {
    /// Nanoseconds of one core, roughly: the piece's fixed work per row and fragments over
    /// half its width, as for a triangle.
    fn row_cost(&self) -> f32;
}

/// A row's fixed work `fixed` and the fragments of half a `width` pixels wide piece.
fn per_row(width: f64, fixed: f32) -> f32 {
    fixed + cost::FRAGMENT * (width.clamp(0.0, 1e6) as f32) / 2.0
}

impl<R: Real> RowCost for ScreenLembo<R> {
    fn row_cost(&self) -> f32 {
        let x = self.x.reference_values().map(|x: R| x.f64());
        let width =
            x.iter().fold(f64::MIN, |a, &b| a.max(b)) - x.iter().fold(f64::MAX, |a, &b| a.min(b));
        per_row(width, cost::LEMBO_SCANLINE)
    }
}

impl<R: Real> RowCost for ScreenTriangle<R> {
    fn row_cost(&self) -> f32 {
        let [i0, i1, _, _] = self.bbox;
        per_row(i1 as f64 - i0 as f64, cost::TRIANGLE_ROW)
    }
}

/// A set-up piece's rows, half-open, and what drawing one of them costs ([`RowCost`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct RowSpan {
    lo: u32,
    hi: u32,
    cost: f32,
}

/// Bands of a frame's rows for `threads` threads, given each row's estimated cost
/// `row_cost` (one entry a row): half-open row ranges, each starting on an even row, in
/// order, covering every row. Each band takes a `1/(2 threads)` share of the estimated cost
/// still left after the bands before it, but not under `1/(64 threads)` of the whole
/// (guided self-scheduling): a thread that takes the next band when it comes free then
/// finishes at most a small band's time after the others.
fn bands(row_cost: &[f64], threads: u32) -> Vec<(u32, u32)> {
    let height = row_cost.len() as u32;
    let pairs: Vec<f64> = row_cost.chunks(2).map(|p| p.iter().sum()).collect();
    let total: f64 = pairs.iter().sum();
    let threads = threads.max(1) as f64;
    let floor = total / (64.0 * threads);
    let (mut out, mut left, mut lo) = (Vec::new(), total, 0);
    while lo < pairs.len() {
        let share = (left / (2.0 * threads)).max(floor);
        let (mut hi, mut cost) = (lo, 0.0);
        while hi < pairs.len() && (hi == lo || cost < share) {
            cost += pairs[hi];
            hi += 1;
        }
        out.push((2 * lo as u32, (2 * hi as u32).min(height)));
        left -= cost;
        lo = hi;
    }
    out
}

/// Most primitives per setup task.
const SETUP_CHUNK: usize = 64;

/// Setup tasks per thread, at most: enough that every thread gets some of a small scene.
const SETUP_TASKS_PER_THREAD: usize = 8;

/// Primitives per setup task on `threads` threads, for `primitives` fetched `together`
/// ([`Stages::fetched_together`]): whole fetches, up to [`SETUP_CHUNK`] primitives (at
/// least one fetch), fewer where there are few so that every thread gets some tasks (a
/// lembo's setup may split it into many pieces).
fn per_task(primitives: usize, together: usize, threads: u32) -> usize {
    let together = together.max(1);
    let fetches = primitives.div_ceil(together);
    let tasks = threads.max(1) as usize * SETUP_TASKS_PER_THREAD;
    together
        * fetches
            .div_ceil(tasks)
            .clamp(1, SETUP_CHUNK.div_ceil(together))
}

/// What a setup task hands on: its pieces, their rows, and what it counted.
type SetUp<T> = (Vec<T>, Vec<RowSpan>, Counts);

/// What setup task `task` hands on: the pieces of its run of `per_task` primitives that
/// cover some row, in order, with their rows, and what it counted.
fn set_up_task<R: Real, P: Stages<R>>(path: &P, per_task: usize, task: usize) -> SetUp<P::Piece>
where
    P::Piece: RowCost,
{
    let run = task * per_task..((task + 1) * per_task).min(path.primitives());
    // Room for a piece a primitive (splitting and clipping add some, culling takes some
    // away): a vector grown by doubling would copy its pieces and fault in pages twice.
    let (mut pieces, mut rows) = (Vec::with_capacity(run.len()), Vec::with_capacity(run.len()));
    let mut counts = Counts::default();
    let keep = |piece: &P::Piece, (lo, hi)| {
        rows.push(RowSpan {
            lo,
            hi,
            cost: piece.row_cost(),
        })
    };
    let mut scratch = P::SetupScratch::default();
    driver::set_up(path, run, &mut scratch, &mut pieces, keep, &mut counts);
    (pieces, rows, counts)
}

/// Set-up pieces in drawing order, as the setup tasks left them (one slice a task; copying
/// a few megabytes of set-up lembos into one vector would be serial work between setup and
/// the bands), each task's with its pieces' rows.
struct Pieces<'a, T>(Vec<(&'a [T], &'a [RowSpan])>);

impl<'a, T> Pieces<'a, T> {
    /// The setup tasks' pieces in task order, their counts added to `counts`.
    fn join(tasks: impl Iterator<Item = &'a SetUp<T>>, counts: &mut Counts) -> Self {
        Pieces(
            tasks
                .map(|(pieces, rows, c)| {
                    *counts += *c;
                    (&pieces[..], &rows[..])
                })
                .collect(),
        )
    }

    /// The estimated cost of each of `height` rows `width` pixels wide: clearing it and
    /// drawing the pieces that meet it ([`RowSpan`]).
    fn row_cost(&self, width: u32, height: u32) -> Vec<f64> {
        // Each piece adds its cost to its rows: a difference array, summed once.
        let mut step = vec![0.0f64; height as usize + 1];
        for r in self.0.iter().flat_map(|(_, rows)| rows.iter()) {
            let (lo, hi) = (r.lo.min(height) as usize, r.hi.min(height) as usize);
            if lo < hi {
                step[lo] += r.cost as f64;
                step[hi] -= r.cost as f64;
            }
        }
        let clear = cost::CLEAR * width as f64;
        let mut run = 0.0;
        step[..height as usize]
            .iter()
            .map(|d| {
                run += d;
                clear + run.max(0.0)
            })
            .collect()
    }

    /// The pieces whose rows meet rows `lo..hi`, in drawing order, with their index in that
    /// order and their own rows (half-open). A band looks only at the pieces' rows, a few
    /// bytes each, to find its own.
    fn meeting(&self, lo: u32, hi: u32) -> impl Iterator<Item = Placed<'a, T>> + '_ {
        self.0
            .iter()
            .flat_map(|&(pieces, rows)| pieces.iter().zip(rows))
            .enumerate()
            .filter(move |(_, (_, r))| r.lo < hi && lo < r.hi)
            .map(|(n, (piece, r))| (n, piece, (r.lo, r.hi)))
    }
}

/// What one band drew: its counts, its passed depth tests and covered pixels
/// ([`RopSink::finish`]); or the first error it met with the (piece, scanline) it met it at.
type Band = std::result::Result<(Counts, (u64, u64)), ((usize, u32), Error)>;

/// A frame's setup tasks, which its threads take by number as they come free.
struct SetupTasks<T> {
    handed_on: Vec<OnceLock<SetUp<T>>>,
    next: AtomicUsize,
    done: AtomicUsize,
}

impl<T> SetupTasks<T> {
    /// `tasks` tasks, none taken yet.
    fn new(tasks: usize) -> Self {
        SetupTasks {
            handed_on: (0..tasks).map(|_| OnceLock::new()).collect(),
            next: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
        }
    }

    /// Runs `set_up(task)` for the tasks no other thread has taken, until none is left.
    fn run(&self, set_up: &impl Fn(usize) -> SetUp<T>) {
        loop {
            let task = self.next.fetch_add(1, Ordering::Relaxed);
            if task >= self.handed_on.len() {
                return;
            }
            let _ = self.handed_on[task].set(set_up(task));
            self.done.fetch_add(1, Ordering::Release);
        }
    }

    /// Whether every task is done.
    fn all_done(&self) -> bool {
        self.done.load(Ordering::Acquire) == self.handed_on.len()
    }
}

/// What the threads share once setup is done: the pieces, setup's counts, the bands and the
/// rows of the frame buffer each band writes (taken by the thread that draws it).
struct Plan<'a, 'fb, T> {
    pieces: Pieces<'a, T>,
    counts: Counts,
    bands: Vec<(u32, u32)>,
    rows: Vec<Mutex<Option<FrameRows<'fb>>>>,
}

/// A frame's bands: planned once, by the first thread done with setup, then taken by number
/// by the threads as they come free.
struct Bands<'a, 'fb, T> {
    /// The frame buffer, until the plan splits it into the bands' rows.
    unclaimed: Mutex<Option<&'fb mut FrameBuffer>>,
    planning: AtomicBool,
    plan: OnceLock<Plan<'a, 'fb, T>>,
    next: AtomicUsize,
}

impl<'a, 'fb, T> Bands<'a, 'fb, T> {
    /// Bands to be planned over `framebuffer`.
    fn new(framebuffer: &'fb mut FrameBuffer) -> Self {
        Bands {
            unclaimed: Mutex::new(Some(framebuffer)),
            planning: AtomicBool::new(false),
            plan: OnceLock::new(),
            next: AtomicUsize::new(0),
        }
    }

    /// Plans the bands for `threads` threads from the pieces `tasks` handed on, unless
    /// another thread already does: the other threads wait for the plan running
    /// (`OnceLock::get_or_init` would put them to sleep).
    fn plan(&self, tasks: &'a SetupTasks<T>, threads: u32) {
        if self.planning.swap(true, Ordering::AcqRel) {
            return;
        }
        let mut counts = Counts::default();
        let pieces = Pieces::join(
            tasks.handed_on.iter().filter_map(OnceLock::get),
            &mut counts,
        );
        let framebuffer = lock(&self.unclaimed)
            .take()
            .expect("the frame buffer is split into bands once");
        let bands = bands(
            &pieces.row_cost(framebuffer.width, framebuffer.height),
            threads,
        );
        let rows = framebuffer
            .bands_mut(&bands)
            .into_iter()
            .map(|r| Mutex::new(Some(r)))
            .collect();
        let planned = self.plan.set(Plan {
            pieces,
            counts,
            bands,
            rows,
        });
        assert!(planned.is_ok(), "one thread plans the bands");
    }

    /// Draws the bands no other thread has taken, each cleared to `background` if given and
    /// then drawn by `draw` with this thread's own scratch, until none is left; what each
    /// drew.
    fn draw<S: Default>(
        &self,
        background: Option<[u8; 3]>,
        draw: &impl Fn(&Pieces<'_, T>, u32, u32, FrameRows<'_>, &mut S) -> Band,
    ) -> Vec<Band> {
        let plan = self.plan.get().expect("the bands are planned");
        let (mut out, mut scratch) = (Vec::new(), S::default());
        loop {
            let b = self.next.fetch_add(1, Ordering::Relaxed);
            let Some(&(lo, hi)) = plan.bands.get(b) else {
                return out;
            };
            let mut rows = lock(&plan.rows[b])
                .take()
                .expect("a band is taken once, by the thread that drew its number");
            if let Some(background) = background {
                rows.clear(background);
            }
            out.push(draw(&plan.pieces, lo, hi, rows, &mut scratch));
        }
    }
}

/// Counts a frame's thread as gone when it leaves its work, and marks the frame abandoned if
/// it unwinds, so that no other thread waits for setup work that will never be done.
struct Leaving<'a> {
    abandoned: &'a AtomicBool,
    gone: &'a AtomicUsize,
}

impl Drop for Leaving<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.abandoned.store(true, Ordering::Release);
        }
        self.gone.fetch_add(1, Ordering::Release);
    }
}

/// Waits, running, until `done()`: false if the frame is abandoned first. A frame's threads
/// never sleep on one another: on the virtual machine we measure on, a thread put to sleep
/// is woken when its idle virtual CPU is, a millisecond or more later, far longer than any
/// of these waits; `yield_now` leaves the CPU to any other thread that wants it.
fn wait_until(done: impl Fn() -> bool, abandoned: &AtomicBool) -> bool {
    while !done() {
        if abandoned.load(Ordering::Acquire) {
            return false;
        }
        std::thread::yield_now();
    }
    true
}

/// Runs `work` on the calling thread and `threads - 1` scoped ones (one the system will not
/// start is simply missing; the others do its share), each counted by `gone` as it leaves
/// ([`Leaving`]); what they return, this thread's first. A panic on another thread is
/// resumed on this one.
fn on_threads<B: Send>(
    threads: u32,
    work: impl Fn() -> Vec<B> + Sync,
    abandoned: &AtomicBool,
    gone: &AtomicUsize,
) -> Vec<B> {
    let work = || {
        let _leaving = Leaving { abandoned, gone };
        work()
    };
    std::thread::scope(|s| {
        let others: Vec<_> = (1..threads.max(1))
            .filter_map(|i| {
                std::thread::Builder::new()
                    .name(format!("frame-{i}"))
                    .spawn_scoped(s, work)
                    .ok()
            })
            .collect();
        let mut drawn = work();
        // Joining a thread still drawing would put this one to sleep (`wait_until`); the
        // others are gone once `gone` counts them all, this one included.
        wait_until(
            || gone.load(Ordering::Acquire) == others.len() + 1,
            abandoned,
        );
        for other in others {
            match other.join() {
                Ok(bands) => drawn.extend(bands),
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
        drawn
    })
}

/// The frame's counts from setup's `counts` and what the bands drew: the bands' counts,
/// passed depth tests and covered pixels added; or the first error any band met, the one
/// at the smallest (piece, scanline), which the single-threaded walk meets first.
fn gather(mut counts: Counts, drawn: Vec<Band>) -> Result<Counts> {
    let mut first_error: Option<((usize, u32), Error)> = None;
    let (mut passed, mut covered) = (0, 0);
    for band in drawn {
        match band {
            Ok((c, (p, n))) => {
                counts += c;
                passed += p;
                covered += n;
            }
            Err((at, e)) => {
                if first_error.as_ref().is_none_or(|(first, _)| at < *first) {
                    first_error = Some((at, e));
                }
            }
        }
    }
    if let Some((_, e)) = first_error {
        return Err(e);
    }
    counts.fragments_passed_depth = passed;
    counts.pixels_covered = covered;
    Ok(counts)
}

/// Draws a frame on `threads` threads ([`on_threads`]), its `tasks` setup tasks
/// (`set_up(task)`) in windows of `window` tasks, one after the other, so that the set-up
/// pieces held at once are one window's (module doc). In a window the threads take its setup
/// tasks by number as they come free, wait until every one is done, and then take the bands
/// ([`bands`], from the window's pieces' estimated costs) in order, each drawn by
/// `draw(pieces, lo, hi, rows, scratch)` into its own rows of one frame buffer (cleared by
/// the band's thread in the first window), with the thread's own `scratch`. Windows follow
/// drawing order, so every pixel still meets its fragments in the single-threaded order.
/// The counts are setup's in task order plus the bands'; the result is the frame, or the
/// first error met, in the first window that met one. Which thread sets up a task or draws a
/// band changes nothing in it.
fn draw_frame<T: Send + Sync, S: Default>(
    scene: &Scene,
    view: &View,
    (threads, keep_normals): (u32, bool),
    (tasks, window): (usize, usize),
    set_up: impl Fn(usize) -> SetUp<T> + Sync,
    draw: impl Fn(&Pieces<'_, T>, u32, u32, FrameRows<'_>, &mut S) -> Band + Sync,
) -> Result<Frame> {
    let vp = view.viewport;
    let background = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let mut framebuffer = FrameBuffer::zeroed(vp.width, vp.height, keep_normals);
    let window = window.max(1);
    let mut counts = Counts::default();
    // At least one window, so that an empty scene's frame is cleared.
    for first in (0..tasks.max(1)).step_by(window) {
        let run = first..(first + window).min(tasks);
        let clear = (first == 0).then_some(background);
        let drawn = draw_window(&mut framebuffer, threads, run, clear, &set_up, &draw)?;
        // Covered pixels are the frame's: the last window's bands count them over every row.
        counts.pixels_covered = 0;
        counts += drawn;
    }
    Ok(Frame {
        framebuffer,
        counts,
        probe: None,
    })
}

/// One window of [`draw_frame`]: setup tasks `run`, then the bands over every row of
/// `framebuffer`, each cleared to `clear` first if given; the window's counts.
fn draw_window<T: Send + Sync, S: Default>(
    framebuffer: &mut FrameBuffer,
    threads: u32,
    run: std::ops::Range<usize>,
    clear: Option<[u8; 3]>,
    set_up: &(impl Fn(usize) -> SetUp<T> + Sync),
    draw: &(impl Fn(&Pieces<'_, T>, u32, u32, FrameRows<'_>, &mut S) -> Band + Sync),
) -> Result<Counts> {
    let first = run.start;
    let tasks = SetupTasks::new(run.len());
    let bands = Bands::new(framebuffer);
    let (abandoned, gone) = (AtomicBool::new(false), AtomicUsize::new(0));
    let work = || -> Vec<Band> {
        tasks.run(&|task| set_up(first + task));
        if !wait_until(|| tasks.all_done(), &abandoned) {
            return Vec::new();
        }
        bands.plan(&tasks, threads);
        if !wait_until(|| bands.plan.get().is_some(), &abandoned) {
            return Vec::new();
        }
        bands.draw(clear, draw)
    };
    let drawn = on_threads(threads, work, &abandoned, &gone);
    let plan = bands
        .plan
        .into_inner()
        .expect("every thread but a panicked one plans the bands");
    gather(plan.counts, drawn)
}

/// A mutex's value; one poisoned by a panicking thread is still read (the panic itself is
/// what the frame reports).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The functional frame of `path` (the lembo or the triangle path) on `threads` threads
/// (module doc): setup tasks of `per_task` primitives, then bands drawn through a ROP
/// each.
pub fn render_in_bands<R: Real, P>(
    scene: &Scene,
    view: &View,
    path: &P,
    threads: u32,
) -> Result<Frame>
where
    P: Stages<R> + for<'fb> Draw<R, RopSink<'fb, R>>,
    P::Piece: RowCost,
{
    plain_in_windows(scene, view, path, threads, WINDOW_PRIMITIVES)
}

/// [`render_in_bands`] with windows of about `window` primitives.
fn plain_in_windows<R: Real, P>(
    scene: &Scene,
    view: &View,
    path: &P,
    threads: u32,
    window: usize,
) -> Result<Frame>
where
    P: Stages<R> + for<'fb> Draw<R, RopSink<'fb, R>>,
    P::Piece: RowCost,
{
    let frame = (threads, window, false);
    render_in_windows(
        scene,
        view,
        path,
        frame,
        |pieces, (lo, hi), rop, c, buffers| {
            driver::draw(path, pieces.meeting(lo, hi), (lo, hi), rop, c, buffers)
        },
    )
}

/// The lembo path's analysed frame on `threads` threads in windows of about `window`
/// primitives ([`WINDOW_PRIMITIVES`] but in tests): [`render_in_bands`] with normals kept
/// and every band's fragments measured by a probe on `board` before its ROP, the same frame
/// and, in `board`, the same measurements as the single-threaded probe's ([`ProbeBoard`]).
pub fn render_probed_in_bands<R: Real>(
    scene: &Scene,
    view: &View,
    path: &LemboPath<'_, R>,
    (threads, window): (u32, usize),
    board: &ProbeBoard,
) -> Result<Frame> {
    let frame = (threads, window, true);
    render_in_windows(
        scene,
        view,
        path,
        frame,
        |pieces, (lo, hi), rop, c, buffers| {
            let mut probe = board.probe(lo, hi, rop);
            driver::draw(
                path,
                pieces.meeting(lo, hi),
                (lo, hi),
                &mut probe,
                c,
                buffers,
            )
        },
    )
}

/// Most primitives set up before their bands are drawn: the set-up pieces a frame holds at
/// once (a set-up lembo takes about 500 bytes with its rows, so some 33 MB), while the
/// threads meet twice a window, a few hundred milliseconds of work apart.
pub const WINDOW_PRIMITIVES: usize = 1 << 16;

/// [`render_in_bands`] on `threads` threads with windows of about `window` primitives
/// (whole setup tasks), normals kept if `keep_normals`, each band's pieces in rows
/// `(lo, hi)` drawn into its ROP by `draw_band`.
fn render_in_windows<R: Real, P>(
    scene: &Scene,
    view: &View,
    path: &P,
    (threads, window, keep_normals): (u32, usize, bool),
    draw_band: impl for<'x, 'fb> Fn(
            &Pieces<'x, P::Piece>,
            (u32, u32),
            &mut RopSink<'fb, R>,
            &mut Counts,
            &mut P::Buffers,
        ) -> std::result::Result<(), ((usize, u32), Error)>
        + Sync,
) -> Result<Frame>
where
    P: Stages<R>,
    P::Piece: RowCost,
{
    let per_task = per_task(path.primitives(), path.fetched_together(), threads);
    crate::progress::add_total(path.primitives() as u64);
    let tasks = path.primitives().div_ceil(per_task);
    draw_frame(
        scene,
        view,
        (threads, keep_normals),
        (tasks, window.div_ceil(per_task)),
        |task| {
            let set_up = set_up_task(path, per_task, task);
            let first = task * per_task;
            crate::progress::advance((path.primitives().min(first + per_task) - first) as u64);
            set_up
        },
        |pieces, lo, hi, rows, buffers: &mut P::Buffers| {
            let mut rop = RopSink::<R>::band(rows, &scene.light, view, lo);
            let mut c = Counts::default();
            draw_band(pieces, (lo, hi), &mut rop, &mut c, buffers)?;
            Ok((c, rop.finish()))
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::lembo_path::LemboPath;
    use crate::raster::triangle::{TrianglePath, TriangleSource};

    /// A shipped scene on a small viewport, and its view.
    fn shipped(path: &str) -> (Scene, View) {
        crate::frame::tests::shipped_at(path, 96, 64)
    }

    /// A setup task that sets up nothing but says which task it was.
    fn tagged(task: usize) -> SetUp<usize> {
        (vec![task], vec![span(0, 2)], Counts::default())
    }

    #[test]
    fn every_setup_task_runs_once_and_the_bands_see_them_in_order() {
        let (scene, view) = shipped("traces/sphere24.json");
        for threads in [1, 2, 5] {
            let ran = Mutex::new(Vec::new());
            let seen = Mutex::new(Vec::new());
            draw_frame(
                &scene,
                &view,
                (threads, false),
                (37, 37),
                |task| {
                    lock(&ran).push(task);
                    tagged(task)
                },
                |pieces, lo, _, _, _: &mut ()| {
                    if lo == 0 {
                        *lock(&seen) = pieces.meeting(0, 2).map(|(n, &t, _)| (n, t)).collect();
                    }
                    Ok((Counts::default(), (0, 0)))
                },
            )
            .expect("a frame");
            let mut ran = ran.into_inner().unwrap();
            ran.sort();
            assert_eq!(ran, (0..37).collect::<Vec<_>>(), "{threads} threads");
            let seen = seen.into_inner().unwrap();
            assert_eq!(seen, (0..37).map(|t| (t, t)).collect::<Vec<_>>());
        }
    }

    #[test]
    fn windows_of_any_size_draw_the_single_threaded_frame() {
        // The bunny's lembos, and its triangles at level 2, in windows of a primitive to the
        // whole scene, on 1 to 3 threads: the frame and counts of one thread, bit for bit.
        let (scene, view) = crate::frame::tests::shipped_at("traces/bunny.json", 160, 128);
        let tol = crate::tolerance::Tolerance::new(0.5);
        let tessellation = crate::lembo::tessellate::Tessellation::new(scene.lembo_sets(), 2);
        let bits = |f: &Frame| {
            let fb = &f.framebuffer;
            let depth: Vec<u32> = fb.depth.iter().map(|d| d.to_bits()).collect();
            (fb.color.to_vec(), depth, fb.primitive.to_vec(), f.counts)
        };
        let lembos = LemboPath::<f32>::new(&scene, &view, tol.k, tol.perspective, 1 << 16);
        let triangles = TrianglePath::new(&tessellation, &view);
        let one = |t: Option<&dyn TriangleSource>| {
            let frame = crate::frame::render_functional_on(
                &scene,
                &view,
                tol,
                t,
                crate::datapath::Datapath::F32,
                false,
                1,
            );
            bits(&frame.expect("a frame"))
        };
        let (lembo_frame, triangle_frame) = (one(None), one(Some(&tessellation)));
        assert!(lembo_frame.3.fragments > 1000 && triangle_frame.3.fragments > 1000);
        for threads in [1, 2, 3] {
            for window in [1, 50, 1000, 1 << 20] {
                let frame = plain_in_windows::<f32, _>(&scene, &view, &lembos, threads, window);
                assert!(
                    bits(&frame.unwrap()) == lembo_frame,
                    "lembos {threads} {window}"
                );
                let frame = plain_in_windows::<f32, _>(&scene, &view, &triangles, threads, window);
                assert!(
                    bits(&frame.unwrap()) == triangle_frame,
                    "triangles {threads} {window}"
                );
            }
        }
    }

    #[test]
    fn probed_bands_draw_and_measure_what_one_thread_does() {
        // The bunny's analysed frame, its normals and the probe's report, in windows of a
        // primitive to the whole scene on 1 to 3 threads: the single-threaded probe's, bit
        // for bit.
        let (scene, view) = crate::frame::tests::shipped_at("traces/bunny.json", 160, 128);
        let tol = crate::tolerance::Tolerance::new(0.5);
        let bits = |f: &Frame| {
            let fb = &f.framebuffer;
            let normal: Vec<[u32; 3]> = (fb.normal.as_ref().expect("normals kept").iter())
                .map(|n| n.map(f32::to_bits))
                .collect();
            (fb.color.to_vec(), fb.primitive.to_vec(), normal, f.counts)
        };
        let one = crate::frame::render_functional(
            &scene,
            &view,
            tol,
            crate::datapath::Datapath::F32,
            true,
        )
        .expect("a frame");
        let report = one.probe.expect("a probe report");
        assert!(report.fragments > 1000 && report.max_scanline_deviation_px > 0.0);
        let lembos = LemboPath::<f32>::new(&scene, &view, tol.k, tol.perspective, 1 << 16);
        for threads in [1, 2, 3] {
            for window in [1, 50, 1 << 20] {
                let board = ProbeBoard::new(&scene, view.viewport, threads);
                let frame =
                    render_probed_in_bands(&scene, &view, &lembos, (threads, window), &board);
                assert!(bits(&frame.unwrap()) == bits(&one), "{threads} {window}");
                assert_eq!(board.report(), report, "{threads} {window}");
            }
        }
    }

    #[test]
    fn a_panic_in_setup_reaches_the_caller_and_no_thread_waits_for_it() {
        // On its own thread, so that a frame whose threads wait for ever fails the test.
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let (scene, view) = shipped("traces/sphere24.json");
            for threads in [1, 2, 4] {
                let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    draw_frame(
                        &scene,
                        &view,
                        (threads, false),
                        (9, 9),
                        |task| {
                            assert_ne!(task, 4, "task 4 fails");
                            tagged(task)
                        },
                        |_, _, _, _, _: &mut ()| Ok((Counts::default(), (0, 0))),
                    )
                }));
                let message = match run {
                    Ok(_) => "no panic".to_string(),
                    Err(p) => p.downcast_ref::<String>().cloned().unwrap_or_default(),
                };
                done.send((threads, message)).unwrap();
            }
        });
        for _ in 0..3 {
            let (threads, message) = finished
                .recv_timeout(std::time::Duration::from_secs(60))
                .expect("the frame ends, with the panic, within a minute");
            assert!(message.contains("task 4 fails"), "{threads}: {message}");
        }
    }

    #[test]
    fn setup_tasks_are_whole_fetches_and_every_thread_gets_some() {
        // Lembos, fetched one at a time: up to 64 a task, fewer so that each of 2 threads
        // gets 8 tasks of a small scene.
        assert_eq!(per_task(5000, 1, 2), 64);
        assert_eq!(per_task(24, 1, 2), 2);
        assert_eq!(per_task(3, 1, 4), 1);
        // Triangles, a lembo's 16 (or 100) fetched together: whole lembos, up to 64
        // triangles a task but at least one lembo.
        assert_eq!(per_task(5000 * 16, 16, 2), 64);
        assert_eq!(per_task(24 * 16, 16, 2), 32);
        assert_eq!(per_task(24 * 100, 100, 2), 100);
        assert_eq!(per_task(0, 16, 2), 16);
    }

    fn span(lo: u32, hi: u32) -> RowSpan {
        RowSpan { lo, hi, cost: 1.0 }
    }

    #[test]
    fn a_band_meets_the_pieces_that_meet_its_rows_in_order() {
        // Pieces over two setup tasks, named by their half-open rows.
        let tasks = [vec![(0, 1), (3, 5), (9, 10)], vec![(0, 10), (4, 4), (7, 8)]];
        let spans: Vec<Vec<RowSpan>> = tasks
            .iter()
            .map(|t| t.iter().map(|&(lo, hi)| span(lo, hi)).collect())
            .collect();
        let pieces = Pieces(
            tasks
                .iter()
                .zip(&spans)
                .map(|(t, s)| (&t[..], &s[..]))
                .collect(),
        );
        let all: Vec<(u32, u32)> = tasks.concat();
        for (lo, hi) in [(0, 4), (4, 8), (8, 10), (0, 10), (4, 5)] {
            let got: Vec<(usize, (u32, u32))> = pieces
                .meeting(lo, hi)
                .map(|(n, &r, rows)| {
                    assert_eq!(rows, r, "a piece's own rows");
                    (n, r)
                })
                .collect();
            let want: Vec<(usize, (u32, u32))> = all
                .iter()
                .copied()
                .enumerate()
                .filter(|&(_, (r0, r1))| r0 < hi && lo < r1)
                .collect();
            assert_eq!(got, want, "rows {lo}..{hi}");
        }
        let ids = |lo, hi| {
            pieces
                .meeting(lo, hi)
                .map(|(n, _, _)| n)
                .collect::<Vec<_>>()
        };
        assert_eq!(ids(0, 4), [0, 1, 3]);
        assert_eq!(ids(4, 8), [1, 3, 5]);
        assert_eq!(ids(8, 10), [2, 3]);
    }

    #[test]
    fn a_rows_cost_is_its_clear_and_the_pieces_that_meet_it() {
        let spans = [
            RowSpan {
                lo: 1,
                hi: 3,
                cost: 10.0,
            },
            RowSpan {
                lo: 2,
                hi: 9,
                cost: 100.0,
            },
        ];
        let pieces = Pieces(vec![(&[(); 2][..], &spans[..])]);
        let clear = cost::CLEAR * 4.0;
        let got = pieces.row_cost(4, 5);
        assert_eq!(
            got,
            [
                clear,
                clear + 10.0,
                clear + 110.0,
                clear + 100.0,
                clear + 100.0
            ]
        );
    }

    #[test]
    fn bands_cover_every_row_once_from_even_rows() {
        for height in [1, 2, 3, 7, 64, 511, 512, 1024] {
            for threads in [1, 2, 3, 16] {
                for cost in [
                    vec![1.0; height],
                    (0..height).map(|j| (j % 7) as f64).collect(),
                ] {
                    let b = bands(&cost, threads);
                    assert_eq!(b[0].0, 0);
                    assert_eq!(b.last().unwrap().1, height as u32);
                    for w in b.windows(2) {
                        assert_eq!(w[0].1, w[1].0);
                    }
                    assert!(b.iter().all(|(lo, hi)| lo % 2 == 0 && lo < hi));
                }
            }
        }
    }

    #[test]
    fn bands_shrink_with_the_cost_left_and_split_costly_rows_finer() {
        let cost_of =
            |cost: &[f64], (lo, hi): (u32, u32)| cost[lo as usize..hi as usize].iter().sum::<f64>();
        // Uniform rows on two threads: the first band a quarter of the frame, then shrinking
        // to the floor of 1/128 of it, never under it but for the last.
        let uniform = vec![1.0; 1024];
        let b = bands(&uniform, 2);
        assert_eq!(b[0], (0, 256));
        assert_eq!(b[1], (256, 448));
        let sizes: Vec<u32> = b.iter().map(|(lo, hi)| hi - lo).collect();
        assert!(sizes.windows(2).all(|w| w[0] >= w[1]), "{sizes:?}");
        assert!(
            sizes[..sizes.len() - 1].iter().all(|&s| s >= 8),
            "{sizes:?}"
        );
        assert!(b.len() < 64, "{} bands", b.len());
        // A costly stretch of rows in the middle is cut into short bands, a cheap one into
        // long: bands hold similar costs, not similar rows.
        let mut lumpy = vec![1.0; 1024];
        lumpy[400..600].iter_mut().for_each(|c| *c = 50.0);
        let b = bands(&lumpy, 2);
        let total: f64 = lumpy.iter().sum();
        let inside = b.iter().filter(|&&(lo, hi)| lo >= 400 && hi <= 600).count();
        assert!(inside >= 4, "{b:?}");
        for &band in &b[..b.len() - 1] {
            assert!(
                cost_of(&lumpy, band) >= total / 128.0 - 1e-9,
                "{band:?} in {b:?}"
            );
        }
    }
}
