//! One channel's controller: its read and write queues, the write drain, FR-FCFS choice and
//! the bank, rank and bus state that times each request's commands.
//!
//! **Queues.** As in DRAMsim3 (`Controller`, `CommandQueue` with `queue_structure =
//! PER_BANK`): admitted requests wait in a read or a write transaction queue of
//! `queue_depth`; at each decision the served queue's oldest requests move, one a cycle
//! since the last decision, into their bank's command queue of `bank_window` (shared by
//! reads and writes). Writes are served while draining (from `write_high` waiting writes
//! down to `write_low`) or when no read is queued, else reads; whatever has moved is
//! chosen from, reads and writes alike, as DRAMsim3 issues any command queue's ready
//! command during a drain.
//!
//! **Timing.** A request is scheduled at a decision time as a group of commands:
//! - a row hit: one column command (RD or WR);
//! - a miss (bank precharged): ACT, then the column command tRCD later;
//! - a conflict (another row open): PRE (after tRAS from its ACT, tRTP from its last read,
//!   tWR from its last write data), ACT tRP later, the column command tRCD after that.
//!
//! A miss's or conflict's PRE and ACT go as early as the request was admitted and its bank
//! allows, which may be before commands already scheduled for other banks: row misses
//! overlap other banks' column traffic, as DRAMsim3 issues any bank's ready PRE or ACT
//! between column commands. ACTs keep tRRD (S or L by bank group) and tFAW against every
//! ACT of the rank ([`super::acts`]). Column commands issue in decision order: tCCD (S or
//! L) after the previous one, tWTR (S or L) after the end of write data before a read, tRTW
//! after a read before a write; data (CL or CWL after the command, tBURST long) never
//! overlaps on the bus, and bursts of two ranks are tRTRS apart. A read completes when its
//! last data beat arrives, a write when its last beat is sent. The next decision is at the
//! chosen hit's column command or one cycle later. While one bank streams hits, each
//! decision also opens ahead the row of one other bank that no queued request hits: a
//! sequential stream crossing into the next bank group then alternates groups at tCCD_S
//! instead of waiting tCCD_L a command.
//!
//! **Not modelled**, each a simplification to state when comparing with DRAMsim3: refresh
//! (tRFC every tREFI: 4.5 % of DDR4-2400's cycles), the one-command-per-cycle command bus,
//! reads served from the write queue, and power-down.

use super::acts::RankActs;
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
    /// The cycle it entered its queue (its bank's PRE and ACT may issue from then on).
    pub admitted: u64,
    /// It has moved from the transaction queue into its bank's command queue.
    pub moved: bool,
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

/// A request's commands if it were scheduled now.
#[derive(Clone, Copy, Debug)]
struct Plan {
    outcome: RowOutcome,
    /// Its PRE or ACT, if it needs one.
    first: Option<u64>,
    act: Option<u64>,
    col: u64,
}

/// Per bank while choosing: requests seen, and whether its oldest is a conflict.
#[derive(Clone, Copy, Debug, Default)]
struct Seen {
    count: u32,
    /// The ticket of its oldest request, and whether that one hits.
    oldest: u64,
    oldest_hit: bool,
    head_conflict: bool,
    has_hit: bool,
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
    ranks: Vec<RankActs>,
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
    /// Bank groups per rank and banks per group.
    bank_groups: u32,
    banks_per_group: u32,
    /// Requests in each bank's command queue (reads and writes, at most `bank_window`).
    in_bank: Vec<u32>,
    /// Reads and writes still in the transaction queues.
    waiting_r: u32,
    waiting_w: u32,
    /// The cycle of the last move into the command queues.
    moved_at: u64,
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
            ranks: vec![RankActs::default(); cfg.ranks as usize],
            last_col: None,
            last_write_end: None,
            last_read: None,
            bus_free: 0,
            seen: Vec::new(),
            bank_groups: cfg.bank_groups,
            banks_per_group: cfg.banks_per_group,
            in_bank: vec![0; banks as usize],
            waiting_r: 0,
            waiting_w: 0,
            moved_at: 0,
        }
    }

    /// Whether the read (or write) transaction queue has room for one more of its
    /// `queue_depth` requests (those moved into their bank's command queue have left it).
    pub(crate) fn accepts(&self, cfg: &DramConfig, write: bool) -> bool {
        let waiting = if write {
            self.waiting_w
        } else {
            self.waiting_r
        };
        waiting < cfg.queue_depth
    }

    /// Queues an admitted request in its transaction queue.
    pub(crate) fn push(&mut self, req: Queued) {
        if req.write {
            self.waiting_w += 1;
            self.writes.push(req);
        } else {
            self.waiting_r += 1;
            self.reads.push(req);
        }
    }

    /// Moves the served queue's requests, oldest first, into their banks' command queues
    /// while those have room, one for each cycle since the last move (DRAMsim3's
    /// `Controller::ScheduleTransaction` moves one a cycle).
    fn move_to_banks(&mut self, cfg: &DramConfig, writes: bool) {
        let (groups, per_group) = (self.bank_groups, self.banks_per_group);
        let queue = if writes {
            &mut self.writes
        } else {
            &mut self.reads
        };
        let mut moved = 0;
        let budget = self.clock.saturating_sub(self.moved_at).max(1);
        self.moved_at = self.clock;
        for q in queue.iter_mut().filter(|q| !q.moved) {
            let b = ((q.loc.rank * groups + q.loc.bank_group) * per_group + q.loc.bank) as usize;
            if u64::from(moved) < budget && self.in_bank[b] < cfg.bank_window {
                self.in_bank[b] += 1;
                q.moved = true;
                moved += 1;
            }
        }
        if writes {
            self.waiting_w -= moved;
        } else {
            self.waiting_r -= moved;
        }
    }

    pub(crate) fn is_idle(&self) -> bool {
        self.reads.is_empty() && self.writes.is_empty()
    }

    /// Each rank's first activation, if any.
    pub(crate) fn first_acts(&self) -> impl Iterator<Item = Option<u64>> + '_ {
        self.ranks.iter().map(|r| r.first)
    }

    /// The index of `loc`'s bank in `banks`.
    fn bank(&self, loc: &Location) -> usize {
        ((loc.rank * self.bank_groups + loc.bank_group) * self.banks_per_group + loc.bank) as usize
    }

    /// Chooses and schedules one request at `self.clock` (a queue must hold one): moves
    /// the served queue's oldest requests into their banks' command queues, then takes,
    /// among every request moved, the one whose column command can issue soonest, a hit
    /// before a miss and the oldest on a tie (FR-FCFS: first ready, row hits first, then
    /// first come). A bank's misses wait while it has a hit to serve, and its hits while
    /// its oldest request conflicts, its row has had `row_hit_cap` column commands and its
    /// PRE may issue. When a hit is chosen, one other bank's row is opened ahead
    /// ([`Channel::prepare`]).
    pub(crate) fn decide(&mut self, cfg: &DramConfig) -> Scheduled {
        let w = self.waiting_w;
        if self.draining && w <= cfg.write_low {
            self.draining = false;
        } else if !self.draining && w >= cfg.write_high {
            self.draining = true;
        }
        let use_writes = (self.draining || self.reads.is_empty()) && !self.writes.is_empty();
        self.move_to_banks(cfg, use_writes);
        let (write, pick) = self.choose(cfg);
        let req = if write {
            self.writes.remove(pick)
        } else {
            self.reads.remove(pick)
        };
        let b = self.bank(&req.loc);
        self.in_bank[b] -= 1;
        let s = self.schedule(cfg, req);
        if s.outcome == RowOutcome::Hit {
            self.prepare(cfg, use_writes, b);
        }
        self.clock = s.first_command.max(self.clock + 1);
        s
    }

    /// The request to schedule next among those in the banks' command queues (see
    /// [`Channel::decide`]): whether it is a write, and its index in its queue.
    fn choose(&mut self, cfg: &DramConfig) -> (bool, usize) {
        let t = &cfg.timings;
        let mut seen = std::mem::take(&mut self.seen);
        seen.clear();
        seen.resize(self.banks.len(), Seen::default());
        let queued = || {
            let reads = self.reads.iter().enumerate().map(|(i, q)| (false, i, q));
            let writes = self.writes.iter().enumerate().map(|(i, q)| (true, i, q));
            reads.chain(writes).filter(|(_, _, q)| q.moved)
        };
        // Each bank's oldest request, and whether it has a hit to serve: one in its command
        // queue, unless its oldest request conflicts and the row has had its cap of hits
        // (DRAMsim3 then precharges for the older request once its PRE may issue).
        for (_, _, q) in queued() {
            let b = self.bank(&q.loc);
            let hit = self.banks[b].open == Some(q.loc.row);
            let s = &mut seen[b];
            if s.count == 0 || q.ticket < s.oldest {
                s.oldest = q.ticket;
                s.oldest_hit = hit;
            }
            s.count += 1;
            s.has_hit |= hit;
        }
        for (b, s) in seen.iter_mut().enumerate() {
            let bank = &self.banks[b];
            let capped = bank.columns >= cfg.row_hit_cap && bank.ready_pre <= self.clock;
            s.head_conflict = s.count > 0 && !s.oldest_hit && bank.open.is_some() && capped;
            s.has_hit &= !s.head_conflict;
        }
        // (column command's cycle, not a hit, age): the smallest wins, among the hits of
        // the banks that have one and the requests of the others.
        let mut best: Option<(u64, bool, u64, bool, usize)> = None;
        for (write, i, q) in queued() {
            let b = self.bank(&q.loc);
            let hit = self.banks[b].open == Some(q.loc.row);
            if hit != seen[b].has_hit {
                continue;
            }
            let key = (self.plan(t, q).col, !hit, q.ticket, write, i);
            if best.is_none_or(|b| key < b) {
                best = Some(key);
            }
        }
        self.seen = seen;
        best.map_or((false, 0), |(_, _, _, w, i)| (w, i))
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
            let b = self.bank(&q.loc);
            seen[b].has_hit |= self.banks[b].open == Some(q.loc.row);
        }
        let queue = if use_writes {
            &self.writes
        } else {
            &self.reads
        };
        let target = queue.iter().filter(|q| q.moved).find_map(|q| {
            let b = self.bank(&q.loc);
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

    /// When `req`'s commands would issue if it were scheduled at `self.clock`. A row hit's
    /// column command waits for the bank's ACT; a miss's or conflict's PRE and ACT go as
    /// early as the request was queued and its bank allows (they may precede commands
    /// already scheduled for other banks), its column command follows in scheduling order.
    fn plan(&self, t: &DramTimings, req: &Queued) -> Plan {
        let now = self.clock;
        let bank = &self.banks[self.bank(&req.loc)];
        let (outcome, pre, act, col_min) = match bank.open {
            Some(row) if row == req.loc.row => {
                let col_min = now.max(bank.act + u64::from(trcd(t, req.write)));
                let outcome = bank.prepared.unwrap_or(RowOutcome::Hit);
                (outcome, None, None, col_min)
            }
            open => {
                let from = req.admitted;
                let (outcome, act_min, pre) = match open {
                    Some(_) => {
                        let pre = from.max(bank.ready_pre);
                        (RowOutcome::Conflict, pre + u64::from(t.trp), Some(pre))
                    }
                    None => (RowOutcome::Miss, from, None),
                };
                let act = self.act_time(t, req.loc, act_min);
                let col_min = now.max(act + u64::from(trcd(t, req.write)));
                (outcome, pre, Some(act), col_min)
            }
        };
        Plan {
            outcome,
            first: pre.or(act),
            act,
            col: self.column_time(t, req, col_min),
        }
    }

    /// Schedules `req` as [`Channel::plan`] times it and updates the state it changes.
    fn schedule(&mut self, cfg: &DramConfig, req: Queued) -> Scheduled {
        let t = &cfg.timings;
        let loc = req.loc;
        let b = self.bank(&loc);
        let Plan {
            outcome,
            first,
            act,
            col,
        } = self.plan(t, &req);
        if let Some(act) = act {
            self.ranks[loc.rank as usize].record(loc.bank_group, act);
        }
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
        self.ranks[loc.rank as usize].earliest(t, loc.bank_group, earliest)
    }

    /// Issues an ACT at the earliest cycle from `earliest` ([`Channel::act_time`]).
    fn activate(&mut self, t: &DramTimings, loc: Location, earliest: u64) -> u64 {
        let act = self.act_time(t, loc, earliest);
        self.ranks[loc.rank as usize].record(loc.bank_group, act);
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
