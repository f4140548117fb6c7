//! [`Ratio`]: an architecture figure that may be a fraction (a rate of half an item a cycle,
//! an access slot of half a cycle), kept exact so that cycle counts stay integers and
//! deterministic.
//!
//! A file writes it as a JSON number (`1`, `0.5`, `2`); it must be a multiple of
//! 1/[`Ratio::DEN`] (checked by [`Ratio::check`] in `validate()`, so the error names the
//! field), and it is computed with as the integer count of those steps. A whole value is
//! written back as an integer, so that an architecture echoed in report.json reads as it
//! did when the field was an integer.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A positive figure in steps of 1/[`Ratio::DEN`], read from a JSON number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ratio(f64);

impl Ratio {
    /// The steps per unit: a figure is a multiple of 1/64 (0.5, 0.25, 1.5 are; 0.3 is not).
    /// Fine enough for halving and doubling any default a few times; coarse enough that a
    /// cycle count times it stays far from overflow.
    pub const DEN: u64 = 64;

    /// A whole figure.
    pub const fn whole(n: u64) -> Ratio {
        Ratio(n as f64)
    }

    /// The figure as written.
    pub fn get(self) -> f64 {
        self.0
    }

    /// The figure in steps of 1/[`Ratio::DEN`] (valid only after [`Ratio::check`]).
    pub fn steps(self) -> u64 {
        (self.0 * Self::DEN as f64) as u64
    }

    /// ceil(n * self), exact.
    pub fn ceil_mul(self, n: u64) -> u64 {
        (n as u128 * self.steps() as u128).div_ceil(Self::DEN as u128) as u64
    }

    /// ceil(n / self), exact.
    pub fn ceil_div(self, n: u64) -> u64 {
        (n as u128 * Self::DEN as u128).div_ceil(self.steps().max(1) as u128) as u64
    }

    /// Whether the figure is a multiple of 1/[`Ratio::DEN`] in 1/DEN..=max; the reason it
    /// is refused otherwise.
    pub fn check(self, max: u64) -> std::result::Result<(), String> {
        let steps = self.0 * Self::DEN as f64;
        let max_steps = (max * Self::DEN) as f64;
        if self.0.is_finite() && steps >= 1.0 && steps <= max_steps && steps.fract() == 0.0 {
            Ok(())
        } else {
            Err(format!(
                "must be a multiple of 1/{} from 1/{} to {max}",
                Self::DEN,
                Self::DEN
            ))
        }
    }
}

impl std::fmt::Display for Ratio {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

impl Serialize for Ratio {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.0.fract() == 0.0 && self.0 >= 0.0 && self.0 <= u64::MAX as f64 {
            s.serialize_u64(self.0 as u64)
        } else {
            s.serialize_f64(self.0)
        }
    }
}

impl<'de> Deserialize<'de> for Ratio {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Ratio, D::Error> {
        f64::deserialize(d).map(Ratio)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_is_exact_and_whole_values_read_back_as_integers() {
        let half = Ratio(0.5);
        assert_eq!(half.check(64), Ok(()));
        assert_eq!((half.ceil_mul(7), half.ceil_div(7)), (4, 14));
        let one = Ratio::whole(1);
        assert_eq!((one.ceil_mul(7), one.ceil_div(7)), (7, 7));
        assert_eq!((Ratio(2.0).ceil_mul(7), Ratio(2.0).ceil_div(7)), (14, 4));
        assert_eq!(serde_json::to_string(&one).unwrap(), "1");
        assert_eq!(serde_json::to_string(&half).unwrap(), "0.5");
        let read: Ratio = serde_json::from_str("3").unwrap();
        assert_eq!(read, Ratio::whole(3));
        for bad in [0.0, -1.0, 0.3, 1.0 / 128.0, 65.0, f64::NAN] {
            assert!(Ratio(bad).check(64).is_err(), "{bad}");
        }
    }
}
