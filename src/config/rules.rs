//! What a field of the architecture accepts: one rule type per kind of value, each checking
//! a value ([`Checked`]) and describing itself for the README's field table
//! ([`Describe`]). A refused value is an [`Error::Invalid`] naming the file, the dotted
//! field path and the value.

use super::ratio::Ratio;
use crate::error::{Error, Result};

/// The largest accepted instance count of a replicated unit. Beyond it the host would run
/// hundreds of actor threads for no architectural insight.
pub const MAX_UNIT_COUNT: u32 = 64;
/// The largest accepted latency or initiation interval \[cycles\]. Far above any plausible
/// hardware figure; it keeps cycle arithmetic far from overflow.
pub const MAX_CYCLES: u64 = 1_000_000;
/// The largest accepted `fragments_per_cycle` of a rasterizer or ROP.
pub const MAX_FRAGMENTS_PER_CYCLE: u64 = 64;
/// The largest accepted ROP interleave tile side \[pixels\].
pub const MAX_TILE_PX: u32 = 256;
/// The largest accepted `bytes_*` figure of the frame buffer \[bytes\].
pub const MAX_BYTES: u64 = 4096;
/// The largest accepted batch of primitives dealt to one front-end engine \[primitives\].
pub const MAX_BATCH: u32 = 65_536;
/// The largest accepted FIFO depth \[items\]. Deeper FIFOs would only cost host memory.
pub const MAX_FIFO_DEPTH: u32 = 4096;
/// The largest accepted post-transform vertex cache \[entries\]. GPUs' hold tens to a few
/// hundred; beyond this the host's cache lookups would only cost time.
pub const MAX_VERTEX_CACHE: u32 = 4096;
/// The longest accepted frame-buffer access slot \[cycles\]: a DRAM access (row open,
/// column access, precharge) is tens of cycles at most.
pub const MAX_ACCESS_CYCLES: u64 = 64;
/// The largest accepted clock \[MHz\].
pub const MAX_CLOCK_MHZ: f64 = 100_000.0;
/// The longest accepted configuration name \[characters\].
pub const MAX_NAME_CHARS: usize = 64;

/// A unit's instance count.
pub const COUNT: Whole = Whole {
    min: 1,
    max: MAX_UNIT_COUNT as u64,
    unit: "instances (every stage needs at least one unit)",
};
/// Primitives per batch dealt to one front-end engine.
pub const BATCH: Whole = Whole {
    min: 1,
    max: MAX_BATCH as u64,
    unit: "primitives per batch",
};
/// A latency or initiation interval.
pub const CYCLES: Whole = Whole {
    min: 1,
    max: MAX_CYCLES,
    unit: "cycles",
};
/// Further cycles that may be none (folded into another figure).
pub const CYCLES_OR_NONE: Whole = Whole {
    min: 0,
    max: MAX_CYCLES,
    unit: "cycles",
};
/// A size in memory.
pub const BYTES: Whole = Whole {
    min: 1,
    max: MAX_BYTES,
    unit: "bytes",
};

/// A whole number in `min..=max`; `unit` completes the reason ("must be 1 to 64 `unit`").
pub struct Whole {
    /// The smallest accepted value.
    pub min: u64,
    /// The largest accepted value.
    pub max: u64,
    /// What the number counts, with why the bounds are what they are.
    pub unit: &'static str,
}

/// A [`Ratio`]: a multiple of 1/[`Ratio::DEN`] from 1/DEN to `max`.
pub struct Steps {
    /// The largest accepted value.
    pub max: u64,
}

/// A text of `min..=max` characters.
pub struct Chars {
    /// The fewest characters.
    pub min: usize,
    /// The most characters.
    pub max: usize,
}

/// A finite number above 0 and at most `max` (`what` and `unit` name it in the reason).
pub struct Positive {
    /// The largest accepted value.
    pub max: f64,
    /// What the number is ("clock").
    pub what: &'static str,
    /// Its unit ("MHz").
    pub unit: &'static str,
}

/// One of the names of an enum, checked as it is parsed (an unknown name is a parse error
/// naming the field and the names accepted), so never refused here.
pub struct OneOf(pub &'static [&'static str]);

/// A rule described for the README's field table.
pub trait Describe: Sync {
    /// What the rule accepts, in words ("1 to 64").
    fn accepted(&self) -> String;
}

/// A value a rule of type `Rule` checks.
pub trait Checked {
    /// The rule for values of this type.
    type Rule: Describe;
    /// The value as an error shows it and the reason, when `rule` refuses it.
    fn refusal(&self, rule: &Self::Rule) -> Option<(String, String)>;
}

/// `n` with its thousands apart (`1 000 000`), as the README writes large figures.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

impl Describe for Whole {
    fn accepted(&self) -> String {
        format!("{} to {}", grouped(self.min), grouped(self.max))
    }
}

impl Describe for Steps {
    fn accepted(&self) -> String {
        format!(
            "1/{den} to {}, in steps of 1/{den}",
            grouped(self.max),
            den = Ratio::DEN
        )
    }
}

impl Describe for Chars {
    fn accepted(&self) -> String {
        format!("{} to {} characters", self.min, self.max)
    }
}

impl Describe for Positive {
    fn accepted(&self) -> String {
        format!("above 0, at most {}", grouped(self.max as u64))
    }
}

impl Describe for OneOf {
    fn accepted(&self) -> String {
        let names: Vec<String> = self.0.iter().map(|n| format!("`\"{n}\"`")).collect();
        names.join(", ")
    }
}

impl Whole {
    fn refusal(&self, value: u64) -> Option<(String, String)> {
        let reason = || format!("must be {} to {} {}", self.min, self.max, self.unit);
        (!(self.min..=self.max).contains(&value)).then(|| (value.to_string(), reason()))
    }
}

impl Checked for u32 {
    type Rule = Whole;
    fn refusal(&self, rule: &Whole) -> Option<(String, String)> {
        rule.refusal((*self).into())
    }
}

impl Checked for u64 {
    type Rule = Whole;
    fn refusal(&self, rule: &Whole) -> Option<(String, String)> {
        rule.refusal(*self)
    }
}

impl Checked for Ratio {
    type Rule = Steps;
    fn refusal(&self, rule: &Steps) -> Option<(String, String)> {
        self.check(rule.max)
            .err()
            .map(|why| (self.to_string(), why))
    }
}

impl Checked for String {
    type Rule = Chars;
    fn refusal(&self, rule: &Chars) -> Option<(String, String)> {
        let chars = self.chars().count();
        let reason = || format!("must be {} to {} characters long", rule.min, rule.max);
        (!(rule.min..=rule.max).contains(&chars)).then(|| (format!("{self:?}"), reason()))
    }
}

impl Checked for f64 {
    type Rule = Positive;
    fn refusal(&self, rule: &Positive) -> Option<(String, String)> {
        let (max, what, unit) = (rule.max, rule.what, rule.unit);
        let accepted = self.is_finite() && *self > 0.0 && *self <= max;
        let reason = || format!("must be a finite {what} above 0 and at most {max} {unit}");
        (!accepted).then(|| (self.to_string(), reason()))
    }
}

/// Where the values checked come from: the file, and the path of the section being checked.
pub struct Check<'a> {
    file: &'a str,
    prefix: String,
}

impl<'a> Check<'a> {
    /// Checks of the fields of `file`'s top level.
    pub fn new(file: &'a str) -> Check<'a> {
        Check {
            file,
            prefix: String::new(),
        }
    }

    /// Checks of the section `key` under this one.
    pub fn at(&self, key: &str) -> Check<'a> {
        Check {
            file: self.file,
            prefix: self.path(key),
        }
    }

    /// The dotted path of `key` under this section (`links.setup_to_minmax.fifo_depth`).
    fn path(&self, key: &str) -> String {
        if self.prefix.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.prefix)
        }
    }

    /// `value` of the field `key` against `rule`: [`Error::Invalid`] naming the file, the
    /// field's path and the value when refused.
    pub fn field<T: Checked>(&self, key: &str, value: &T, rule: &T::Rule) -> Result<()> {
        match value.refusal(rule) {
            None => Ok(()),
            Some((value, reason)) => Err(Error::invalid(self.file, self.path(key), value, reason)),
        }
    }
}
