//! The controller's tests: exact small cases computed by hand from the timings, the
//! bandwidth and row-buffer behaviour of streams, bad configurations, the every-request-
//! once property, determinism, and the presets' measurements.

use super::*;
use crate::error::Error;
use crate::memory::trace::Request;
use crate::testkit::SplitMix64;

/// One channel, one rank, 2 groups of 2 banks, 1024 rows of 16 atoms of 64 B; timings
/// chosen distinct so each sum below names its terms.
fn tiny() -> DramConfig {
    let timings = DramTimings {
        tck_ps: 1000,
        trcd_rd: 10,
        trcd_wr: 10,
        trp: 9,
        tcl: 7,
        tcwl: 5,
        tras: 20,
        tburst: 4,
        twtr_s: 2,
        twtr_l: 3,
        trtw: 8,
        trtrs: 1,
        tccd_s: 4,
        tccd_l: 5,
        trrd_s: 3,
        trrd_l: 4,
        tfaw: 20,
        trtp: 4,
        twr: 6,
    };
    DramConfig {
        name: "tiny".to_string(),
        channels: 1,
        ranks: 1,
        bank_groups: 2,
        banks_per_group: 2,
        rows: 1024,
        atoms_per_row: 16,
        bus_bits: 64,
        burst_length: 8,
        mapping: AddressMapping::ROCHRABABGCO,
        timings,
        queue_depth: 8,
        write_high: 4,
        write_low: 1,
        bank_window: 8,
        row_hit_cap: u32::MAX,
        energy: DramEnergy::per_bit(1.0, 100.0, 64),
        bank_xor: false,
    }
}

/// The byte address of (group, bank, row, column) in [`tiny`] (`rochrababgco`: 6 offset
/// bits, 4 column bits, 1 group bit, 1 bank bit, then the row).
fn at(bg: u64, bank: u64, row: u64, col: u64) -> u64 {
    ((((row << 1 | bank) << 1 | bg) << 4 | col) << 6) + 3
}

fn read(addr: u64, arrival: u64) -> Request {
    Request {
        addr,
        write: false,
        arrival,
    }
}

fn write(addr: u64, arrival: u64) -> Request {
    Request {
        addr,
        write: true,
        arrival,
    }
}

/// Every request's completion cycle, by ticket.
fn done_times(cfg: &DramConfig, reqs: &[Request]) -> Vec<u64> {
    let mut dram = Dram::new(cfg).unwrap();
    for r in reqs {
        dram.submit(*r);
    }
    dram.finish();
    let mut c = dram.complete();
    c.sort_by_key(|c| c.ticket);
    c.iter().map(|c| c.done).collect()
}

#[test]
fn a_read_from_idle_takes_trcd_plus_cl_plus_the_burst() {
    assert_eq!(
        done_times(&tiny(), &[read(at(1, 1, 5, 3), 0)]),
        [10 + 7 + 4]
    );
    assert_eq!(done_times(&tiny(), &[read(at(1, 1, 5, 3), 50)]), [50 + 21]);
}

#[test]
fn a_second_read_of_the_open_row_is_a_hit_one_tccd_later() {
    let cfg = tiny();
    let reqs = [read(at(0, 1, 5, 3), 0), read(at(0, 1, 5, 9), 0)];
    assert_eq!(done_times(&cfg, &reqs), [21, 21 + 5]);
    let s = replay(&cfg, &reqs).unwrap();
    assert_eq!((s.activations, s.row_hits, s.row_misses), (1, 1, 1));
}

#[test]
fn another_row_of_the_same_bank_pays_trp_and_trcd() {
    let cfg = tiny();
    // Arriving after tRAS, the PRE issues at once: 100 + tRP + tRCD + CL + tBURST.
    let reqs = [read(at(0, 1, 5, 3), 0), read(at(0, 1, 6, 3), 100)];
    assert_eq!(done_times(&cfg, &reqs), [21, 100 + 9 + 10 + 7 + 4]);
    let s = replay(&cfg, &reqs).unwrap();
    assert_eq!((s.activations, s.precharges, s.row_conflicts), (2, 1, 1));
    // Arriving at once, the PRE waits for tRAS from the first ACT: 20 + 9 + 10 + 7 + 4.
    let reqs = [read(at(0, 1, 5, 3), 0), read(at(0, 1, 6, 3), 0)];
    assert_eq!(done_times(&cfg, &reqs), [21, 50]);
}

#[test]
fn a_read_after_a_write_waits_twtr_after_the_write_data() {
    // The write: ACT 0, WR at tRCD 10, data to 10 + CWL 5 + tBURST 4 = 19. The read (same
    // group): RD at 19 + tWTR_L 3 = 22, done 22 + 7 + 4 = 33.
    let reqs = [write(at(0, 0, 2, 0), 0), read(at(0, 0, 2, 1), 1)];
    assert_eq!(done_times(&tiny(), &reqs), [19, 33]);
    // Another group: its own ACT (tRRD_S after the first: 3), RD at 19 + tWTR_S 2 = 21.
    let reqs = [write(at(0, 0, 2, 0), 0), read(at(1, 0, 2, 1), 1)];
    assert_eq!(done_times(&tiny(), &reqs), [19, 21 + 11]);
}

#[test]
fn a_write_after_a_read_waits_the_turnaround() {
    // RD at 10 (done 21); WR at RD + tRTW 8 = 18, data to 18 + 5 + 4 = 27.
    let reqs = [read(at(0, 0, 2, 0), 0), write(at(0, 0, 2, 1), 1)];
    assert_eq!(done_times(&tiny(), &reqs), [21, 27]);
}

#[test]
fn writes_wait_for_reads_until_the_high_watermark_then_drain_to_the_low() {
    // A bank's command queue of one request, so the watermarks on the writes waiting in the
    // transaction queue alone decide the order (a write already moved into its bank's
    // command queue is served alongside the reads, as DRAMsim3 issues what those hold).
    let cfg = DramConfig {
        bank_window: 1,
        ..tiny()
    };
    let order = |n_writes: u64| {
        let mut reqs: Vec<Request> = (0..n_writes).map(|i| write(at(0, 0, 1, i), 0)).collect();
        reqs.extend((0..3).map(|i| read(at(0, 0, 1, 8 + i), 0)));
        let done = done_times(&cfg, &reqs);
        let mut by_done: Vec<(u64, bool)> =
            done.iter().zip(&reqs).map(|(d, r)| (*d, r.write)).collect();
        by_done.sort();
        by_done
            .iter()
            .map(|(_, w)| if *w { 'W' } else { 'R' })
            .collect::<String>()
    };
    // Three writes (below write_high 4): the reads go first.
    assert_eq!(order(3), "RRRWWW");
    // Four: a drain to write_low 1 (three writes), the reads, then the last write.
    assert_eq!(order(4), "WWWRRRW");
}

/// 64-byte requests at consecutive addresses (sequential) or uniform over 4 GiB (random),
/// every atom arriving at 0, expanded to the preset's atoms.
fn stream(cfg: &DramConfig, n: u64, random: bool) -> Vec<Request> {
    let atom = u64::from(cfg.atom_bytes());
    let per = 64u64.div_ceil(atom);
    let mut rng = SplitMix64::new(51);
    let mut out = Vec::with_capacity((n * per) as usize);
    for i in 0..n {
        let base = if random {
            rng.below(1 << 26) * 64
        } else {
            i * 64
        };
        out.extend((0..per).map(|k| read(base + k * atom, 0)));
    }
    out
}

#[test]
fn a_sequential_stream_nears_the_peak_and_random_reads_rarely_hit() {
    for (cfg, least) in [
        (ddr4_2400_x8(), 0.6),
        (gddr6_16g_x16(), 0.75),
        (lpddr5_6400_x16(), 0.7),
    ] {
        let s = replay(&cfg, &stream(&cfg, 20_000, false)).unwrap();
        let fraction = s.bytes_per_cycle / cfg.peak_bytes_per_cycle();
        assert!(fraction >= least, "{}: {fraction:.3} of the peak", cfg.name);
        assert!(
            s.row_hit_rate() > 0.95,
            "{}: {}",
            cfg.name,
            s.row_hit_rate()
        );
        let r = replay(&cfg, &stream(&cfg, 20_000, true)).unwrap();
        assert!(r.row_hit_rate() < 0.1, "{}: {}", cfg.name, r.row_hit_rate());
        assert!(
            r.activations as f64 > 0.9 * r.requests as f64,
            "{}",
            cfg.name
        );
    }
}

#[test]
fn halving_bytes_per_cycle_takes_at_least_1_6_times_the_cycles_each_time() {
    // Halved twice by channels, and twice by a longer burst (tCCD with it).
    let cycles = |cfg: &DramConfig| replay(cfg, &stream(cfg, 8_000, false)).unwrap().last_done;
    let mut cfg = gddr6_16g_x16();
    let mut last = cycles(&cfg);
    for channels in [4, 2] {
        cfg.channels = channels;
        let now = cycles(&cfg);
        assert!(
            now as f64 >= 1.6 * last as f64,
            "{channels} channels: {now} after {last}"
        );
        last = now;
    }
    let mut cfg = gddr6_16g_x16();
    let mut last = cycles(&cfg);
    for tburst in [4, 8] {
        cfg.timings.tburst = tburst;
        cfg.timings.tccd_s = tburst;
        cfg.timings.tccd_l = tburst;
        let now = cycles(&cfg);
        assert!(
            now as f64 >= 1.6 * last as f64,
            "tBURST {tburst}: {now} after {last}"
        );
        last = now;
    }
}

fn refused_field(cfg: &DramConfig) -> String {
    match Dram::new(cfg) {
        Err(Error::Invalid { field, .. }) => field,
        other => panic!("expected Error::Invalid, got {:?}", other.map(|_| ())),
    }
}

#[test]
fn bad_configurations_are_refused_naming_the_field() {
    type Spoil = fn(&mut DramConfig);
    let cases: [(&str, Spoil); 9] = [
        ("channels", |c| c.channels = 0),
        ("channels", |c| c.channels = 3),
        ("atoms_per_row", |c| c.atoms_per_row = 0),
        ("timings.trcd_rd", |c| c.timings.trcd_rd = 0),
        ("timings.tck_ps", |c| c.timings.tck_ps = 0),
        ("timings.tfaw", |c| c.timings.tfaw = 0),
        ("write_high", |c| c.write_high = 9),
        ("write_low", |c| c.write_low = 4),
        ("energy.activation_pj", |c| {
            c.energy.activation_pj = f64::NAN
        }),
    ];
    for (field, spoil) in cases {
        let mut cfg = tiny();
        spoil(&mut cfg);
        assert_eq!(refused_field(&cfg), field);
        assert!(replay(&cfg, &[]).is_err());
    }
    for cfg in [tiny(), ddr4_2400_x8(), gddr6_16g_x16(), lpddr5_6400_x16()] {
        cfg.validate().unwrap();
    }
}

/// The first broken promise of a run's completions: every ticket once, none before its
/// request's arrival plus the shortest access, in (done, ticket) order.
fn check_completions(cfg: &DramConfig, reqs: &[Request], got: &[Completion]) -> Option<String> {
    let mut seen = vec![false; reqs.len()];
    let t = &cfg.timings;
    for (i, c) in got.iter().enumerate() {
        let k = c.ticket.0 as usize;
        let r = reqs.get(k)?;
        if std::mem::replace(&mut seen[k], true) {
            return Some(format!("ticket {k} twice"));
        }
        let least = if r.write { t.tcwl } else { t.tcl } + t.tburst;
        if c.done < r.arrival + u64::from(least) {
            return Some(format!(
                "ticket {k} done at {} before {}",
                c.done, r.arrival
            ));
        }
        if i > 0 && got[i - 1] > *c {
            return Some(format!("completions out of order at {i}"));
        }
    }
    seen.iter()
        .position(|s| !s)
        .map(|k| format!("ticket {k} never completed"))
}

#[test]
fn every_request_completes_exactly_once_whatever_the_polling() {
    let mut rng = SplitMix64::new(7);
    for case in 0..40 {
        let mut cfg = tiny();
        cfg.channels = 1 << rng.below(3);
        cfg.ranks = 1 << rng.below(2);
        cfg.queue_depth = 1 + rng.below(8) as u32;
        cfg.write_high = 1 + rng.below(u64::from(cfg.queue_depth)) as u32;
        cfg.write_low = rng.below(u64::from(cfg.write_high)) as u32;
        let mut arrival = 0;
        let reqs: Vec<Request> = (0..300)
            .map(|_| {
                arrival += rng.below(6);
                let addr = rng.below(1 << 20) * 8;
                Request {
                    addr,
                    write: rng.below(3) == 0,
                    arrival,
                }
            })
            .collect();
        let mut dram = Dram::new(&cfg).unwrap();
        let mut got = Vec::new();
        for (i, r) in reqs.iter().enumerate() {
            assert_eq!(dram.submit(*r), Ticket(i as u64));
            if rng.below(4) == 0 {
                dram.run_until(r.arrival + rng.below(50));
                got.extend(dram.complete());
            }
        }
        dram.finish();
        got.extend(dram.complete());
        assert_eq!(check_completions(&cfg, &reqs, &got), None, "case {case}");
        assert_eq!(dram.stats().requests, reqs.len() as u64);
        // The checker catches a planted duplicate and a planted loss.
        let mut dup = got.clone();
        dup.push(*got.last().unwrap());
        assert!(check_completions(&cfg, &reqs, &dup).is_some());
        assert!(check_completions(&cfg, &reqs, &got[1..]).is_some());
    }
}

#[test]
fn runs_are_deterministic() {
    let cfg = gddr6_16g_x16();
    let mut reqs = stream(&cfg, 3_000, true);
    for (i, r) in reqs.iter_mut().enumerate() {
        r.write = i % 3 == 0;
        r.arrival = i as u64 / 4;
    }
    assert_eq!(replay(&cfg, &reqs).unwrap(), replay(&cfg, &reqs).unwrap());
    assert_eq!(done_times(&cfg, &reqs), done_times(&cfg, &reqs));
}

#[test]
fn energy_counts_atoms_and_activations() {
    // tiny: 1 pJ/bit, 64-byte atoms (512 pJ each), 100 pJ an activation, no background.
    let reqs = [
        read(at(0, 1, 5, 3), 0),
        read(at(0, 1, 5, 4), 0),
        write(at(1, 0, 7, 0), 0),
    ];
    let s = replay(&tiny(), &reqs).unwrap();
    assert_eq!((s.atoms_read, s.atoms_written, s.bytes_read), (2, 1, 128));
    assert_eq!(s.energy.read_pj, 1024.0);
    assert_eq!(s.energy.write_pj, 512.0);
    assert_eq!(s.energy.activation_pj, 200.0);
    assert_eq!(s.energy.background_pj, 0.0);
}

#[test]
fn presets_energies_follow_dramsim3s_formulas() {
    // DDR4-2400 x8: 1.2 V x (135 - 43) mA x 4 x 0.833 ns x 8 devices.
    let e = ddr4_2400_x8().energy;
    assert!((e.read_atom_pj - 1.2 * 92.0 * 4.0 * 0.833 * 8.0).abs() < 1e-6);
    // Activation: 1.2 x (48 x 56 - (43 x 39 + 34 x 17)) x 0.833 x 8.
    assert!((e.activation_pj - 1.2 * 433.0 * 0.833 * 8.0).abs() < 1e-6);
}

/// The presets' measurement quoted in `presets.rs`; run with `-- --nocapture` to print.
#[test]
fn measure() {
    let n = if cfg!(debug_assertions) {
        20_000
    } else {
        200_000
    };
    println!("| preset | stream | cycles | B/cycle | of peak | row hits | pJ/B | host ms |");
    for cfg in [ddr4_2400_x8(), gddr6_16g_x16(), lpddr5_6400_x16()] {
        for random in [false, true] {
            let reqs = stream(&cfg, n, random);
            let start = std::time::Instant::now();
            let s = replay(&cfg, &reqs).unwrap();
            let ms = start.elapsed().as_secs_f64() * 1e3;
            println!(
                "| {} | {} | {} | {:.2} | {:.0} % | {:.1} % | {:.1} | {:.0} |",
                cfg.name,
                if random { "random" } else { "sequential" },
                s.last_done,
                s.bytes_per_cycle,
                100.0 * s.bytes_per_cycle / cfg.peak_bytes_per_cycle(),
                100.0 * s.row_hit_rate(),
                s.pj_per_byte(),
                ms
            );
            assert_eq!(s.requests, reqs.len() as u64);
        }
    }
}
