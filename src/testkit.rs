//! What tests, studies and examples share and the shipped binary leaves out: compiled for
//! the crate's unit tests and with the `testkit` feature, which every build of tests,
//! examples or benchmarks turns on (Cargo.toml) and `cargo build --release` does not.
//!
//! [`SplitMix64`] is the one seeded random number generator of the crate's tests, of the
//! timed runtime's test hooks (`SimOptions::perturb` and `partition_seed`, compiled with
//! this feature only) and of the datapath study (`examples/datapath_study/`): the study's
//! committed results are its sequence, so it stays this generator, bit for bit.

use glam::{DVec2, DVec3};

/// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators",
/// OOPSLA 2014): a 64-bit state, one multiply-xorshift finaliser per draw. The same seed
/// gives the same sequence on every machine.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator started at `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in 0..n (n > 0), by the top bits' product, without a division's bias
    /// beyond 2⁻⁶⁴ n.
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// Uniform in lo..hi (lo < hi).
    pub fn range_i64(&mut self, lo: i64, hi: i64) -> i64 {
        lo + self.below(hi.abs_diff(lo)) as i64
    }

    /// Log-uniform in [lo, hi), both > 0.
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }

    /// A uniform point of the unit disc.
    pub fn disc(&mut self) -> DVec2 {
        let (r, a) = (self.unit().sqrt(), self.range(0.0, std::f64::consts::TAU));
        DVec2::new(r * a.cos(), r * a.sin())
    }

    /// A uniform unit vector.
    pub fn direction(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let a = self.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        DVec3::new(r * a.cos(), r * a.sin(), z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        // The first outputs for seed 1234567 of the reference C implementation
        // (Vigna, splitmix64.c).
        let mut g = SplitMix64::new(1234567);
        assert_eq!(g.next_u64(), 6457827717110365317);
        assert_eq!(g.next_u64(), 3203168211198807973);
    }

    #[test]
    fn below_stays_below_and_reaches_every_value() {
        let mut g = SplitMix64::new(3);
        let mut seen = [false; 5];
        for _ in 0..200 {
            let v = g.below(5);
            assert!(v < 5, "{v}");
            seen[v as usize] = true;
        }
        assert_eq!(seen, [true; 5]);
    }
}
