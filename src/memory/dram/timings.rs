//! The DRAM timings, in cycles of the command clock, and the name configuration errors
//! carry. Apart from `config.rs` so that the energies (computed from the timings) and the
//! configuration (which holds both) import them without a ring.

/// Where configuration errors say they come from.
pub(crate) const FILE: &str = "DRAM config";

/// The timings, in cycles of the DRAM command clock (JEDEC's nCK) but for the clock period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DramTimings {
    /// Command clock period \[ps\].
    pub tck_ps: u32,
    /// ACT to a read command \[cycles\].
    pub trcd_rd: u32,
    /// ACT to a write command \[cycles\] (GDDR6's tRCDWR; tRCD on DDR4).
    pub trcd_wr: u32,
    /// PRE to ACT, same bank \[cycles\].
    pub trp: u32,
    /// Read command to first data: CAS latency (CL, with AL = 0) \[cycles\].
    pub tcl: u32,
    /// Write command to first data: CAS write latency (CWL) \[cycles\].
    pub tcwl: u32,
    /// ACT to PRE, same bank \[cycles\].
    pub tras: u32,
    /// One atom's data on the bus \[cycles\].
    pub tburst: u32,
    /// End of write data to a read command, other bank group \[cycles\].
    pub twtr_s: u32,
    /// End of write data to a read command, same bank group \[cycles\].
    pub twtr_l: u32,
    /// Read command to write command (the bus turnaround, tRTW) \[cycles\].
    pub trtw: u32,
    /// Idle data-bus cycles between bursts of different ranks (tRTRS) \[cycles\].
    pub trtrs: u32,
    /// Column command to column command, other bank group \[cycles\].
    pub tccd_s: u32,
    /// Column command to column command, same bank group \[cycles\].
    pub tccd_l: u32,
    /// ACT to ACT, same rank, other bank group \[cycles\].
    pub trrd_s: u32,
    /// ACT to ACT, same rank, same bank group \[cycles\].
    pub trrd_l: u32,
    /// Window that holds at most four ACTs of one rank \[cycles\].
    pub tfaw: u32,
    /// Read command to PRE, same bank \[cycles\].
    pub trtp: u32,
    /// End of write data to PRE, same bank (write recovery) \[cycles\].
    pub twr: u32,
}

impl DramTimings {
    /// Each timing by name, for validation.
    pub(crate) fn named(&self) -> [(&'static str, u32); 19] {
        [
            ("timings.tck_ps", self.tck_ps),
            ("timings.trcd_rd", self.trcd_rd),
            ("timings.trcd_wr", self.trcd_wr),
            ("timings.trp", self.trp),
            ("timings.tcl", self.tcl),
            ("timings.tcwl", self.tcwl),
            ("timings.tras", self.tras),
            ("timings.tburst", self.tburst),
            ("timings.twtr_s", self.twtr_s),
            ("timings.twtr_l", self.twtr_l),
            ("timings.trtw", self.trtw),
            ("timings.trtrs", self.trtrs),
            ("timings.tccd_s", self.tccd_s),
            ("timings.tccd_l", self.tccd_l),
            ("timings.trrd_s", self.trrd_s),
            ("timings.trrd_l", self.trrd_l),
            ("timings.tfaw", self.tfaw),
            ("timings.trtp", self.trtp),
            ("timings.twr", self.twr),
        ]
    }

    /// The clock period \[ns\].
    pub fn tck_ns(&self) -> f64 {
        f64::from(self.tck_ps) / 1000.0
    }
}
