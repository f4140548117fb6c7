//! The in-house DRAM controller against DRAMsim3 on real frames (issue 51, item 5): the
//! timed pipeline renders each frame of `examples/dram_check/frames.rs` with the DRAM
//! model, its controller's requests are replayed through `memory::dram::replay` and
//! compared with DRAMsim3's figures for the same trace, recorded in
//! `traces/dram/dramsim3.json` (`frame_runs`) by the example, which needs cmake and the
//! `dramsim3` feature (so this test reads the record instead of running DRAMsim3).

#[path = "../../examples/dram_check/frames.rs"]
mod frames;

use lembo_sim::memory::dram::{for_dramsim3_file, replay, DramConfig};
use serde::Deserialize;

#[derive(Deserialize)]
struct Recorded {
    frame_runs: Vec<FrameRun>,
}

#[derive(Deserialize)]
struct FrameRun {
    trace: String,
    config: String,
    requests: u64,
    reads: u64,
    writes: u64,
    checksum: String,
    dram_cycles: u64,
    activations: u64,
    row_hit_rate: f64,
    energy_pj: Energy,
}

#[derive(Deserialize)]
struct Energy {
    refresh: f64,
    total: f64,
}

/// The in-house configuration of DRAMsim3's file `name`.
fn config(name: &str) -> DramConfig {
    for_dramsim3_file(name).unwrap_or_else(|| panic!("no configuration for {name}"))
}

/// Relative difference of `ours` from `theirs`.
fn rel(ours: f64, theirs: f64) -> f64 {
    (ours - theirs) / theirs
}

const REFRESH: &str = "the pipeline's DRAM traffic changed: refresh the record with \
     `cargo run --release --example dram_check --features dramsim3 -- frames /tmp/dram_frames` \
     and copy /tmp/dram_frames/frame_runs.json into traces/dram/dramsim3.json's `frame_runs` \
     (examples/dram_check/README.md)";

/// Every recorded frame on both memories: the pipeline still sends the recorded trace
/// (same requests, reads, writes and checksum), and the controller's cycles to the last
/// completion are within 15 % of DRAMsim3's and its energy within 20 %, against DRAMsim3's
/// total without refresh (which the controller does not model) and with it. Measured
/// (RESULTS.md, "The memory controller against DRAMsim3"): cycles -1.3 % to +2.4 %, energy
/// without refresh -1.6 % to +2.2 %, with it -10.0 % to -2.6 %.
#[test]
fn dram_check_frames_agree_with_dramsim3() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/traces/dram/dramsim3.json");
    let text = std::fs::read_to_string(path).expect("the record");
    let runs = serde_json::from_str::<Recorded>(&text)
        .expect("the record parses")
        .frame_runs;
    assert_eq!(
        runs.len(),
        2 * frames::FRAMES.len(),
        "each frame on two memories"
    );
    for name in frames::FRAMES {
        let requests = frames::frame(name).expect("the frame renders");
        let reads = requests.iter().filter(|r| !r.write).count() as u64;
        let checksum = frames::checksum(&requests);
        for run in runs.iter().filter(|r| r.trace == name) {
            let what = format!("{name} on {}", run.config);
            assert_eq!(
                (requests.len() as u64, reads, checksum.as_str()),
                (run.requests, run.reads, run.checksum.as_str()),
                "{what}: {REFRESH}"
            );
            assert_eq!(run.requests, run.reads + run.writes, "{what}");
            let s = replay(&config(&run.config), &requests).expect("replay");
            let cycles = rel(s.last_done as f64, run.dram_cycles as f64);
            assert!(cycles.abs() <= 0.15, "{what}: cycles {cycles:+.3}");
            let e = &run.energy_pj;
            let ours = s.energy.total_pj();
            let like = rel(ours, e.total - e.refresh);
            let all = rel(ours, e.total);
            assert!(
                like.abs() <= 0.20,
                "{what}: energy without refresh {like:+.3}"
            );
            assert!(all.abs() <= 0.20, "{what}: energy {all:+.3}");
            // RESULTS.md's row (with --nocapture).
            let bytes = (run.requests * u64::from(config(&run.config).atom_bytes())) as f64;
            eprintln!(
                "| {name} | {} | {} / {} ({:+.1} %) | {:.2} / {:.2} | {} / {} | {:.1} / {:.1} \
                 | {:.1} / {:.1} ({:+.1} %) | {:.1} ({:+.1} %) |",
                run.config,
                s.last_done,
                run.dram_cycles,
                100.0 * cycles,
                bytes / s.last_done as f64,
                bytes / run.dram_cycles as f64,
                s.activations,
                run.activations,
                100.0 * s.row_hit_rate(),
                100.0 * run.row_hit_rate,
                ours * 1e-6,
                (e.total - e.refresh) * 1e-6,
                100.0 * like,
                e.total * 1e-6,
                100.0 * all
            );
        }
    }
}
