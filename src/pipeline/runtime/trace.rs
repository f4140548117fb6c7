//! The timeline of a timed run (`--trace-out`): Chrome trace-event JSON that Perfetto
//! (ui.perfetto.dev) and chrome://tracing open. One track per unit instance, one complete
//! ("X") event per stretch of busy or blocked cycles; starved time is the gaps.
//!
//! Size is bounded: each unit keeps at most its share of a global event cap. When a unit's
//! events reach the cap, its *quantum* doubles and neighbouring events of the same state
//! closer than the quantum merge (the merged event then also covers the short gaps). The
//! file's `otherData` says the cap and every unit's final quantum. Coarsening depends only
//! on the sequence of events, so the file is as deterministic as the run.

use std::fmt::Write as _;

/// What a unit was doing over an event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// Issuing operations.
    Busy,
    /// Frozen on a full FIFO downstream.
    Blocked,
}

impl State {
    fn name(self) -> &'static str {
        match self {
            State::Busy => "busy",
            State::Blocked => "blocked",
        }
    }
}

/// The events of one unit, coarsened to stay under a cap.
#[derive(Clone, Debug)]
pub struct Recorder {
    /// (start, end, state) in cycles, start-ordered, non-overlapping.
    events: Vec<(u64, u64, State)>,
    /// Same-state events closer than this many cycles are merged \[cycles\].
    quantum: u64,
    cap: usize,
}

impl Recorder {
    /// An empty recorder that keeps at most `cap` events (at least 2).
    pub fn new(cap: usize) -> Self {
        Recorder {
            events: Vec::new(),
            quantum: 0,
            cap: cap.max(2),
        }
    }

    /// Records `state` over cycles [start, end).
    pub fn record(&mut self, start: u64, end: u64, state: State) {
        if end <= start {
            return;
        }
        if let Some(last) = self.events.last_mut() {
            if last.2 == state && start <= last.1 + self.quantum {
                last.1 = end;
                return;
            }
        }
        self.events.push((start, end, state));
        if self.events.len() > self.cap {
            self.coarsen();
        }
    }

    /// Doubles the quantum until the events fit in half the cap.
    fn coarsen(&mut self) {
        while self.events.len() > self.cap / 2 {
            self.quantum = (self.quantum * 2).max(1);
            let mut merged: Vec<(u64, u64, State)> = Vec::with_capacity(self.events.len());
            for &e in &self.events {
                let n = merged.len();
                match merged.last_mut() {
                    Some(last) if last.2 == e.2 && e.0 <= last.1 + self.quantum => last.1 = e.1,
                    // A short event of the other state between two merged ones is dropped
                    // once it is shorter than the quantum.
                    Some(last) if e.1 - e.0 < self.quantum && n >= 2 && last.2 != e.2 => {
                        last.1 = last.1.max(e.1);
                    }
                    _ => merged.push(e),
                }
            }
            self.events = merged;
        }
    }

    /// The recorded events: (start, end, state) in cycles, merged to the quantum.
    pub fn events(&self) -> &[(u64, u64, State)] {
        &self.events
    }

    /// Same-state events closer than this were merged \[cycles\]; doubled each time the
    /// cap was reached.
    pub fn quantum(&self) -> u64 {
        self.quantum
    }
}

/// One unit's track in the file.
pub struct Track<'a> {
    /// The unit instance's name.
    pub name: &'a str,
    /// Its kind's name (the track's group).
    pub kind: &'a str,
    /// Its events.
    pub recorder: &'a Recorder,
}

/// Chrome trace-event JSON for the tracks. Times are microseconds at `clock_mhz`, so the
/// viewer's time axis is simulated time at the configured clock.
pub fn chrome_json(tracks: &[Track], clock_mhz: f64, total_cycles: u64, cap: usize) -> String {
    let us = |c: u64| c as f64 / clock_mhz;
    let mut s = String::from("{\"traceEvents\":[\n");
    let _ = write!(
        s,
        "{{\"name\":\"process_name\",\"ph\":\"M\",\"pid\":1,\"args\":{{\"name\":\"lembo-sim timed pipeline\"}}}}"
    );
    for (tid, t) in tracks.iter().enumerate() {
        let _ = write!(
            s,
            ",\n{{\"name\":\"thread_name\",\"ph\":\"M\",\"pid\":1,\"tid\":{tid},\"args\":{{\"name\":{}}}}}",
            serde_json::Value::from(t.name)
        );
        let _ = write!(
            s,
            ",\n{{\"name\":\"thread_sort_index\",\"ph\":\"M\",\"pid\":1,\"tid\":{tid},\"args\":{{\"sort_index\":{tid}}}}}"
        );
        for &(start, end, state) in t.recorder.events() {
            let _ = write!(
                s,
                ",\n{{\"name\":\"{}\",\"cat\":{},\"ph\":\"X\",\"pid\":1,\"tid\":{tid},\"ts\":{},\"dur\":{},\"args\":{{\"start_cycle\":{start},\"cycles\":{}}}}}",
                state.name(),
                serde_json::Value::from(t.kind),
                us(start),
                us(end - start),
                end - start
            );
        }
    }
    s.push_str("\n],\n\"displayTimeUnit\":\"ns\",\n\"otherData\":");
    let quanta: serde_json::Map<String, serde_json::Value> = tracks
        .iter()
        .map(|t| (t.name.to_string(), t.recorder.quantum().into()))
        .collect();
    let other = serde_json::json!({
        "time_axis": format!("microseconds at the configured clock of {clock_mhz} MHz"),
        "total_cycles": total_cycles,
        "starved": "gaps between events are starved cycles",
        "event_cap_per_unit": cap,
        "coarsening": "per unit, same-state events closer than the quantum [cycles] are merged; 0 = exact",
        "quantum_cycles": quanta,
    });
    s.push_str(&other.to_string());
    s.push_str("\n}\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_merges_adjacent_events_of_the_same_state() {
        let mut r = Recorder::new(100);
        r.record(0, 2, State::Busy);
        r.record(2, 5, State::Busy);
        r.record(5, 6, State::Blocked);
        r.record(8, 9, State::Busy);
        assert_eq!(
            r.events(),
            &[
                (0, 5, State::Busy),
                (5, 6, State::Blocked),
                (8, 9, State::Busy)
            ]
        );
        assert_eq!(r.quantum(), 0);
    }

    #[test]
    fn trace_stays_under_its_cap_and_covers_the_same_span() {
        let mut r = Recorder::new(64);
        for n in 0..10_000u64 {
            r.record(3 * n, 3 * n + 1, State::Busy);
        }
        assert!(r.events().len() <= 64);
        assert!(r.quantum() >= 2);
        assert_eq!(r.events().first().unwrap().0, 0);
        assert_eq!(r.events().last().unwrap().1, 3 * 9_999 + 1);
    }

    #[test]
    fn trace_file_is_json_with_one_track_per_unit() {
        let mut r = Recorder::new(10);
        r.record(0, 500, State::Busy);
        let tracks = [Track {
            name: "Segmenter[0]",
            kind: "Segmenter",
            recorder: &r,
        }];
        let text = chrome_json(&tracks, 500.0, 500, 10);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        let events = v["traceEvents"].as_array().unwrap();
        let x: Vec<_> = events.iter().filter(|e| e["ph"] == "X").collect();
        assert_eq!(x.len(), 1);
        assert_eq!(x[0]["dur"], 1.0);
        assert_eq!(v["otherData"]["total_cycles"], 500);
    }
}
