//! What DRAMsim3 counts, read back from its own statistics output.
//!
//! The `dramsim3` crate (0.2.2) exposes no statistics call: `MemorySystem` has `new`,
//! `tick`, `can_add`, `add`, `tck`, `bus_bits`, `burst_length` and `queue_size`, and its drop
//! does not call DRAMsim3's `PrintStats`. What DRAMsim3 does write without being asked is its
//! epoch file: every `epoch_period` cycles (`[other]` of the configuration) each channel
//! appends its counters for that epoch to `<dir>/dramsim3epoch.json` (DRAMsim3
//! `src/dram_system.cc`, `PrintEpochStats`; `src/simple_stats.cc`, `UpdateEpochStats`).
//! So the check runs each trace twice: once to find the cycle `C` of the last completion,
//! then with `epoch_period = C`, so that epoch 1 covers exactly that run and epoch 2 the same
//! number of cycles after it (where posted writes still in the write buffer drain).

use serde::Serialize;
use serde_json::Value;

/// A copy of a DRAMsim3 configuration with `[other] epoch_period` and `output_level`
/// replaced (output level 1: the epoch file, nothing on stdout).
pub fn with_epoch_period(ini: &str, epoch_period: u64) -> String {
    let ours = format!("epoch_period = {epoch_period}\noutput_level = 1\n");
    let mut out = String::with_capacity(ini.len() + ours.len());
    let mut section = String::new();
    let mut placed = false;
    for line in ini.lines() {
        let trimmed = line.trim();
        if let Some(name) = trimmed.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            section = name.trim().to_string();
            out.push_str(line);
            out.push('\n');
            if section == "other" && !placed {
                out.push_str(&ours);
                placed = true;
            }
            continue;
        }
        let key = trimmed.split('=').next().unwrap_or("").trim();
        if section == "other" && (key == "epoch_period" || key == "output_level") {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    if !placed {
        out.push_str("[other]\n");
        out.push_str(&ours);
    }
    out
}

/// One epoch's counters, summed over channels. Energies are DRAMsim3's, in its unit
/// V x mA x DRAM cycles (`Config::InitPowerParams`: the increments are voltage times current
/// times cycles, which is pJ only when tCK is 1 ns); [`Epoch::energy_pj`] converts.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Epoch {
    pub num_cycles: u64,
    pub num_reads_done: u64,
    pub num_writes_done: u64,
    pub num_write_buf_hits: u64,
    pub num_read_cmds: u64,
    pub num_write_cmds: u64,
    pub num_read_row_hits: u64,
    pub num_write_row_hits: u64,
    pub num_act_cmds: u64,
    pub num_pre_cmds: u64,
    pub num_ref_cmds: u64,
    pub num_refb_cmds: u64,
    pub act_energy: f64,
    pub read_energy: f64,
    pub write_energy: f64,
    pub ref_energy: f64,
    pub refb_energy: f64,
    /// Active standby, precharge standby and self-refresh energy, summed over ranks.
    pub background_energy: f64,
    pub total_energy: f64,
    /// DRAMsim3's `average_read_latency` times `num_reads_done`, summed over channels.
    pub read_latency_sum: f64,
}

const COUNTERS: [&str; 12] = [
    "num_cycles",
    "num_reads_done",
    "num_writes_done",
    "num_write_buf_hits",
    "num_read_cmds",
    "num_write_cmds",
    "num_read_row_hits",
    "num_write_row_hits",
    "num_act_cmds",
    "num_pre_cmds",
    "num_ref_cmds",
    "num_refb_cmds",
];

impl Epoch {
    /// Row-buffer hits over column commands (reads and writes issued to the DRAM).
    pub fn row_hit_rate(&self) -> f64 {
        let cmds = self.num_read_cmds + self.num_write_cmds;
        if cmds == 0 {
            return 0.0;
        }
        (self.num_read_row_hits + self.num_write_row_hits) as f64 / cmds as f64
    }

    /// The energies in pJ: DRAMsim3's V x mA x cycles times tCK in ns.
    pub fn energy_pj(&self, tck_ns: f64) -> EnergyPj {
        EnergyPj {
            activate: self.act_energy * tck_ns,
            read: self.read_energy * tck_ns,
            write: self.write_energy * tck_ns,
            refresh: (self.ref_energy + self.refb_energy) * tck_ns,
            background: self.background_energy * tck_ns,
            total: self.total_energy * tck_ns,
        }
    }

    fn add(&mut self, channel: &Value) -> Result<(), String> {
        let int = |k: &str| {
            channel[k]
                .as_u64()
                .ok_or_else(|| format!("epoch stats: `{k}` is missing or not a count"))
        };
        let real = |k: &str| {
            channel[k]
                .as_f64()
                .ok_or_else(|| format!("epoch stats: `{k}` is missing or not a number"))
        };
        let ranks = |k: &str| -> Result<f64, String> {
            let per_rank = channel[k]
                .as_object()
                .ok_or_else(|| format!("epoch stats: `{k}` is missing or not per rank"))?;
            Ok(per_rank.values().filter_map(Value::as_f64).sum())
        };
        let counts: Vec<u64> = COUNTERS.iter().map(|k| int(k)).collect::<Result<_, _>>()?;
        let fields = [
            &mut self.num_cycles,
            &mut self.num_reads_done,
            &mut self.num_writes_done,
            &mut self.num_write_buf_hits,
            &mut self.num_read_cmds,
            &mut self.num_write_cmds,
            &mut self.num_read_row_hits,
            &mut self.num_write_row_hits,
            &mut self.num_act_cmds,
            &mut self.num_pre_cmds,
            &mut self.num_ref_cmds,
            &mut self.num_refb_cmds,
        ];
        for (field, count) in fields.into_iter().zip(counts) {
            *field += count;
        }
        self.act_energy += real("act_energy")?;
        self.read_energy += real("read_energy")?;
        self.write_energy += real("write_energy")?;
        self.ref_energy += real("ref_energy")?;
        self.refb_energy += real("refb_energy")?;
        self.background_energy +=
            ranks("act_stb_energy")? + ranks("pre_stb_energy")? + ranks("sref_energy")?;
        self.total_energy += real("total_energy")?;
        self.read_latency_sum += real("average_read_latency")? * int("num_reads_done")? as f64;
        Ok(())
    }
}

/// Energies of an epoch in pJ.
#[derive(Clone, Debug, Serialize)]
pub struct EnergyPj {
    pub activate: f64,
    pub read: f64,
    pub write: f64,
    pub refresh: f64,
    pub background: f64,
    pub total: f64,
}

/// The epochs of a `dramsim3epoch.json` DRAMsim3 has not closed: `[` then one object per
/// channel and epoch, each followed by `,\n` (its `PrintStats` would replace the last comma
/// with `]`, and nothing calls it). Returns epoch `n` at index `n - 1`, channels summed.
pub fn parse_epochs(text: &str) -> Result<Vec<Epoch>, String> {
    let body = text.trim_end().trim_end_matches(',');
    let closed = if body.ends_with(']') {
        body.to_string()
    } else {
        format!("{body}]")
    };
    let channels: Vec<Value> =
        serde_json::from_str(&closed).map_err(|e| format!("epoch stats: {e}"))?;
    let mut epochs: Vec<Epoch> = Vec::new();
    for channel in &channels {
        let n = channel["epoch_num"]
            .as_u64()
            .filter(|&n| n >= 1)
            .ok_or("epoch stats: an entry without an epoch_num of 1 or more")?
            as usize;
        if epochs.len() < n {
            epochs.resize(n, Epoch::default());
        }
        epochs[n - 1].add(channel)?;
    }
    Ok(epochs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn epoch_period_is_replaced_in_other_only() {
        let ini = "[timing]\nepoch_period = 3\n[other]\nepoch_period = 1204819\noutput_level = 2\nx = 1\n";
        let out = with_epoch_period(ini, 77);
        assert_eq!(
            out,
            "[timing]\nepoch_period = 3\n[other]\nepoch_period = 77\noutput_level = 1\nx = 1\n"
        );
        let out = with_epoch_period("[system]\nchannels = 1\n", 5);
        assert!(
            out.ends_with("[other]\nepoch_period = 5\noutput_level = 1\n"),
            "{out}"
        );
    }

    fn channel(epoch: u64, ch: u64, cmds: u64) -> String {
        format!(
            r#"{{"channel":{ch},"epoch_num":{epoch},"num_cycles":100,"num_reads_done":{cmds},
            "num_writes_done":0,"num_write_buf_hits":0,"num_read_cmds":{cmds},
            "num_write_cmds":2,"num_read_row_hits":3,"num_write_row_hits":1,"num_act_cmds":1,
            "num_pre_cmds":0,"num_ref_cmds":0,"num_refb_cmds":0,"act_energy":1.5,
            "read_energy":2.0,"write_energy":0.5,"ref_energy":0.0,"refb_energy":0.0,
            "act_stb_energy":{{"0":10.0}},"pre_stb_energy":{{"0":1.0}},"sref_energy":{{"0":0.0}},
            "total_energy":15.0,"average_read_latency":2.5}}"#
        )
    }

    #[test]
    fn epochs_sum_channels_and_row_hits_count_column_commands() {
        let text = format!(
            "[{},\n{},\n{},\n",
            channel(1, 0, 4),
            channel(1, 1, 6),
            channel(2, 0, 0)
        );
        let e = parse_epochs(&text).unwrap();
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].num_read_cmds, 10);
        assert_eq!(e[0].num_cycles, 200);
        assert_eq!(e[0].background_energy, 22.0);
        // (3 + 1) hits of (4 + 2) commands on each of two channels.
        assert_eq!(e[0].row_hit_rate(), 8.0 / 14.0);
        assert_eq!(e[0].energy_pj(0.5).total, 15.0);
        assert_eq!(e[0].read_latency_sum, 2.5 * 10.0);
        assert_eq!(e[1].num_read_cmds, 0);
        let missing = parse_epochs(r#"[{"epoch_num":1},"#).unwrap_err();
        assert!(missing.contains("num_cycles"), "{missing}");
    }
}
