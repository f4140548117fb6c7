//! One channel's controller: its read and write queues, the write drain, FR-FCFS choice and
//! the bank, rank and bus state that times each request's commands.
//!
//! **Timing.** A request is scheduled at a decision time `t` as a group of commands, the
//! earliest each may issue given what was scheduled before it:
//! - a row hit: one column command (RD or WR);
//! - a miss (bank precharged): ACT, then the column command tRCD later;
//! - a conflict (another row open): PRE (after tRAS from its ACT, tRTP from its last read,
//!   tWR from its last write data), ACT tRP later, the column command tRCD after that.
//!
//! ACTs respect tRRD (S or L by bank group) and tFAW per rank; column commands tCCD (S or
//! L) after the previous one, tWTR (S or L) after the end of write data before a read, tRTW
//! after a read before a write; data (CL or CWL after the command, tBURST long) never
//! overlaps on the bus, and bursts of two ranks are tRTRS apart. A read completes when its
//! last data beat arrives, a write when its last beat is sent. The next decision is at the
//! chosen request's first command (at least one cycle later), so ACTs to other banks
//! overlap earlier requests' tRCD, and column commands issue in decision order. While one
//! bank streams hits, each decision also opens ahead the row of one other bank that no
//! queued request hits, as DRAMsim3 issues any bank's ready ACT between another bank's
//! column commands: a sequential stream crossing into the next bank group then alternates
//! groups at tCCD_S instead of waiting tCCD_L a command (on DDR4-2400, `stream_200k` of
//! [`super::traces`] moves 12.35 bytes a cycle, DRAMsim3 12.42; 10.30 without it). The
//! choice looks at each bank's oldest `bank_window` requests (DRAMsim3's per-bank command
//! queue), which bounds how many hits a row collects before it is closed.
//!
//! **Not modelled**, each a simplification to state when comparing with DRAMsim3: refresh
//! (tRFC every tREFI: 4.5 % of DDR4-2400's cycles), the one-command-per-cycle command bus,
//! reads served from the write queue, and power-down.

use super::config::DramConfig;
use super::mapping::Location;
use super::timings::DramTimings;

/// A request waiting in a queue.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Queued {
    pub ticket: u64,
    /// The cycle it arrived (latency counts from here).
    pub arrival: u64,
    /// The cycle it may be admitted: its arrival, or the horizon the caller had already
    /// run to when it was submitted.
    pub ready: u64,
    pub write: bool,
    pub loc: Location,
}

/// What the row buffer held when a request was scheduled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RowOutcome {
    Hit,
    /// The bank was precharged.
    Miss,
    /// Another row was open.
    Conflict,
}

/// A request scheduled: its outcome, when its first command issues and when it is done.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scheduled {
    pub req: Queued,
    pub outcome: RowOutcome,
    pub first_command: u64,
    pub done: u64,
}

#[derive(Clone, Copy, Debug, Default)]
struct Bank {
    open: Option<u32>,
    /// Earliest PRE.
    ready_pre: u64,
    /// The last ACT's cycle (a column command waits tRCD after it).
    act: u64,
    /// Column commands since the last ACT (the row-hit cap).
    columns: u32,
    /// The row was opened ahead of its request ([`Channel::prepare`]): the outcome that
    /// request is counted with when it is scheduled.
    prepared: Option<RowOutcome>,
}

/// Per bank while choosing: requests seen, and whether its oldest is a conflict.
#[derive(Clone, Copy, Debug, Default)]
struct Seen {
    count: u32,
    head_conflict: bool,
    has_hit: bool,
}

#[derive(Clone, Copy, Debug, Default)]
struct Rank {
    /// The last four ACTs' cycles, a ring (tFAW).
    acts: [Option<u64>; 4],
    head: usize,
    /// The last ACT's cycle and bank group (tRRD).
    last_act: Option<(u64, u32)>,
    /// The first ACT's cycle (background energy).
    first_act: Option<u64>,
}

/// One channel.
#[derive(Clone, Debug)]
pub(crate) struct Channel {
    pub reads: Vec<Queued>,
    pub writes: Vec<Queued>,
    draining: bool,
    /// The next decision's cycle while a queue holds a request.
    pub clock: u64,
    banks: Vec<Bank>,
    ranks: Vec<Rank>,
    /// The last column command: cycle, rank, bank group.
    last_col: Option<(u64, u32, u32)>,
    /// The last write's end of data: cycle, rank, bank group.
    last_write_end: Option<(u64, u32, u32)>,
    /// The last read command's cycle.
    last_read: Option<u64>,
    /// The cycle the data bus is free.
    bus_free: u64,
    /// Scratch per bank for [`Channel::choose`] and [`Channel::prepare`].
    seen: Vec<Seen>,
}

impl Channel {
    pub(crate) fn new(cfg: &DramConfig) -> Channel {
        let banks = cfg.ranks * cfg.bank_groups * cfg.banks_per_group;
        Channel {
            reads: Vec::with_capacity(cfg.queue_depth as usize),
            writes: Vec::with_capacity(cfg.queue_depth as usize),
            draining: false,
            clock: 0,
            banks: vec![Bank::default(); banks as usize],
            ranks: vec![Rank::default(); cfg.ranks as usize],
            last_col: None,
            last_write_end: None,
            last_read: None,
            bus_free: 0,
            seen: Vec::new(),
        }
    }

    pub(crate) fn is_idle(&self) -> bool {
        self.reads.is_empty() && self.writes.is_empty()
    }

    /// Each rank's first activation, if any.
    pub(crate) fn first_acts(&self) -> impl Iterator<Item = Option<u64>> + '_ {
        self.ranks.iter().map(|r| r.first_act)
    }

    fn bank_index(cfg: &DramConfig, loc: &Location) -> usize {
        ((loc.rank * cfg.bank_groups + loc.bank_group) * cfg.banks_per_group + loc.bank) as usize
    }

    /// Chooses and schedules one request at `self.clock` (a queue must hold one): writes
    /// while draining (from `write_high` down to `write_low`) or when no read waits, else
    /// reads; within the queue a row hit whose column command can issue soonest, else the
    /// request whose first command (PRE or ACT) can, the oldest on a tie (FR-FCFS: first
    /// ready, row hits first, then first come), among each bank's oldest `bank_window`
    /// requests, and a hit only while its row has had fewer than `row_hit_cap` column
    /// commands or the bank's oldest request wants the same row. When a hit is chosen, one
    /// other bank's row is opened ahead ([`Channel::prepare`]).
    pub(crate) fn decide(&mut self, cfg: &DramConfig) -> Scheduled {
        let w = self.writes.len() as u32;
        if self.draining && w <= cfg.write_low {
            self.draining = false;
        } else if !self.draining && w >= cfg.write_high {
            self.draining = true;
        }
        let use_writes = (self.draining || self.reads.is_empty()) && !self.writes.is_empty();
        let pick = self.choose(cfg, use_writes);
        let req = if use_writes {
            self.writes.remove(pick)
        } else {
            self.reads.remove(pick)
        };
        let s = self.schedule(cfg, req);
        if s.outcome == RowOutcome::Hit {
            self.prepare(cfg, use_writes, Self::bank_index(cfg, &req.loc));
        }
        self.clock = s.first_command.max(self.clock + 1);
        s
    }

    /// The index in the read or write queue of the request to schedule next (see
    /// [`Channel::decide`]).
    fn choose(&mut self, cfg: &DramConfig, use_writes: bool) -> usize {
        let t = &cfg.timings;
        let mut seen = std::mem::take(&mut self.seen);
        seen.clear();
        seen.resize(self.banks.len(), Seen::default());
        let queue = if use_writes {
            &self.writes
        } else {
            &self.reads
        };
        // (not a hit, ready cycle, age): the smallest wins.
        let mut best: Option<(bool, u64, usize)> = None;
        for (i, q) in queue.iter().enumerate() {
            let b = Self::bank_index(cfg, &q.loc);
            let bank = &self.banks[b];
            let s = &mut seen[b];
            s.count += 1;
            if s.count > cfg.bank_window {
                continue;
            }
            let key = match bank.open {
                Some(row) if row == q.loc.row => {
                    // DRAMsim3 precharges for the older request once the cap is reached
                    // and its PRE may issue; until then hits go on.
                    let capped = bank.columns >= cfg.row_hit_cap && bank.ready_pre <= self.clock;
                    if s.head_conflict && capped {
                        continue;
                    }
                    let col_min = self.clock.max(bank.act + u64::from(trcd(t, q.write)));
                    (false, self.column_time(t, q, col_min), i)
                }
                Some(_) => {
                    s.head_conflict |= s.count == 1;
                    (true, self.clock.max(bank.ready_pre), i)
                }
                None => (true, self.act_time(t, q.loc, self.clock), i),
            };
            if best.is_none_or(|b| key < b) {
                best = Some(key);
            }
        }
        self.seen = seen;
        best.map_or(0, |(_, _, i)| i)
    }

    /// Opens ahead the row of the oldest request, in the queue served, of one bank other
    /// than `chosen` that no queued request hits (so closing its row costs no hit): its
    /// PRE (if another row is open) and ACT issue at their earliest, overlapping the
    /// chosen bank's column commands, as DRAMsim3 issues any bank's ready ACT while another
    /// bank streams hits. The request stays queued and is counted as the miss or conflict
    /// it was when it is scheduled.
    fn prepare(&mut self, cfg: &DramConfig, use_writes: bool, chosen: usize) {
        let t = &cfg.timings;
        let mut seen = std::mem::take(&mut self.seen);
        seen.clear();
        seen.resize(self.banks.len(), Seen::default());
        for q in self.reads.iter().chain(&self.writes) {
            let b = Self::bank_index(cfg, &q.loc);
            seen[b].has_hit |= self.banks[b].open == Some(q.loc.row);
        }
        let queue = if use_writes {
            &self.writes
        } else {
            &self.reads
        };
        let target = queue.iter().find_map(|q| {
            let b = Self::bank_index(cfg, &q.loc);
            let first = seen[b].count == 0;
            seen[b].count += 1;
            (first && b != chosen && !seen[b].has_hit).then_some((b, q.loc))
        });
        self.seen = seen;
        let Some((b, loc)) = target else {
            return;
        };
        let bank = self.banks[b];
        let (outcome, act_min) = match bank.open {
            Some(_) => (
                RowOutcome::Conflict,
                self.clock.max(bank.ready_pre) + u64::from(t.trp),
            ),
            None => (RowOutcome::Miss, self.clock),
        };
        let act = self.activate(t, loc, act_min);
        let bank = &mut self.banks[b];
        *bank = Bank {
            open: Some(loc.row),
            ready_pre: act + u64::from(t.tras),
            act,
            columns: 0,
            prepared: Some(outcome),
        };
    }

    /// Times `req`'s commands from `self.clock` and updates the state they change.
    fn schedule(&mut self, cfg: &DramConfig, req: Queued) -> Scheduled {
        let t = &cfg.timings;
        let now = self.clock;
        let loc = req.loc;
        let b = Self::bank_index(cfg, &loc);
        let bank = self.banks[b];
        let (outcome, first, col_min, act) = match bank.open {
            Some(row) if row == loc.row => {
                let col_min = now.max(bank.act + u64::from(trcd(t, req.write)));
                let outcome = bank.prepared.unwrap_or(RowOutcome::Hit);
                (outcome, None, col_min, None)
            }
            open => {
                let (outcome, act_min, pre) = match open {
                    Some(_) => {
                        let pre = now.max(bank.ready_pre);
                        (RowOutcome::Conflict, pre + u64::from(t.trp), Some(pre))
                    }
                    None => (RowOutcome::Miss, now, None),
                };
                let act = self.activate(t, loc, act_min);
                (
                    outcome,
                    Some(pre.unwrap_or(act)),
                    act + u64::from(trcd(t, req.write)),
                    Some(act),
                )
            }
        };
        let col = self.column_time(t, &req, col_min);
        let lat = if req.write { t.tcwl } else { t.tcl };
        let data_end = col + u64::from(lat) + u64::from(t.tburst);
        self.bus_free = data_end;
        self.last_col = Some((col, loc.rank, loc.bank_group));
        let bank = &mut self.banks[b];
        bank.open = Some(loc.row);
        bank.prepared = None;
        bank.columns += 1;
        if let Some(act) = act {
            bank.ready_pre = act + u64::from(t.tras);
            bank.act = act;
            bank.columns = 1;
        }
        if req.write {
            self.last_write_end = Some((data_end, loc.rank, loc.bank_group));
            bank.ready_pre = bank.ready_pre.max(data_end + u64::from(t.twr));
        } else {
            self.last_read = Some(col);
            bank.ready_pre = bank.ready_pre.max(col + u64::from(t.trtp));
        }
        Scheduled {
            req,
            outcome,
            first_command: first.unwrap_or(col),
            done: data_end,
        }
    }

    /// The earliest ACT at or after `earliest` that tRRD and tFAW allow.
    fn act_time(&self, t: &DramTimings, loc: Location, earliest: u64) -> u64 {
        let rank = &self.ranks[loc.rank as usize];
        let mut act = earliest;
        if let Some((last, bg)) = rank.last_act {
            let trrd = if bg == loc.bank_group {
                t.trrd_l
            } else {
                t.trrd_s
            };
            act = act.max(last + u64::from(trrd));
        }
        if let Some(oldest) = rank.acts[rank.head] {
            act = act.max(oldest + u64::from(t.tfaw));
        }
        act
    }

    /// Issues an ACT at the earliest cycle from `earliest` ([`Channel::act_time`]).
    fn activate(&mut self, t: &DramTimings, loc: Location, earliest: u64) -> u64 {
        let act = self.act_time(t, loc, earliest);
        let rank = &mut self.ranks[loc.rank as usize];
        rank.acts[rank.head] = Some(act);
        rank.head = (rank.head + 1) % 4;
        rank.last_act = Some((act, loc.bank_group));
        rank.first_act.get_or_insert(act);
        act
    }

    /// The earliest column command at or after `earliest` that tCCD, tWTR, tRTW and the
    /// data bus allow.
    fn column_time(&self, t: &DramTimings, req: &Queued, earliest: u64) -> u64 {
        let loc = req.loc;
        let mut col = earliest;
        if let Some((last, rank, bg)) = self.last_col {
            let same = rank == loc.rank && bg == loc.bank_group;
            let tccd = if same { t.tccd_l } else { t.tccd_s };
            col = col.max(last + u64::from(tccd));
        }
        let lat = u64::from(if req.write { t.tcwl } else { t.tcl });
        if req.write {
            if let Some(read) = self.last_read {
                col = col.max(read + u64::from(t.trtw));
            }
        } else if let Some((end, rank, bg)) = self.last_write_end {
            let same = rank == loc.rank && bg == loc.bank_group;
            let twtr = if same { t.twtr_l } else { t.twtr_s };
            col = col.max(end + u64::from(twtr));
        }
        // Data may not start before the bus is free, tRTRS later from another rank.
        let mut free = self.bus_free;
        if self.last_col.is_some_and(|(_, rank, _)| rank != loc.rank) {
            free += u64::from(t.trtrs);
        }
        col.max(free.saturating_sub(lat))
    }
}

/// ACT to a read or a write command.
fn trcd(t: &DramTimings, write: bool) -> u32 {
    if write {
        t.trcd_wr
    } else {
        t.trcd_rd
    }
}
