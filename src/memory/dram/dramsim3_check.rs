//! The controller against DRAMsim3 (issue 51, item 5): the check's traces ([`super::traces`])
//! replayed through [`super::replay`] and compared with DRAMsim3's figures for the same
//! traces on the same memories, recorded in `traces/dram/dramsim3.json` by
//! `examples/dram_check` (which needs cmake and the `dramsim3` feature, so this test reads
//! its recorded figures instead of running it).

use super::traces;
use super::*;
use serde::Deserialize;

#[derive(Deserialize)]
struct Recorded {
    runs: Vec<Run>,
}

#[derive(Deserialize)]
struct Run {
    trace: String,
    config: String,
    requests: u64,
    reads: u64,
    writes: u64,
    dram_cycles: u64,
    activations: u64,
    row_hit_rate: f64,
    refreshes: u64,
    energy_pj: Energy,
}

#[derive(Deserialize)]
struct Energy {
    activate: f64,
    read: f64,
    write: f64,
    refresh: f64,
    background: f64,
    total: f64,
}

fn recorded() -> Recorded {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/traces/dram/dramsim3.json");
    let text = std::fs::read_to_string(path).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The in-house configuration of DRAMsim3's file `name`.
fn config(name: &str) -> DramConfig {
    for_dramsim3_file(name).unwrap_or_else(|| panic!("no configuration for {name}"))
}

/// Relative difference of `ours` from `theirs`.
fn rel(ours: f64, theirs: f64) -> f64 {
    (ours - theirs) / theirs
}

/// The targets: cycles within 15 %, energy within 20 %.
const CYCLES: f64 = 0.15;
const ENERGY: f64 = 0.20;
/// Activations: the controller places a row miss's PRE and ACT as early as its bank
/// allows and sees each bank's command queue of reads and writes together, so a row
/// collects a few more hits than under DRAMsim3, whose refreshes also close open rows
/// (measured: -11.3 % to -3.6 % on the write-back traces).
const ACTS: f64 = 0.15;

/// Every recorded run: the same requests, reads and writes; cycles to the last completion
/// within 15 %; energy within 20 %, both against DRAMsim3's total without refresh (which
/// this controller does not model: the like-for-like figure) and with it; activations
/// within 15 % plus one per refresh DRAMsim3 issued (a refresh closes every open row of its
/// rank, so each may cost one activation this controller does not pay). Measured
/// (RESULTS.md, "The memory controller against DRAMsim3"): cycles -11.3 % to -1.5 %, energy
/// without refresh -6.7 % to +1.8 %, with it -15.4 % to -2.6 %.
#[test]
fn the_controller_agrees_with_dramsim3_on_every_recorded_run() {
    let traces = traces::all();
    let runs = recorded().runs;
    assert_eq!(
        runs.len(),
        7,
        "three traces on two memories and stream_200k on DDR4"
    );
    for run in &runs {
        let what = format!("{} on {}", run.trace, run.config);
        let (_, reqs) = traces
            .iter()
            .find(|(n, _)| *n == run.trace)
            .unwrap_or_else(|| panic!("no trace {}", run.trace));
        let s = replay(&config(&run.config), reqs).unwrap();
        assert_eq!(s.requests, run.requests, "{what}");
        assert_eq!(
            (s.atoms_read, s.atoms_written),
            (run.reads, run.writes),
            "{what}"
        );
        let cycles = rel(s.last_done as f64, run.dram_cycles as f64);
        assert!(cycles.abs() <= CYCLES, "{what}: cycles {cycles:+.3}");
        let e = &run.energy_pj;
        let parts = e.activate + e.read + e.write + e.refresh + e.background;
        assert!(
            (parts - e.total).abs() < 1.0,
            "{what}: DRAMsim3's energy split"
        );
        let ours = s.energy.total_pj();
        let like = rel(ours, e.total - e.refresh);
        let all = rel(ours, e.total);
        assert!(
            like.abs() <= ENERGY,
            "{what}: energy without refresh {like:+.3}"
        );
        assert!(all.abs() <= ENERGY, "{what}: energy {all:+.3}");
        let acts = s.activations.abs_diff(run.activations) as f64;
        let slack = ACTS * run.activations as f64 + run.refreshes as f64;
        assert!(
            acts <= slack,
            "{what}: {} activations, DRAMsim3 {}",
            s.activations,
            run.activations
        );
        assert!(
            (s.row_hit_rate() - run.row_hit_rate).abs() < 0.02,
            "{what}: row hits"
        );
    }
}
