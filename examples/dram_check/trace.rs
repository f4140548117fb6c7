//! DRAMsim3's request-trace format, as its trace-driven front end reads it (DRAMsim3
//! `src/common.cc`, `operator>>(istream, Transaction)`): one request a line,
//! `0x<hex address> READ|WRITE <arrival cycle>`, the cycle in DRAM clock cycles.
//!
//! A small parser of its own, so the example does not depend on the in-house controller's
//! code being written at the same time: `memory::trace` holds the crate's parser of the same
//! format, and the example switches to it when the two are merged.

use std::fmt::Write as _;

/// One request of a trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// Byte address.
    pub addr: u64,
    /// A write (`WRITE`) or a read (`READ`).
    pub write: bool,
    /// The DRAM cycle from which the request is offered to the controller.
    pub arrival_cycle: u64,
}

/// Parses a trace: blank lines and lines starting with `#` are skipped; anything else must
/// be `0x<hex> READ|WRITE <cycle>`, with cycles that never decrease.
pub fn parse(text: &str) -> Result<Vec<Request>, String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let request = parse_line(line).map_err(|e| format!("trace line {}: {e}", i + 1))?;
        if let Some(last) = out.last() {
            let last: &Request = last;
            if request.arrival_cycle < last.arrival_cycle {
                return Err(format!(
                    "trace line {}: arrival cycle {} is before the previous line's {}",
                    i + 1,
                    request.arrival_cycle,
                    last.arrival_cycle
                ));
            }
        }
        out.push(request);
    }
    Ok(out)
}

fn parse_line(line: &str) -> Result<Request, String> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    let [addr, op, cycle] = fields[..] else {
        return Err(format!(
            "expected `0x<hex> READ|WRITE <cycle>`, got `{line}`"
        ));
    };
    let hex = addr
        .strip_prefix("0x")
        .or_else(|| addr.strip_prefix("0X"))
        .ok_or_else(|| format!("address `{addr}` does not start with 0x"))?;
    let addr = u64::from_str_radix(hex, 16).map_err(|e| format!("address `{addr}`: {e}"))?;
    let write = match op {
        "READ" => false,
        "WRITE" => true,
        _ => return Err(format!("operation `{op}` is neither READ nor WRITE")),
    };
    let arrival_cycle = cycle
        .parse()
        .map_err(|e| format!("arrival cycle `{cycle}`: {e}"))?;
    Ok(Request {
        addr,
        write,
        arrival_cycle,
    })
}

/// The trace's text, one line a request, that [`parse`] reads back.
pub fn format(requests: &[Request]) -> String {
    let mut s = String::with_capacity(requests.len() * 24);
    for r in requests {
        let op = if r.write { "WRITE" } else { "READ" };
        let _ = writeln!(s, "0x{:x} {op} {}", r.addr, r.arrival_cycle);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_round_trips_through_its_text() {
        let requests = vec![
            Request {
                addr: 0x40,
                write: false,
                arrival_cycle: 0,
            },
            Request {
                addr: 0xdead_bee0,
                write: true,
                arrival_cycle: 7,
            },
        ];
        let text = format(&requests);
        assert_eq!(text, "0x40 READ 0\n0xdeadbee0 WRITE 7\n");
        assert_eq!(parse(&text).unwrap(), requests);
    }

    #[test]
    fn trace_refuses_bad_lines_naming_them() {
        let e = parse("0x40 READ 0\n0x80 FETCH 1\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("FETCH"), "{e}");
        let e = parse("40 READ 0\n").unwrap_err();
        assert!(e.contains("0x"), "{e}");
        let e = parse("0x40 READ 5\n0x80 READ 4\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("before"), "{e}");
        let e = parse("0x40 READ\n").unwrap_err();
        assert!(e.contains("expected"), "{e}");
    }
}
