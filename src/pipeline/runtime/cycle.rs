//! Simulated time: [`Cycle`] and the timestamped item [`Timed`].

use serde::Serialize;
use std::fmt;
use std::ops::{Add, AddAssign, Sub};

/// A point in simulated time, or a number of cycles \[clock cycles\]. Reports carry it
/// as a plain number (`serde(transparent)`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(transparent)]
pub struct Cycle(pub u64);

impl Cycle {
    /// The start of the frame.
    pub const ZERO: Cycle = Cycle(0);
    /// Later than any real time: the bound of an input that has ended.
    pub const NEVER: Cycle = Cycle(u64::MAX);
}

impl Add<u64> for Cycle {
    type Output = Cycle;
    #[inline(always)]
    fn add(self, rhs: u64) -> Cycle {
        Cycle(self.0.saturating_add(rhs))
    }
}

impl Add for Cycle {
    type Output = Cycle;
    #[inline(always)]
    fn add(self, rhs: Cycle) -> Cycle {
        self + rhs.0
    }
}

impl AddAssign<u64> for Cycle {
    #[inline(always)]
    fn add_assign(&mut self, rhs: u64) {
        self.0 = self.0.saturating_add(rhs);
    }
}

impl Sub for Cycle {
    type Output = u64;
    #[inline(always)]
    fn sub(self, rhs: Cycle) -> u64 {
        self.0 - rhs.0
    }
}

impl Cycle {
    /// The number of cycles as a float, for rates and ratios.
    #[inline]
    pub fn as_f64(self) -> f64 {
        self.0 as f64
    }
}

impl fmt::Display for Cycle {
    /// As the number, honouring width and alignment (report tables pad it).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

/// An item on a link with its push time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timed<T> {
    /// Push time p_n \[cycle\].
    pub at: Cycle,
    /// What was pushed.
    pub item: T,
}
