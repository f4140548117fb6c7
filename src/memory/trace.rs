//! The memory-request trace: DRAMsim3's own trace format, so one file feeds both this
//! crate's controller ([`crate::memory::dram`]) and DRAMsim3 (Li et al., "DRAMsim3: a
//! Cycle-accurate, Thermal-Capable DRAM Simulator", IEEE CAL 2020).
//!
//! One request a line: `0x<hex address> READ|WRITE <arrival cycle>`, separated by
//! whitespace, as DRAMsim3's `TraceBasedCPU` reads it (`src/cpu.cc`, through the
//! `Transaction` extraction operator in `src/common.cc`, which reads the address in hex,
//! the operation word, then the cycle in decimal). DRAMsim3 takes `WRITE`, `write`,
//! `P_MEM_WR` and `BOFF` as writes and any other word as a read; this parser is stricter:
//! `READ`/`read` and `WRITE`/`write` only, and anything else is an error naming the line.
//! Blank lines are skipped (DRAMsim3 stops at end of file). Arrival cycles are in the DRAM's
//! command clock, as DRAMsim3 counts them, and must not decrease (DRAMsim3 issues the trace
//! in file order, stalling on a request until its cycle comes).

use crate::error::{Error, Result};
use std::fmt::Write as _;

/// One memory request: the atom containing `addr` is read or written. A request smaller
/// than an atom still moves the whole atom (a partial write pays a whole atom).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// Byte address.
    pub addr: u64,
    /// A write (else a read).
    pub write: bool,
    /// The DRAM command-clock cycle it reaches the controller \[cycles\].
    pub arrival: u64,
}

/// Parses a trace; `file` names it in errors. Each error is [`Error::Parse`] with the
/// field `line N` (1-based).
pub fn parse(file: &str, text: &str) -> Result<Vec<Request>> {
    let mut out = Vec::new();
    let mut last = 0u64;
    for (i, line) in text.lines().enumerate() {
        let err = |message: String| Error::Parse {
            file: file.to_string(),
            field: format!("line {}", i + 1),
            message,
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.is_empty() {
            continue;
        }
        let [addr, op, cycle] = words[..] else {
            return Err(err(format!(
                "expected `0x<address> READ|WRITE <cycle>`, found {} words",
                words.len()
            )));
        };
        let hex = addr
            .strip_prefix("0x")
            .or_else(|| addr.strip_prefix("0X"))
            .unwrap_or(addr);
        let addr = u64::from_str_radix(hex, 16)
            .map_err(|e| err(format!("address `{addr}` is not hexadecimal: {e}")))?;
        let write = match op {
            "READ" | "read" => false,
            "WRITE" | "write" => true,
            _ => return Err(err(format!("operation `{op}` is not READ or WRITE"))),
        };
        let arrival: u64 = cycle
            .parse()
            .map_err(|e| err(format!("cycle `{cycle}` is not a decimal count: {e}")))?;
        if arrival < last {
            return Err(err(format!(
                "cycle {arrival} is before the previous request's {last}"
            )));
        }
        last = arrival;
        out.push(Request {
            addr,
            write,
            arrival,
        });
    }
    Ok(out)
}

/// Writes a trace in the format [`parse`] reads (and DRAMsim3 reads).
pub fn write(requests: &[Request]) -> String {
    let mut s = String::with_capacity(requests.len() * 24);
    for r in requests {
        let op = if r.write { "WRITE" } else { "READ" };
        // Writing to a String cannot fail.
        let _ = writeln!(s, "0x{:x} {op} {}", r.addr, r.arrival);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::SplitMix64;

    #[test]
    fn a_random_trace_round_trips_through_write_and_parse() {
        let mut rng = SplitMix64::new(51);
        let mut arrival = 0;
        let reqs: Vec<Request> = (0..500)
            .map(|_| {
                arrival += rng.below(5);
                Request {
                    addr: rng.next_u64(),
                    write: rng.below(2) == 1,
                    arrival,
                }
            })
            .collect();
        let text = write(&reqs);
        assert_eq!(parse("t", &text).unwrap(), reqs);
    }

    #[test]
    fn dramsim3_lines_parse() {
        let text = "0x1f40 READ 0\n\n0X80 write 3\n  0xdeadbeef   WRITE  3  \n";
        let reqs = parse("t", text).unwrap();
        assert_eq!(
            reqs,
            vec![
                Request {
                    addr: 0x1f40,
                    write: false,
                    arrival: 0
                },
                Request {
                    addr: 0x80,
                    write: true,
                    arrival: 3
                },
                Request {
                    addr: 0xdead_beef,
                    write: true,
                    arrival: 3
                },
            ]
        );
    }

    fn field_of(text: &str) -> String {
        match parse("t", text) {
            Err(Error::Parse { field, .. }) => field,
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn bad_lines_are_named_by_number() {
        assert_eq!(field_of("0x0 READ 0\n0xzz READ 1\n"), "line 2");
        assert_eq!(field_of("0x0 READ 0\n\n0x40 FETCH 1\n"), "line 3");
        assert_eq!(field_of("0x0 READ\n"), "line 1");
        assert_eq!(field_of("0x0 READ -1\n"), "line 1");
        assert_eq!(field_of("0x0 READ 5\n0x40 READ 4\n"), "line 2");
        assert_eq!(field_of("0x0 READ 5 extra\n"), "line 1");
    }
}
