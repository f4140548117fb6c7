//! The frame-buffer memory (DESIGN.md §3): the ROPs' traffic, merged by (arrival, port),
//! through one of two models (`memory.model`).
//!
//! **The port** (`port`, the default): the ROPs' depth reads and colour and depth writes
//! share one port of `framebuffer.bytes_per_cycle`. Input: [`MemAccess`]s, each the bytes
//! of one span or piece. Cost: the port moves data in slots of `framebuffer.access_cycles`
//! cycles, each carrying `bytes_per_cycle` * `access_cycles` bytes, and an access of b bytes
//! occupies whole slots, `access_cycles` * ceil(b / (`bytes_per_cycle` * `access_cycles`))
//! cycles, at least one slot: with the default slot of one cycle, ceil(b / bytes_per_cycle)
//! cycles, at least one. A slot may be a fraction of a cycle ([`PortClock`] keeps the port's
//! time exactly and charges whole cycles as it crosses them). With more than one sample per
//! pixel, the resolve after the last access: every sample's colour read and every pixel's
//! written, at the same rate. The geometry fetch's share of the port is a bound
//! (`fetch.rs`, which prices its reads with its own [`PortClock`]).
//!
//! **The DRAM controller** (`dram`, [`run_dram`]): the items carry the ROP caches' fills and
//! write-backs ([`crate::pipeline::rop_memory`]), each atom they touch one request to the
//! controller of [`crate::memory::dram`]. The frame ends when the last write has gone
//! through it.

use crate::config::{FrameBufferConfig, MemoryModel, Ratio};
use crate::datapath::Real;
use crate::graph::UnitKind;
use crate::memory::dram::{Dram, DramConfig};
use crate::memory::trace::Request;
use crate::pipeline::items::MemAccess;
use crate::pipeline::rop_memory::{ClientStats, RopMemory};
use crate::pipeline::runtime::executor::UnitFuture;
use crate::pipeline::runtime::{Ctx, Cycle};
use crate::pipeline::unit::{Finished, RunInputs, Unit, UnitReport};
use crate::raster::Counts;

/// The frame-buffer memory port.
pub struct FrameBufferPort;

impl<R: Real> Unit<R> for FrameBufferPort {
    const KIND: UnitKind = UnitKind::FrameBuffer;
    type In = MemAccess;
    type Out = ();
    // A sink: no output links.
    const OUT_WORDS: u32 = 0;

    fn spawn<'a>(
        ctx: Ctx<Self::In, Self::Out>,
        run: &'a RunInputs<'a, R>,
        _: usize,
    ) -> UnitFuture<'a, Finished> {
        let vp = run.view.viewport;
        let samples = run.view.samples;
        if run.arch.memory.model == MemoryModel::Dram {
            let clock = DramClock::new(run.arch.clock_mhz, &run.arch.memory.dram_config());
            let sector = u64::from(run.arch.memory.sector_bytes);
            let record = run.dram_requests;
            let geometry_base = RopMemory::geometry_base(&run.arch.memory, vp.width, vp.height)
                .expect("the memory fields were checked when the run was built");
            return Box::pin(self::run_dram(
                ctx,
                run.arch.memory.dram_config(),
                clock,
                sector,
                geometry_base,
                record,
            ));
        }
        let resolve =
            crate::rop::FrameBuffer::resolve_bytes(vp.width, vp.height / samples.get(), samples);
        Box::pin(self::run(ctx, &run.arch.framebuffer, resolve))
    }
}

/// The units' clock against the DRAM's command clock.
#[derive(Clone, Copy, Debug)]
pub struct DramClock {
    /// A unit cycle \[ps\].
    core_ps: f64,
    /// A DRAM cycle \[ps\].
    dram_ps: f64,
}

impl DramClock {
    /// Units at `clock_mhz` against the DRAM of `cfg`.
    pub fn new(clock_mhz: f64, cfg: &DramConfig) -> Self {
        DramClock {
            core_ps: 1e6 / clock_mhz,
            dram_ps: f64::from(cfg.timings.tck_ps),
        }
    }

    /// The first DRAM cycle at or after unit cycle `c`.
    pub fn to_dram(&self, c: Cycle) -> u64 {
        (c.0 as f64 * self.core_ps / self.dram_ps).ceil() as u64
    }

    /// The first unit cycle at or after DRAM cycle `d`.
    pub fn to_core(&self, d: u64) -> u64 {
        (d as f64 * self.dram_ps / self.core_ps).ceil() as u64
    }
}

/// The memory controller's body with the DRAM model (`memory.model = "dram"`): each item's
/// transfers become one request per DRAM atom they touch (a sector smaller than the atom
/// pays the whole atom), submitted at the item's arrival; a geometry fetch's batch
/// ([`MemAccess::is_geometry`]) reads the atoms of its bytes from `geometry_base` on. The
/// unit takes its next item once they have entered the controller's queues, so a full queue
/// holds the ROPs back, and the fetch's reads queue among the ROPs' traffic in time. The
/// frame ends when the last request has completed.
pub async fn run_dram(
    mut ctx: Ctx<MemAccess, ()>,
    cfg: DramConfig,
    clock: DramClock,
    sector_bytes: u64,
    geometry_base: u64,
    record: bool,
) -> Finished {
    let mut dram = Dram::new(&cfg).expect("the memory fields were checked when the run was built");
    let atom = u64::from(cfg.atom_bytes());
    let mut clients = Clients {
        requests: record.then(Vec::new),
        ..Clients::default()
    };
    while let Some(t) = ctx.next_input().await {
        let (now, _) = ctx.clock();
        let at = clock.to_dram(now);
        let before = clients.submitted;
        if t.is_geometry() {
            let start = geometry_base + t.offset;
            for a in start / atom..(start + t.bytes).div_ceil(atom) {
                clients.submit(&mut dram, a * atom, false, at, false);
            }
        }
        for tr in t.transfers() {
            let mut last = u64::MAX;
            for s in (0..64).filter(|s| tr.sectors >> s & 1 == 1) {
                let a = (tr.addr + s * sector_bytes) / atom;
                if a != last {
                    clients.submit(&mut dram, a * atom, tr.write, at, true);
                    last = a;
                }
            }
        }
        if clients.submitted > before {
            let admitted = dram.admit_all();
            ctx.work(clock.to_core(admitted).saturating_sub(now.0));
            clients.collect(&mut dram);
        }
    }
    let last = dram.finish();
    clients.collect(&mut dram);
    let (now, _) = ctx.clock();
    ctx.work(clock.to_core(last).saturating_sub(now.0));
    let stats = ClientStats {
        rop_read_latency_mean: clients.rop_latency as f64 / clients.stats.rop_reads.max(1) as f64,
        ..clients.stats
    };
    Finished::new(ctx, Counts::default()).with(UnitReport::Dram(
        dram.stats(),
        stats,
        clients.requests,
    ))
}

/// The controller's clients as it submits their requests: the trace, if kept, and which
/// requests are the ROPs' reads, whose latencies it sums as they complete.
#[derive(Default)]
struct Clients {
    requests: Option<Vec<Request>>,
    /// Bit t: request t is a ROP's read.
    rop_read: Vec<u64>,
    /// The completed ROP reads' latencies, summed \[DRAM cycles\].
    rop_latency: u64,
    /// Requests submitted.
    submitted: u64,
    stats: ClientStats,
}

impl Clients {
    /// Submits a request for the atom at `addr` arriving `at`, from a ROP if `rop` (else
    /// from the geometry fetch).
    fn submit(&mut self, dram: &mut Dram, addr: u64, write: bool, at: u64, rop: bool) {
        let req = Request {
            addr,
            write,
            arrival: at,
        };
        if let Some(r) = self.requests.as_mut() {
            r.push(req);
        }
        let t = dram.submit(req).0;
        self.submitted += 1;
        if t / 64 >= self.rop_read.len() as u64 {
            self.rop_read.push(0);
        }
        if !rop {
            self.stats.geometry_atoms += 1;
        } else if !write {
            self.rop_read[(t / 64) as usize] |= 1 << (t % 64);
            self.stats.rop_reads += 1;
        }
    }

    /// Takes the requests `dram` has completed.
    fn collect(&mut self, dram: &mut Dram) {
        for c in dram.complete() {
            let t = c.ticket.0;
            if self.rop_read[(t / 64) as usize] >> (t % 64) & 1 == 1 {
                self.rop_latency += c.done - c.arrival;
            }
        }
    }
}

/// The memory port's body: every access through the port at its byte rate, then the
/// multisample resolve's `resolve_bytes` (0 with one sample per pixel: no resolve).
pub async fn run(
    mut ctx: Ctx<MemAccess, ()>,
    cfg: &FrameBufferConfig,
    resolve_bytes: u64,
) -> Finished {
    let mut port = PortClock::new(cfg);
    while let Some(t) = ctx.next_input().await {
        let bytes = t.bytes;
        let (now, arrival) = ctx.clock();
        ctx.work(port.access(now, arrival, bytes));
    }
    if resolve_bytes > 0 {
        // The resolve reads every sample's colour and writes each pixel once the last
        // write is in, from where the last access left the port.
        let (now, _) = ctx.clock();
        ctx.work(port.access(now, Cycle::ZERO, resolve_bytes));
    }
    Finished::new(ctx, Counts::default())
}

/// The time of one client of the memory port, kept exactly in 1/[`Ratio::DEN`] cycles so
/// that slots shorter than a cycle (`framebuffer.access_cycles` < 1) share cycles: an
/// access starts when it arrives or when the port's last slot ends, whichever is later,
/// and the unit is charged the whole cycles from its clock to the end of the access's last
/// slot (0 when that slot ends within a cycle already charged). With whole slots the port's
/// time is always a whole cycle, and each access costs exactly its slots' cycles.
pub struct PortClock<'a> {
    cfg: &'a FrameBufferConfig,
    /// When the port's last slot ends \[1/DEN cycles\].
    free: u128,
}

impl<'a> PortClock<'a> {
    /// A port that has moved nothing yet.
    pub fn new(cfg: &'a FrameBufferConfig) -> Self {
        PortClock { cfg, free: 0 }
    }

    /// The busy cycles an access of `bytes` adds to a unit whose clock reads `now`, for an
    /// access that arrived at `arrival` (a unit that sends rather than receives passes its
    /// clock). At least one slot, even for no bytes.
    pub fn access(&mut self, now: Cycle, arrival: Cycle, bytes: u64) -> u64 {
        let den = u128::from(Ratio::DEN);
        let start = self.free.max(u128::from(arrival.0) * den);
        self.free = start + self.cfg.slot_time(self.cfg.slots(bytes).max(1));
        (self.free.div_ceil(den) as u64).saturating_sub(now.0)
    }

    /// The port is busy at least to the start of cycle `end` (a client charged a whole
    /// cycle its slot did not fill).
    pub fn hold_until(&mut self, end: Cycle) {
        self.free = self.free.max(u128::from(end.0) * u128::from(Ratio::DEN));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Port cycles of a stream of accesses of `bytes`, all waiting at cycle 0, charged as
    /// the unit would be.
    fn stream(cfg: &FrameBufferConfig, bytes: &[u64]) -> Vec<u64> {
        let mut port = PortClock::new(cfg);
        let mut now = 0;
        bytes
            .iter()
            .map(|&b| {
                let c = port.access(Cycle(now), Cycle::ZERO, b);
                now += c;
                c
            })
            .collect()
    }

    /// The default slot of one cycle reproduces ceil(b / bytes_per_cycle), at least one.
    #[test]
    fn port_default_slot_charges_ceil_bytes_over_rate() {
        let cfg = FrameBufferConfig::default();
        let bytes: [u64; 7] = [4, 64, 65, 0, 12, 200, 128];
        let want: Vec<u64> = bytes.iter().map(|&b| b.div_ceil(64).max(1)).collect();
        assert_eq!(stream(&cfg, &bytes), want);
        assert_eq!(cfg.transfer_cycles(200), 4);
        assert_eq!(cfg.transfer_cycles(0), 0);
    }

    /// Halved and doubled slots on small accesses: 8 accesses of 12 bytes take 8 cycles
    /// with slots of one cycle, 4 with half-cycle slots (two accesses a cycle) and 16 with
    /// two-cycle slots; large accesses are limited by the byte rate whatever the slot.
    #[test]
    fn port_access_cycles_halved_and_doubled() {
        let at = |slot: f64| FrameBufferConfig {
            access_cycles: serde_json::from_str(&slot.to_string()).unwrap(),
            ..FrameBufferConfig::default()
        };
        let small = [12; 8];
        assert_eq!(stream(&at(1.0), &small).iter().sum::<u64>(), 8);
        assert_eq!(stream(&at(0.5), &small), [1, 0, 1, 0, 1, 0, 1, 0]);
        assert_eq!(stream(&at(2.0), &small).iter().sum::<u64>(), 16);
        // 640 bytes: 10 cycles at 64 bytes a cycle, in slots of 1, 0.5 or 2 cycles.
        for slot in [1.0, 0.5, 2.0] {
            assert_eq!(stream(&at(slot), &[640]), [10], "slot {slot}");
        }
        // 65 bytes: 2 slots of 64 bytes (2 cycles); 3 slots of 32 (1.5 cycles, 2 charged
        // on an idle port, the next access finishing the shared cycle); 1 slot of 128 (2).
        assert_eq!(stream(&at(0.5), &[65, 65]), [2, 1]);
        assert_eq!(at(0.5).transfer_cycles(65), 2);
        assert_eq!(at(2.0).transfer_cycles(65), 2);
        assert_eq!(at(2.0).transfer_cycles(129), 4);
    }

    /// A half-cycle left free is lost when the port waits for the next access.
    #[test]
    fn port_idle_cycle_ends_a_shared_cycle() {
        let cfg = FrameBufferConfig {
            access_cycles: serde_json::from_str("0.5").unwrap(),
            ..FrameBufferConfig::default()
        };
        let mut port = PortClock::new(&cfg);
        assert_eq!(port.access(Cycle(0), Cycle(0), 4), 1);
        // Arrives at cycle 5, after the port went idle: a fresh cycle.
        assert_eq!(port.access(Cycle(5), Cycle(5), 4), 1);
        // Waiting since cycle 3: shares cycle 5 with the access before.
        assert_eq!(port.access(Cycle(6), Cycle(3), 4), 0);
    }
}
