//! Presets: DDR4-2400 (x8 devices, one 64-bit channel), GDDR6 at 16 Gb/s (x16 channels)
//! and LPDDR5-6400 (x16 channels), each figure cited. The queues follow DRAMsim3's
//! `trans_queue_size = 32` and its write drain (a full write queue is drained until empty:
//! `Controller::ScheduleTransaction`, `src/controller.cc`), so the same trace run through
//! both differs by the models, not by the queue sizes. DDR4 keeps its file's mapping,
//! `rochrababgco`; the x16 presets (several channels, which DRAMsim3's one-channel files
//! never say how to interleave) take `rorabacobgch`: the channel lowest, so consecutive
//! atoms go to consecutive channels as a GPU spreads an address range, then the bank
//! group, so one channel's consecutive atoms alternate groups at tCCD_S, then the column.
//!
//! Measured (`cargo test --lib memory::dram::tests::measure -- --nocapture`, 20 000
//! requests of 64 bytes each (the test's size with debug assertions on), every request's
//! atoms arriving at cycle 0 and admitted in order; sequential: consecutive addresses;
//! random: uniform 64-byte-aligned addresses over 4 GiB, SplitMix64 seed 51):
//!
//! | preset | stream | cycles | bytes/cycle | of peak | row hits | pJ/B |
//! |---|---|---:|---:|---:|---:|---:|
//! | DDR4-2400 x8 | sequential | 99 401 | 12.88 | 80 % | 99.2 % | 99.3 |
//! | DDR4-2400 x8 | random | 81 410 | 15.72 | 98 % | 0.1 % | 143.8 |
//! | GDDR6 16 Gb/s x16 | sequential | 10 064 | 127.19 | 99 % | 99.2 % | 10.7 |
//! | GDDR6 16 Gb/s x16 | random | 60 978 | 20.99 | 16 % | 0.1 % | 46.2 |
//! | LPDDR5-6400 x16 | sequential | 20 037 | 63.88 | 100 % | 98.4 % | 21.1 |
//! | LPDDR5-6400 x16 | random | 40 445 | 31.65 | 49 % | 0.0 % | 98.2 |
//!
//! Cycles are each preset's command clock (0.833, 0.5 and 1.25 ns); pJ/B includes
//! background. DDR4's sequential stream stays in one bank group for a row (128 atoms)
//! under `rochrababgco`, at tCCD_L = 6 cycles a 4-cycle burst, and alternates groups at
//! tCCD_S only while the next row, opened ahead, overlaps it (`channel.rs`): 80 % of peak;
//! DRAMsim3 on the same file moves 12.42 bytes a cycle on 200 000 such reads (issue 51;
//! `traces/dram/dramsim3.json`). The controller's agreement with DRAMsim3 on the check's
//! traces is measured in `dramsim3_check.rs` and RESULTS.md.

use super::config::DramConfig;
use super::energy::{DramEnergy, IddCurrents};
use super::mapping::{AddressMapping, MapField};
use super::timings::DramTimings;

/// DRAMsim3's queue depth (`trans_queue_size` in every configuration file named here).
const QUEUE_DEPTH: u32 = 32;
/// DRAMsim3's per-bank command queue (`cmd_queue_size` in every file named here).
const BANK_WINDOW: u32 = 8;
/// DRAMsim3's row-hit cap (`CommandQueue::ArbitratePrecharge`, `src/command_queue.cc`).
const ROW_HIT_CAP: u32 = 4;

/// The x16 presets' mapping, `rorabacobgch`: the channel lowest, so consecutive atoms go
/// to consecutive channels (a GPU spreads an address range over every channel), then the
/// bank group, so consecutive atoms of one channel alternate groups and pay tCCD_S, not
/// tCCD_L, then the column, so each group's share of a stream stays in one row. DRAMsim3's
/// files have one channel each and say nothing of this; its `rochrababgco` keeps a stream in
/// one bank group, at tCCD_L a column command.
fn interleaved() -> AddressMapping {
    AddressMapping([
        MapField::Row,
        MapField::Rank,
        MapField::Bank,
        MapField::Column,
        MapField::BankGroup,
        MapField::Channel,
    ])
}

/// `cycles` of a clock of `from_ps` as cycles of a clock of `to_ps`, rounded up (JEDEC
/// rounds a time up to whole clocks).
const fn reclock(cycles: u32, from_ps: u32, to_ps: u32) -> u32 {
    (cycles * from_ps).div_ceil(to_ps)
}

/// DDR4-2400, 8 Gb x8 devices, one 64-bit channel of two ranks (eight devices each).
///
/// From DRAMsim3's `configs/DDR4_8Gb_x8_2400.ini` (JEDEC JESD79-4 speed bin DDR4-2400R,
/// 17-17-17): 4 bank groups of 4 banks, 65 536 rows, 1 024 columns, BL8, CL 17, CWL 12,
/// tRCD 17, tRP 17, tRAS 39, tRRD_S/L 4/6, tWTR_S/L 3/9, tFAW 26, tWR 18, tRTP 9, tCCD_S/L
/// 4/6, tRTRS 1; `channel_size = 16384` MB over 8 GB a rank gives two ranks; address mapping
/// `rochrababgco`. tCK 833 ps is JESD79-4's 0.833 ns for 2400 MT/s (the file rounds it to
/// 0.83). The atom is 64 B (8 B bus, BL8) in tBURST = BL/2 = 4 cycles; a row of a rank is
/// 1 024 columns of 8 B = 128 atoms. tRTW = CL + tBURST + 2 - CWL = 11 (JESD79-4's read to
/// write: RL + BL/2 - WL + 2 tCK). Energy from the file's `[power]` section (VDD 1.2 V,
/// IDD0 48, IDD2N 34, IDD3N 43, IDD4R 135, IDD4W 123 mA) by [`DramEnergy::from_idd`]:
/// 2 943 pJ a read atom, 2 559 pJ a write atom, 3 463 pJ an activation.
pub fn ddr4_2400_x8() -> DramConfig {
    let timings = DramTimings {
        tck_ps: 833,
        trcd_rd: 17,
        trcd_wr: 17,
        trp: 17,
        tcl: 17,
        tcwl: 12,
        tras: 39,
        tburst: 4,
        twtr_s: 3,
        twtr_l: 9,
        trtw: 17 + 4 + 2 - 12,
        trtrs: 1,
        tccd_s: 4,
        tccd_l: 6,
        trrd_s: 4,
        trrd_l: 6,
        tfaw: 26,
        trtp: 9,
        twr: 18,
    };
    let idd = IddCurrents {
        vdd: 1.2,
        idd0: 48.0,
        idd2n: 34.0,
        idd3n: 43.0,
        idd4r: 135.0,
        idd4w: 123.0,
        devices: 8,
    };
    DramConfig {
        name: "DDR4-2400 x8".to_string(),
        channels: 1,
        ranks: 2,
        bank_groups: 4,
        banks_per_group: 4,
        rows: 65536,
        atoms_per_row: 1024 / 8,
        bus_bits: 64,
        burst_length: 8,
        mapping: AddressMapping::ROCHRABABGCO,
        timings,
        queue_depth: QUEUE_DEPTH,
        write_high: QUEUE_DEPTH,
        write_low: 0,
        bank_window: BANK_WINDOW,
        row_hit_cap: ROW_HIT_CAP,
        bank_xor: false,
        energy: DramEnergy::from_idd(&idd, &timings),
    }
}

/// GDDR6 at 16 Gb/s a pin: eight x16 channels (four x32 devices, a 128-bit interface).
///
/// Organisation and timings from DRAMsim3's `configs/GDDR6_8Gb_x16.ini` (JEDEC JESD250):
/// 16 banks (`bankgroup_enable = false`: one group), 16 384 rows, 128 columns of BL16 x 16
/// bits = 32 B (so 128 atoms a row), CL 24, CWL 16, tRCDRD 24, tRCDWR 20, tRP 24, tRAS 54,
/// tRRD 9, tWTR 7, tFAW 32, tWR 16, tRTP 3, tRTRS 1, all at the file's tCK of 0.66 ns. This preset
/// runs the command clock at 2 GHz (tCK 0.5 ns), where 16 Gb/s moves BL16 in 2 cycles
/// (8 bits a pin a clock), and takes each of the file's times to that clock rounded up
/// (n x 0.66 / 0.5). tCCD is taken as tBURST = 2: back-to-back bursts keep a channel's pins
/// busy at 16 Gb/s; the file's tCCD_L = 4 at 0.66 ns (2.64 ns a 32-byte burst) would cap a
/// channel at 38 % of its pins, and its `burst_cycle = BL/16 = 1` is 24 Gb/s, so the file
/// is not self-consistent there. Mapping `rorabacobgch` (channel lowest: the module doc).
/// tRTW = CL + tBURST + 2 - CWL. Energy from the file's
/// `[power]` section (VDD 1.35 V, IDD0 71, IDD2N 60, IDD3N 61, IDD4R 248, IDD4W 231 mA,
/// one x16 device a channel as the file counts them) by [`DramEnergy::from_idd`]: the DRAM
/// core only, about 1 pJ/bit; a system figure with the interface (GDDR6 about 7.5 pJ/bit,
/// issue 51) goes in through [`DramEnergy::per_bit`].
pub fn gddr6_16g_x16() -> DramConfig {
    let r = |cycles| reclock(cycles, 660, 500);
    let (tcl, tcwl, tburst) = (r(24), r(16), 2);
    let timings = DramTimings {
        tck_ps: 500,
        trcd_rd: r(24),
        trcd_wr: r(20),
        trp: r(24),
        tcl,
        tcwl,
        tras: r(54),
        tburst,
        twtr_s: r(7),
        twtr_l: r(7),
        trtw: tcl + tburst + 2 - tcwl,
        trtrs: r(1),
        tccd_s: tburst,
        tccd_l: tburst,
        trrd_s: r(9),
        trrd_l: r(9),
        tfaw: r(32),
        trtp: r(3),
        twr: r(16),
    };
    let idd = IddCurrents {
        vdd: 1.35,
        idd0: 71.0,
        idd2n: 60.0,
        idd3n: 61.0,
        idd4r: 248.0,
        idd4w: 231.0,
        devices: 1,
    };
    DramConfig {
        name: "GDDR6 16 Gb/s x16".to_string(),
        channels: 8,
        ranks: 1,
        bank_groups: 1,
        banks_per_group: 16,
        rows: 16384,
        atoms_per_row: 128,
        bus_bits: 16,
        burst_length: 16,
        mapping: interleaved(),
        timings,
        queue_depth: QUEUE_DEPTH,
        write_high: QUEUE_DEPTH,
        write_low: 0,
        bank_window: BANK_WINDOW,
        row_hit_cap: ROW_HIT_CAP,
        bank_xor: false,
        energy: DramEnergy::from_idd(&idd, &timings),
    }
}

/// LPDDR5-6400, 8 Gb x16: four x16 channels (a 64-bit interface).
///
/// DRAMsim3 ships no LPDDR5 file. Timings from Ramulator 2.0 (Luo et al., IEEE CAL 2023),
/// `src/dram/impl/LPDDR5.cpp`, preset `LPDDR5_6400` (JEDEC JESD209-5, bank-group mode):
/// tCK 1.25 ns (CK 800 MHz), CL 20, CWL 11, tRCD 15, tRPpb 15, tRAS 34, tWR 28, tRTP 4,
/// tCCD 4 (same group), tRRD 4, tWTR_S/L 5/10, tFAW 16, nCS 2 (taken as tRTRS); organisation `LPDDR5_8Gb_x16`: 4
/// bank groups of 4 banks, 32 768 rows, 1 024 columns of 16 bits (a 2 KB row: 64 atoms).
/// The atom is 32 B (x16, BL16); at 6400 MT/s it takes 2.5 ns = tBURST 2 cycles (8 bits a
/// pin a clock), which is also tCCD to another group. Mapping `rorabacobgch` (channel
/// lowest: the module doc). tRTW = CL + tBURST + 2 - CWL.
/// Energy: DRAMsim3's LPDDR4 currents (`configs/LPDDR4_8Gb_x16_2400.ini`: IDD0 80, IDD2N
/// 34, IDD3N 47, IDD4R 243, IDD4W 228 mA, one x16 device a channel) at LPDDR5's VDD2H of
/// 1.05 V (JESD209-5) by [`DramEnergy::from_idd`]: a stand-in until an LPDDR5 datasheet's
/// currents are taken.
pub fn lpddr5_6400_x16() -> DramConfig {
    let (tcl, tcwl, tburst) = (20, 11, 2);
    let timings = DramTimings {
        tck_ps: 1250,
        trcd_rd: 15,
        trcd_wr: 15,
        trp: 15,
        tcl,
        tcwl,
        tras: 34,
        tburst,
        twtr_s: 5,
        twtr_l: 10,
        trtw: tcl + tburst + 2 - tcwl,
        trtrs: 2,
        tccd_s: tburst,
        tccd_l: 4,
        trrd_s: 4,
        trrd_l: 4,
        tfaw: 16,
        trtp: 4,
        twr: 28,
    };
    let idd = IddCurrents {
        vdd: 1.05,
        idd0: 80.0,
        idd2n: 34.0,
        idd3n: 47.0,
        idd4r: 243.0,
        idd4w: 228.0,
        devices: 1,
    };
    DramConfig {
        name: "LPDDR5-6400 x16".to_string(),
        channels: 4,
        ranks: 1,
        bank_groups: 4,
        banks_per_group: 4,
        rows: 32768,
        atoms_per_row: 64,
        bus_bits: 16,
        burst_length: 16,
        mapping: interleaved(),
        timings,
        queue_depth: QUEUE_DEPTH,
        write_high: QUEUE_DEPTH,
        write_low: 0,
        bank_window: BANK_WINDOW,
        row_hit_cap: ROW_HIT_CAP,
        bank_xor: false,
        energy: DramEnergy::from_idd(&idd, &timings),
    }
}

/// GDDR6 as DRAMsim3's `configs/GDDR6_8Gb_x16.ini` describes it, every figure the file's:
/// the memory the DRAM check runs on DRAMsim3 (`examples/dram_check`), so the in-house
/// controller is compared with it on the same system. Unlike [`gddr6_16g_x16`] (eight x16
/// channels, 32-byte atoms): one 128-bit channel of eight x16 devices, BL16, so one column
/// command moves 256 B, in DRAMsim3's `burst_cycle = BL/16 = 1` cycle at tCK 0.66 ns;
/// `bankgroup_enable = false`, so 16 banks in one group and DRAMsim3 takes the `_S`
/// timings for both (`Timing::Timing`, `src/timing.cc`): tCCD = tCCD_S = 3, tRRD 9,
/// tWTR 7; 16 384 rows of 2 048 columns (`columns x BL`, `Config::InitDRAMParams`) = 128
/// atoms; CL 24, CWL 16, tRCDRD 24, tRCDWR 20, tRP 24, tRAS 54, tFAW 32, tWR 16, tRTP 3,
/// tRTRS 1; tRTW = CL + burst - CWL + tRTRS = 10 (DRAMsim3's `read_to_write`); mapping
/// `rochrababgco`. Energy from the file's `[power]` section with DRAMsim3's eight devices
/// (bus width over device width).
pub fn gddr6_dramsim3_x128() -> DramConfig {
    let (tcl, tcwl, tburst, trtrs) = (24, 16, 1, 1);
    let timings = DramTimings {
        tck_ps: 660,
        trcd_rd: 24,
        trcd_wr: 20,
        trp: 24,
        tcl,
        tcwl,
        tras: 54,
        tburst,
        twtr_s: 7,
        twtr_l: 7,
        trtw: tcl + tburst - tcwl + trtrs,
        trtrs,
        tccd_s: 3,
        tccd_l: 3,
        trrd_s: 9,
        trrd_l: 9,
        tfaw: 32,
        trtp: 3,
        twr: 16,
    };
    let idd = IddCurrents {
        vdd: 1.35,
        idd0: 71.0,
        idd2n: 60.0,
        idd3n: 61.0,
        idd4r: 248.0,
        idd4w: 231.0,
        devices: 8,
    };
    DramConfig {
        name: "GDDR6 x128 (DRAMsim3's file)".to_string(),
        channels: 1,
        ranks: 1,
        bank_groups: 1,
        banks_per_group: 16,
        rows: 16384,
        atoms_per_row: 128,
        bus_bits: 128,
        burst_length: 16,
        mapping: AddressMapping::ROCHRABABGCO,
        timings,
        queue_depth: QUEUE_DEPTH,
        write_high: QUEUE_DEPTH,
        write_low: 0,
        bank_window: BANK_WINDOW,
        row_hit_cap: ROW_HIT_CAP,
        bank_xor: false,
        energy: DramEnergy::from_idd(&idd, &timings),
    }
}

/// The preset that models DRAMsim3's configuration file `name` (its stem, as
/// `traces/dram/dramsim3.json` records it), for runs compared against DRAMsim3; None for a
/// file no preset models.
pub fn for_dramsim3_file(name: &str) -> Option<DramConfig> {
    match name {
        "DDR4_8Gb_x8_2400" => Some(ddr4_2400_x8()),
        "GDDR6_8Gb_x16" => Some(gddr6_dramsim3_x128()),
        _ => None,
    }
}
