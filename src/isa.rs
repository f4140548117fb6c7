//! The instruction set the model's hot kernels run as compiled for on this host: on an
//! x86-64 CPU with AVX2, the AVX2 builds of the scan-line stages, the triangle rows and the
//! ROP's shading lanes; elsewhere, the baseline build. Both are the same IEEE operations in
//! the same order (no fused multiply-add is enabled, and Rust does not contract without
//! it), so the same bits: only host time differs. Tests compare the two builds, and check
//! that a CPU with AVX2 is given the AVX2 build.

/// An instruction set the hot kernels are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// x86-64 with AVX2 (three-operand vector instructions, rounding inline).
    Avx2,
    /// The target's baseline.
    Baseline,
}

/// The build of the hot kernels this host runs: [`Isa::Avx2`] exactly when the CPU has it
/// (a cached check, cheap enough to ask per call).
#[inline]
pub fn kernels() -> Isa {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        return Isa::Avx2;
    }
    Isa::Baseline
}

/// Whether this host's CPU reports AVX2, read from /proc/cpuinfo rather than by the check
/// [`kernels`] makes, so that a test can hold the dispatch to it; None where the file
/// cannot be read (not Linux). Under Miri the CPU is the one Miri models, which has the
/// features the build enables (`-C target-feature=+avx2` to run the AVX2 kernels there).
#[cfg(test)]
pub fn cpu_reports_avx2() -> Option<bool> {
    if cfg!(miri) {
        return Some(cfg!(target_feature = "avx2"));
    }
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let flags = text.lines().find(|l| l.starts_with("flags"))?;
    Some(flags.split_whitespace().any(|f| f == "avx2"))
}

/// For a test comparing the AVX2 build with the baseline: true when the comparison can run
/// here. Fails the test when the CPU reports AVX2 but the kernels dispatched are not the
/// AVX2 build; says on standard error when the CPU has no AVX2 (then the AVX2 build cannot
/// run, and `what` is skipped).
#[cfg(test)]
pub fn avx2_comparable(what: &str) -> bool {
    let reported = cpu_reports_avx2();
    if reported == Some(true) {
        assert_eq!(
            kernels(),
            Isa::Avx2,
            "the CPU has AVX2 but the kernels dispatched are the baseline build"
        );
    }
    if kernels() == Isa::Avx2 {
        return true;
    }
    eprintln!("skipped {what}: this CPU has no AVX2 (/proc/cpuinfo: {reported:?}), so only the baseline build can run");
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dispatch follows the CPU: AVX2 where /proc/cpuinfo lists it, the baseline where
    /// it does not.
    #[test]
    fn the_kernels_follow_the_cpu() {
        match cpu_reports_avx2() {
            Some(true) => assert_eq!(kernels(), Isa::Avx2),
            Some(false) => assert_eq!(kernels(), Isa::Baseline),
            None => eprintln!("skipped: no /proc/cpuinfo to hold the dispatch to"),
        }
    }
}
