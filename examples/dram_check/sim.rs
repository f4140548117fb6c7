//! A trace fed to DRAMsim3 through the `dramsim3` crate, as DRAMsim3's own trace-driven
//! front end feeds it (DRAMsim3 `src/cpu.cc`, `TraceBasedCPU::ClockTick`): each DRAM cycle
//! the memory system ticks (completions arrive through the callback), then the next request
//! of the trace, if its arrival cycle has come, is offered; it is added only if DRAMsim3
//! will accept it (`WillAcceptTransaction`, the crate's `can_add`), and otherwise offered
//! again the next cycle, in order. At most one request enters per cycle.
//!
//! DRAMsim3 posts writes: a write completes the cycle after it is accepted into the write
//! buffer (`Controller::AddTransaction`), and reaches the DRAM when the buffer drains. So
//! the cycle of the last completion is when the last read returned or the last write was
//! accepted; writes still buffered then show in the epoch after it (`stats.rs`).

use crate::stats::{self, Epoch};
use dramsim3::MemorySystem;
use lembo_sim::memory::trace::Request;
use std::collections::{HashMap, VecDeque};
use std::path::Path;
use std::time::Instant;

/// What the timed run measures itself, from the callbacks.
#[derive(Clone, Debug)]
pub struct Run {
    /// DRAM cycles (ticks) up to and including the one of the last completion.
    pub cycles: u64,
    /// Sum and maximum over reads of cycles from acceptance to the callback (DRAMsim3's own
    /// `read_latency`: `clk - added_cycle` when the read returns).
    pub read_latency_sum: u64,
    pub read_latency_max: u64,
    /// Sum over reads of cycles from the trace's arrival cycle to the callback: acceptance
    /// latency plus the time the read waited on backpressure.
    pub read_latency_from_arrival_sum: u64,
    /// Wall seconds of the run (DRAMsim3's ticks and this driver), without set-up.
    pub host_seconds: f64,
    /// tCK in ns, the bytes one transaction moves (bus width x burst length) and the
    /// transaction queue's depth, as DRAMsim3 reads them from the configuration.
    pub tck_ns: f64,
    pub burst_bytes: u64,
    pub queue_size: u64,
}

/// Runs `requests` on a fresh DRAMsim3 built from `ini` (a configuration's text), writing
/// its files in `dir`; stops after `stop_after` cycles if given, else at the last
/// completion.
fn drive(
    ini: &str,
    dir: &Path,
    requests: &[Request],
    stop_after: Option<u64>,
) -> Result<Run, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let config = dir.join("config.ini");
    std::fs::write(&config, ini).map_err(|e| format!("{}: {e}", config.display()))?;
    let mut sys = MemorySystem::new(&config, dir)
        .map_err(|e| format!("DRAMsim3 refused {}: {e:?}", config.display()))?;
    let burst_bytes = (sys.bus_bits() * sys.burst_length() / 8) as u64;
    // A bound on the run: every request served alone, with room for refreshes.
    let guard = 10_000 + 1_000 * requests.len() as u64;
    // Reads in flight by address, oldest first: (acceptance cycle, arrival cycle).
    let mut in_flight: HashMap<u64, VecDeque<(u64, u64)>> = HashMap::new();
    let mut run = Run {
        cycles: 0,
        read_latency_sum: 0,
        read_latency_max: 0,
        read_latency_from_arrival_sum: 0,
        host_seconds: 0.0,
        tck_ns: sys.tck(),
        burst_bytes,
        queue_size: sys.queue_size() as u64,
    };
    let (mut next, mut done, mut clk) = (0usize, 0usize, 0u64);
    let mut callback_error = None;
    let start = Instant::now();
    loop {
        sys.tick(|addr, is_write| {
            done += 1;
            if is_write {
                return;
            }
            let Some((accepted, arrival)) = in_flight.get_mut(&addr).and_then(VecDeque::pop_front)
            else {
                callback_error = Some(format!("DRAMsim3 returned a read of 0x{addr:x} never sent"));
                return;
            };
            let latency = clk - accepted;
            run.read_latency_sum += latency;
            run.read_latency_max = run.read_latency_max.max(latency);
            run.read_latency_from_arrival_sum += clk - arrival;
        });
        if let Some(r) = requests.get(next) {
            if r.arrival <= clk && sys.can_add(r.addr, r.write) {
                if !sys.add(r.addr, r.write) {
                    return Err(format!(
                        "DRAMsim3 refused 0x{:x} after accepting it",
                        r.addr
                    ));
                }
                if !r.write {
                    in_flight
                        .entry(r.addr)
                        .or_default()
                        .push_back((clk + 1, r.arrival));
                }
                next += 1;
            }
        }
        clk += 1;
        if let Some(e) = callback_error {
            return Err(e);
        }
        if done == requests.len() && run.cycles == 0 {
            run.cycles = clk;
        }
        if stop_after.map_or(run.cycles != 0, |stop| clk >= stop) {
            break;
        }
        if clk > guard {
            return Err(format!(
                "DRAMsim3 completed {done} of {} requests in {clk} cycles",
                requests.len()
            ));
        }
    }
    run.host_seconds = start.elapsed().as_secs_f64();
    Ok(run)
}

/// The timed run and DRAMsim3's counters: epoch 1 (the run up to its last completion) and
/// epoch 2 (as many cycles again, where buffered writes drain).
pub struct Checked {
    pub run: Run,
    pub epochs: Vec<Epoch>,
}

/// Runs `requests` on the configuration `ini` twice in `dir` (see `stats.rs`): the first
/// run is timed and finds the last completion's cycle, the second reads DRAMsim3's counters.
pub fn check(ini: &str, dir: &Path, requests: &[Request]) -> Result<Checked, String> {
    if requests.is_empty() {
        return Err("the trace has no requests".into());
    }
    // No epoch inside the timed run: DRAMsim3 reads `epoch_period` as an int.
    let quiet = stats::with_epoch_period(ini, i32::MAX as u64);
    let run = drive(&quiet, &dir.join("timed"), requests, None)?;
    let counted = stats::with_epoch_period(ini, run.cycles);
    let stats_dir = dir.join("stats");
    let again = drive(&counted, &stats_dir, requests, Some(2 * run.cycles))?;
    if again.cycles != run.cycles {
        return Err(format!(
            "DRAMsim3 is not deterministic here: {} cycles, then {}",
            run.cycles, again.cycles
        ));
    }
    let epoch_file = stats_dir.join("dramsim3epoch.json");
    let text = std::fs::read_to_string(&epoch_file)
        .map_err(|e| format!("{}: {e}", epoch_file.display()))?;
    let epochs = stats::parse_epochs(&text)?;
    if epochs.len() != 2 {
        return Err(format!(
            "expected 2 epochs in {}, found {}",
            epoch_file.display(),
            epochs.len()
        ));
    }
    Ok(Checked { run, epochs })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ddr4() -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/dram_check/configs/DDR4_8Gb_x8_2400.ini");
        std::fs::read_to_string(path).unwrap()
    }

    #[test]
    fn four_reads_of_one_row_open_it_once() {
        let requests: Vec<Request> = (0..4)
            .map(|i| Request {
                addr: i * 64,
                write: false,
                arrival: 0,
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let c = check(&ddr4(), dir.path(), &requests).unwrap();
        let e = &c.epochs[0];
        assert_eq!(
            (e.num_read_cmds, e.num_act_cmds, e.num_read_row_hits),
            (4, 1, 3)
        );
        assert_eq!(e.num_cycles, c.run.cycles);
        // The first read waits at least tRCD + CL + the burst (17 + 17 + 4 cycles, the
        // configuration's DDR4-2400 timings).
        assert!(c.run.read_latency_max >= 38, "{}", c.run.read_latency_max);
        assert!(c.run.cycles < 100, "{}", c.run.cycles);
        assert_eq!(c.run.burst_bytes, 64);
    }

    #[test]
    fn an_empty_trace_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let e = check(&ddr4(), dir.path(), &[]).err().unwrap();
        assert!(e.contains("no requests"), "{e}");
    }
}
