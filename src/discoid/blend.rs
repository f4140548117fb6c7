//! The arithmetic of the ROP's blend units in the accumulation pass of the atlas of discoids
//! (Piranda et al. 2006 section 3, equations 4-6, Table 1 and its shaders), one pixel at a time.
//!
//! Each fragment brings its beta and two interest values, cos α and cos^N γ (the diffuse
//! and specular factors of equation 6). The pixel keeps their beta-weighted averages and
//! Σβ, updated by equation (5)'s incremental form as fragments arrive:
//!
//! ```text
//! S_new = S_old + β                         F_new = (F_old·S_old + β·F_t) / S_new
//! ```
//!
//! for F = diffuse and F = specular, so the resolve pass reads the averages of equation (4)
//! directly. The blend ALU computes in f32 in every mode (a GPU's shader and blend
//! arithmetic); the modes differ in what the accumulation target stores:
//!
//! - **f32** (an RGBA32F target, the paper's MRT future work): the two averages and Σβ are
//!   f32 words. The fragment's beta is rounded to f32, each update is computed in f32. No
//!   clamping (float targets do not clamp; the update is a convex combination of values in
//!   [0, 1], so it stays there up to rounding).
//! - **f16** (RGBA16F): the same words stored as f16 ([`half::f16`]): read and widened to
//!   f32, updated in f32 (dividing by the unrounded f32 S_new), each word rounded to
//!   nearest f16 on store. Σβ's f16 ulp is 1/64 at 16 and the largest f16 is 65504, so
//!   Σβ loses precision long before it could overflow; float modes never saturate.
//! - **rgba8** (Table 1, the paper's own 4-byte target): R and G hold the running averages
//!   of diffuse and specular as unorm8, round(255·F) (Table 1 labels them with the sums
//!   Σβ cos α, but the text applies equation 5 to them, and a sum would overflow unorm8
//!   beyond Σβ = 1); B and A hold Σβ as a sum of 8-bit beta codes split into nibbles. A
//!   fragment's code is b = [`beta_code`]\(β) = min(255, round(256·β)) (the shader's
//!   `coef = beta*256`); it adds b >> 4 to B and b & 15 to A with 8-bit saturating adds
//!   (the blender's clamped additive blending; nibble sums do not carry into B). Σβ decodes as (16·B + A)/256. The fragment's beta in the update is
//!   the quantized b/256, and with the decoded (possibly saturated) S_old and S_new:
//!   R_new = round(255·clamp((R_old/255·S_old + (b/256)·F_t)/S_new, 0, 1)), the same for G.
//!   A fragment whose add would take B or A past 255 is *saturated* ([`Blended`]): from
//!   then on Σβ is too small and the averages lean towards later fragments (the clamp keeps
//!   them in range). The larger nibble saturates first: 17 fragments of β = 1
//!   (code 255 = (15, 15)) fit and the 18th does not, while code 1 fits 255 times; see
//!   `rgba8_saturates_at_the_overlap_count_the_packing_predicts`.
//!
//! In every mode a fragment whose (stored) beta is 0 changes nothing: the paper's shader
//! discards beta = 0, and in rgba8 that includes every β < 1/512 (b = 0).
//!
//! [`ExactAccum`] accumulates the same fragments in f64 with the unquantized beta and
//! divides once at the end (equation 4 directly): the reference the modes' errors are
//! measured against.
//!
//! **Counting** (DESIGN.md §12). The arithmetic is written once over the blend ALU's word
//! `W` ([`BlendMode::blend_in`], [`BlendMode::resolve_in`]): `f32` for every image, and a
//! counting `f32` for the cost model's counting run, the same IEEE operations in the same
//! order. What a word operation does is counted by the word: per fragment of a float mode
//! the zero test of β, S_old + β and per average two multiplies, an add and a divide. In
//! rgba8 the same update is counted on the word, and the integer work beside it: the
//! beta code's zero test, the two saturating nibble adds and the recombination 16·B + A of
//! each Σβ decoded. Not counted, as conversions everywhere are not: widening a stored f16
//! or unorm8 word to the ALU word (`R / 255`, Σβ's scale 1/256), and the store's rounding
//! back (f16 rounding; unorm8's clamp, scale by 255 and rounding, as the shader's colour
//! quantisation is not counted).
//!
//! What this does not model: where the fragments come from (the depth and culling tests of
//! the accumulation pass), the time a blend takes (a timed model charges
//! [`BlendMode::bytes_per_fragment`]), and two details of the paper's GPU encoding that a
//! fixed-function blend unit would not have: its shader writes the A nibble as a fraction of
//! 256 into a unorm8 channel (so A is the rounded, not the exact, remainder) and its resolve
//! decodes B·16 + A from unorm values (scaling Σβ by 256/255, a factor that cancels in the
//! averages). We keep the integer nibbles the paper describes.

use crate::datapath::{Op, Real};
use half::f16;
use serde::{Deserialize, Serialize};

/// The accumulation target's precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BlendMode {
    /// Table 1: unorm8 averages in R and G, Σβ in the nibbles of B and A.
    Rgba8,
    /// RGBA16F: averages and Σβ as f16.
    F16,
    /// RGBA32F: averages and Σβ as f32.
    F32,
}

impl BlendMode {
    /// Every mode, from the paper's to the most precise.
    pub const ALL: [BlendMode; 3] = [BlendMode::Rgba8, BlendMode::F16, BlendMode::F32];

    /// The mode's name in reports and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            BlendMode::Rgba8 => "rgba8",
            BlendMode::F16 => "f16",
            BlendMode::F32 => "f32",
        }
    }

    /// Accumulation-target bytes of one pixel: four channels of the mode's stored word,
    /// rgba8 4 (Table 1's RGBA8), f16 8 (RGBA16F), f32 16 (RGBA32F). The float modes use
    /// three of the four channels; the target is four-channel as a GPU's is \[bytes\].
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            BlendMode::Rgba8 => 4,
            BlendMode::F16 => 4 * 2,
            BlendMode::F32 => 4 * 4,
        }
    }

    /// Accumulation-target bytes one accumulated fragment moves: its pixel read and
    /// written, rgba8 8, f16 16, f32 32 \[bytes\].
    pub fn bytes_per_fragment(self) -> u64 {
        2 * self.bytes_per_pixel()
    }

    /// Blends one fragment into `px` by equation (5)'s incremental form:
    /// F_new = (F_old·S_old + β·F_t) / S_new, S_new = S_old + β, for F = diffuse and
    /// specular (see the module doc for each mode's words and rounding).
    pub fn blend(self, px: &mut Accum, f: BlendInput) -> Blended {
        self.blend_in::<f32>(px, f)
    }

    /// [`Self::blend`] with the blend ALU's word `W`: `f32`, or a counting `f32` that gives
    /// the same bits and counts the operations (see the module doc).
    pub fn blend_in<W: Real>(self, px: &mut Accum, f: BlendInput) -> Blended {
        debug_assert!(
            [f.beta, f.diffuse, f.specular]
                .iter()
                .all(|v| (0.0..=1.0).contains(v)),
            "{f:?}"
        );
        let input = [f.beta as f32, f.diffuse as f32, f.specular as f32];
        match self {
            BlendMode::F32 => {
                if let Some(words) = update::<W>(px.f32, input) {
                    px.f32 = words;
                }
                Blended { saturated: false }
            }
            BlendMode::F16 => {
                if let Some(words) = update::<W>(px.f16.map(f16::to_f32), input) {
                    px.f16 = words.map(f16::from_f32);
                }
                Blended { saturated: false }
            }
            BlendMode::Rgba8 => blend_rgba8::<W>(&mut px.rgba8, beta_code(f.beta), input),
        }
    }

    /// The resolved averages (diffuse, specular) = (Σβ cos α / Σβ, Σβ cos^N γ / Σβ), or None
    /// when nothing was accumulated (Σβ = 0).
    pub fn resolve(self, px: &Accum) -> Option<(f64, f64)> {
        self.resolve_in::<f32>(px)
    }

    /// [`Self::resolve`] with the blend ALU's word `W`: the stored averages are read as
    /// they are (equation 5 divided by Σβ as the fragments arrived), so the resolve's one
    /// operation is Σβ's zero test: a compare of the word in the float modes, the
    /// recombination 16·B + A and an integer test in rgba8.
    pub fn resolve_in<W: Real>(self, px: &Accum) -> Option<(f64, f64)> {
        let empty = match self {
            BlendMode::F32 | BlendMode::F16 => W::of(self.sum_beta(px)) == W::zero(),
            BlendMode::Rgba8 => {
                W::count_beside(Op::IntAdd, 2);
                self.sum_beta(px) == 0.0
            }
        };
        if empty {
            return None;
        }
        Some(match self {
            BlendMode::F32 => (f64::from(px.f32[0]), f64::from(px.f32[1])),
            BlendMode::F16 => (f64::from(px.f16[0]), f64::from(px.f16[1])),
            BlendMode::Rgba8 => (
                f64::from(px.rgba8[0]) / 255.0,
                f64::from(px.rgba8[1]) / 255.0,
            ),
        })
    }

    /// The pixel's Σβ as this mode stores it (rgba8: decoded, possibly saturated).
    pub fn sum_beta(self, px: &Accum) -> f64 {
        match self {
            BlendMode::F32 => f64::from(px.f32[2]),
            BlendMode::F16 => f64::from(px.f16[2]),
            BlendMode::Rgba8 => f64::from(decode_sum::<f32>(px.rgba8)),
        }
    }
}

/// What one fragment brings to the accumulation: its beta and its two interest values
/// (Piranda et al. 2006: cos α and cos^N γ), each in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendInput {
    /// The discoid's beta at the fragment (the sampled texture), in [0, 1].
    pub beta: f64,
    /// cos α, the diffuse factor, in [0, 1].
    pub diffuse: f64,
    /// cos^N γ, the specular factor, in [0, 1].
    pub specular: f64,
}

/// One pixel's accumulation target, in any mode (only the words of the pixel's mode are
/// used). The default is the cleared target: nothing accumulated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Accum {
    /// f32 mode: [diffuse average, specular average, Σβ].
    f32: [f32; 3],
    /// f16 mode: [diffuse average, specular average, Σβ].
    f16: [f16; 3],
    /// rgba8 mode: [R, G, B, A] of Table 1: unorm8 diffuse and specular averages, Σβ's
    /// high and low nibble sums.
    rgba8: [u8; 4],
}

impl Accum {
    /// The f32 mode's words: [diffuse average, specular average, Σβ].
    pub fn f32_words(&self) -> [f32; 3] {
        self.f32
    }

    /// The f16 mode's words: [diffuse average, specular average, Σβ].
    pub fn f16_words(&self) -> [f16; 3] {
        self.f16
    }

    /// The rgba8 mode's bytes [R, G, B, A].
    pub fn rgba8_bytes(&self) -> [u8; 4] {
        self.rgba8
    }
}

/// One pixel's exact accumulation in f64, from the same fragments (the error reference):
/// sums of beta, beta·diffuse, beta·specular with the unquantized beta.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExactAccum {
    /// Σβ.
    sum_beta: f64,
    /// Σβ·cos α.
    sum_diffuse: f64,
    /// Σβ·cos^N γ.
    sum_specular: f64,
}

impl ExactAccum {
    /// Adds fragment `f` to the sums, in f64.
    pub fn add(&mut self, f: BlendInput) {
        self.sum_beta += f.beta;
        self.sum_diffuse += f.beta * f.diffuse;
        self.sum_specular += f.beta * f.specular;
    }

    /// Σβ.
    pub fn sum_beta(&self) -> f64 {
        self.sum_beta
    }

    /// Equation (4): (Σβ cos α / Σβ, Σβ cos^N γ / Σβ), or None when Σβ = 0.
    pub fn resolve(&self) -> Option<(f64, f64)> {
        (self.sum_beta > 0.0).then(|| {
            (
                self.sum_diffuse / self.sum_beta,
                self.sum_specular / self.sum_beta,
            )
        })
    }
}

/// What blending one fragment did (for counters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Blended {
    /// rgba8: the fragment's beta code did not fit in B or A (an 8-bit add clamped at 255).
    /// Always false in the float modes.
    pub saturated: bool,
}

/// The rgba8 packing of an 8-bit beta code b (beta·256 = 16·B + A, paper Table 1 and its
/// shader): (B, A) = (b >> 4, b & 15).
pub fn pack_beta(b: u8) -> (u8, u8) {
    (b >> 4, b & 15)
}

/// The 8-bit beta code of a beta in [0, 1]: min(255, round(256·beta)) (the shader's
/// coef = beta·256, stored in 8 bits).
pub fn beta_code(beta: f64) -> u8 {
    // The float-to-int cast saturates (and maps NaN to 0); the min is the 8-bit store.
    (256.0 * beta).round().min(255.0) as u8
}

/// An `f32` as the blend ALU's word (exact: the word is an `f32`).
#[inline(always)]
fn word<W: Real>(x: f32) -> W {
    W::of(f64::from(x))
}

/// The blend ALU's word back as the `f32` it holds (exact).
#[inline(always)]
fn f32_of<W: Real>(w: W) -> f32 {
    w.f64() as f32
}

/// Equation (5) in the ALU's word on [F_diffuse, F_specular, S] with the fragment's
/// [β, diffuse, specular]; None when β = 0 (nothing changes).
fn update<W: Real>(words: [f32; 3], input: [f32; 3]) -> Option<[f32; 3]> {
    let [fd, fs, s_old] = words.map(word::<W>);
    let [beta, d, s] = input.map(word::<W>);
    if beta == W::zero() {
        return None;
    }
    let s_new = s_old + beta;
    Some(
        [
            (fd * s_old + beta * d) / s_new,
            (fs * s_old + beta * s) / s_new,
            s_new,
        ]
        .map(f32_of),
    )
}

/// Σβ of an rgba8 pixel, (16·B + A)/256: the recombination of the nibble sums is an
/// integer add (counted); the scale by 1/256 places Σβ's fixed point (a conversion).
fn decode_sum<W: Real>(rgba: [u8; 4]) -> W {
    W::count_beside(Op::IntAdd, 1);
    word((16.0 * f32::from(rgba[2]) + f32::from(rgba[3])) / 256.0)
}

/// Table 1's update of the bytes [R, G, B, A] by a fragment of beta code `b` and interest
/// values `input[1..]` (see the module doc).
fn blend_rgba8<W: Real>(rgba: &mut [u8; 4], b: u8, input: [f32; 3]) -> Blended {
    // The zero test of the 8-bit code.
    W::count_beside(Op::IntAdd, 1);
    if b == 0 {
        return Blended { saturated: false };
    }
    let s_old = decode_sum::<W>(*rgba);
    // Two 8-bit saturating adds (the saturation is the adder's carry out).
    W::count_beside(Op::IntAdd, 2);
    let (hi, lo) = pack_beta(b);
    let (new_b, b_over) = rgba[2].overflowing_add(hi);
    let (new_a, a_over) = rgba[3].overflowing_add(lo);
    rgba[2] = if b_over { u8::MAX } else { new_b };
    rgba[3] = if a_over { u8::MAX } else { new_a };
    let s_new = decode_sum::<W>(*rgba);
    let beta = word::<W>(f32::from(b) / 256.0);
    for (channel, value) in [(0, input[1]), (1, input[2])] {
        let old = word::<W>(f32::from(rgba[channel]) / 255.0);
        let avg = f32_of((old * s_old + beta * word(value)) / s_new);
        rgba[channel] = (255.0 * avg.clamp(0.0, 1.0)).round() as u8;
    }
    Blended {
        saturated: b_over || a_over,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::testkit::SplitMix64;

    pub(crate) fn frag(beta: f64, diffuse: f64, specular: f64) -> BlendInput {
        BlendInput {
            beta,
            diffuse,
            specular,
        }
    }

    /// Blends `frags` into a cleared pixel in `mode`; the pixel and whether any saturated.
    fn accumulate(mode: BlendMode, frags: &[BlendInput]) -> (Accum, bool) {
        let mut px = Accum::default();
        let mut saturated = false;
        for &f in frags {
            saturated |= mode.blend(&mut px, f).saturated;
        }
        (px, saturated)
    }

    /// 1..=16 fragments with beta in (0, 1] and interest values in [0, 1], drawn from `rng`.
    pub(crate) fn stream(rng: &mut SplitMix64) -> Vec<BlendInput> {
        let n = 1 + (rng.next_u64() % 16) as usize;
        (0..n)
            .map(|_| frag(1.0 - rng.unit(), rng.unit(), rng.unit()))
            .collect()
    }

    #[test]
    fn blend_modes_have_names_and_bytes() {
        let names: Vec<_> = BlendMode::ALL.iter().map(|m| m.name()).collect();
        assert_eq!(names, ["rgba8", "f16", "f32"]);
        let bytes: Vec<_> = BlendMode::ALL
            .iter()
            .map(|m| m.bytes_per_fragment())
            .collect();
        assert_eq!(bytes, [8, 16, 32]);
        for mode in BlendMode::ALL {
            let json = serde_json::to_string(&mode).unwrap();
            assert_eq!(json, format!("\"{}\"", mode.name()));
            assert_eq!(serde_json::from_str::<BlendMode>(&json).unwrap(), mode);
        }
    }

    /// The accumulation target's bytes per pixel are four channels of the word each mode
    /// stores (the float modes use three of them), and a fragment reads and writes one.
    #[test]
    fn bytes_per_pixel_are_four_channels_of_the_stored_word() {
        let px = Accum::default();
        let stored = [
            (
                BlendMode::Rgba8,
                std::mem::size_of_val(&px.rgba8_bytes()) / 4,
            ),
            (BlendMode::F16, std::mem::size_of_val(&px.f16_words()) / 3),
            (BlendMode::F32, std::mem::size_of_val(&px.f32_words()) / 3),
        ];
        for (mode, word_bytes) in stored {
            assert_eq!(mode.bytes_per_pixel(), 4 * word_bytes as u64, "{mode:?}");
            assert_eq!(mode.bytes_per_fragment(), 2 * mode.bytes_per_pixel());
        }
        assert_eq!(BlendMode::ALL.map(BlendMode::bytes_per_pixel), [4, 8, 16]);
    }

    #[test]
    fn blend_two_overlapping_discoids_by_hand() {
        // β = 1/2 with (cos α, cos^N γ) = (1, 0), then β = 1/4 with (0, 1): Σβ = 3/4,
        // averages (0.5/0.75, 0.25/0.75) = (2/3, 1/3).
        let frags = [frag(0.5, 1.0, 0.0), frag(0.25, 0.0, 1.0)];
        let mut exact = ExactAccum::default();
        frags.iter().for_each(|&f| exact.add(f));
        assert_eq!(exact.sum_beta(), 0.75);
        let (d, s) = exact.resolve().unwrap();
        assert!((d - 2.0 / 3.0).abs() < 1e-15 && (s - 1.0 / 3.0).abs() < 1e-15);

        // f32: after the first fragment (1·0 + 0.5·1)/0.5 = 1 and 0 exactly; after the
        // second 0.5/0.75 and 0.25/0.75, each one correctly rounded f32 division.
        let (px, sat) = accumulate(BlendMode::F32, &frags[..1]);
        assert_eq!((px.f32_words(), sat), ([1.0, 0.0, 0.5], false));
        let (px, sat) = accumulate(BlendMode::F32, &frags);
        assert_eq!(px.f32_words(), [0.5f32 / 0.75, 0.25f32 / 0.75, 0.75]);
        assert_eq!(px.f32_words()[0], 11_184_811.0 / 16_777_216.0); // 2/3 to 24 bits
        assert!(!sat);
        let (d, s) = BlendMode::F32.resolve(&px).unwrap();
        assert_eq!(
            (d, s),
            (11_184_811.0 / 16_777_216.0, 11_184_811.0 / 33_554_432.0)
        );

        // f16: the same f32 results stored to 11 significant bits: 2/3 = 1.0101010101|01..
        // × 2^-1 rounds down to 1365/2048, 1/3 to 1365/4096; 0.75 is exact.
        let (px, sat) = accumulate(BlendMode::F16, &frags);
        let words = px.f16_words().map(f16::to_f64);
        assert_eq!(words, [1365.0 / 2048.0, 1365.0 / 4096.0, 0.75]);
        assert!(!sat);
        assert_eq!(
            BlendMode::F16.resolve(&px),
            Some((1365.0 / 2048.0, 1365.0 / 4096.0))
        );

        // rgba8: codes 128 = (8, 0) and 64 = (4, 0).
        // First: B = 8, S = 0.5, R = round(255·(0.5·1)/0.5) = 255, G = 0.
        let (px, _) = accumulate(BlendMode::Rgba8, &frags[..1]);
        assert_eq!(px.rgba8_bytes(), [255, 0, 8, 0]);
        // Second: B = 12, S_old = 0.5, S_new = 192/256 = 0.75,
        // R = round(255·(255/255·0.5 + 0.25·0)/0.75) = 170, G = round(255·(0.25·1)/0.75) = 85.
        let (px, sat) = accumulate(BlendMode::Rgba8, &frags);
        assert_eq!(px.rgba8_bytes(), [170, 85, 12, 0]);
        assert!(!sat);
        assert_eq!(BlendMode::Rgba8.sum_beta(&px), 0.75);
        assert_eq!(
            BlendMode::Rgba8.resolve(&px),
            Some((170.0 / 255.0, 85.0 / 255.0))
        );
    }

    #[test]
    fn blend_three_overlapping_discoids_by_hand() {
        // β = 100/256, 60/256, 96/256 (codes 100 = (6, 4), 60 = (3, 12), 96 = (6, 0): the A
        // nibbles sum to 16 without carrying into B); Σβ = 1.
        // (cos α, cos^N γ) = (1, 0), (0, 1), (1/2, 1/4).
        // Exact: diffuse = (100 + 0 + 48)/256 = 0.578125, specular = (0 + 60 + 24)/256 = 0.328125.
        let frags = [
            frag(100.0 / 256.0, 1.0, 0.0),
            frag(60.0 / 256.0, 0.0, 1.0),
            frag(96.0 / 256.0, 0.5, 0.25),
        ];
        let mut exact = ExactAccum::default();
        frags.iter().for_each(|&f| exact.add(f));
        assert_eq!(exact.resolve(), Some((0.578125, 0.328125)));

        // Floats: every intermediate is dyadic, so both float modes are exact. After two:
        // S = 160/256, F = (100/256)/(160/256) = 0.625 and (60/256)/(160/256) = 0.375.
        // After three: 0.625·0.625 + 0.375·0.5 = 0.578125, 0.375·0.625 + 0.375·0.25 = 0.328125.
        for mode in [BlendMode::F32, BlendMode::F16] {
            let (px, sat) = accumulate(mode, &frags[..2]);
            assert!(!sat);
            assert_eq!(mode.sum_beta(&px), 0.625, "{}", mode.name());
            assert_eq!(mode.resolve(&px), Some((0.625, 0.375)), "{}", mode.name());
            let (px, _) = accumulate(mode, &frags);
            assert_eq!(mode.sum_beta(&px), 1.0, "{}", mode.name());
            assert_eq!(
                mode.resolve(&px),
                Some((0.578125, 0.328125)),
                "{}",
                mode.name()
            );
        }
        let (px, _) = accumulate(BlendMode::F16, &frags);
        assert_eq!(px.f16_words().map(f16::to_f64), [0.578125, 0.328125, 1.0]);

        // rgba8, fragment by fragment.
        // 1: B = 6, A = 4, S = 100/256: R = round(255·(100/256·1)/(100/256)) = 255, G = 0.
        let (px, _) = accumulate(BlendMode::Rgba8, &frags[..1]);
        assert_eq!(px.rgba8_bytes(), [255, 0, 6, 4]);
        // 2: B = 9, A = 16, S = (144 + 16)/256 = 0.625:
        //    R = round(255·(1·100/256 + 0)/0.625) = round(159.375) = 159,
        //    G = round(255·(0 + 60/256·1)/0.625) = round(95.625) = 96.
        let (px, _) = accumulate(BlendMode::Rgba8, &frags[..2]);
        assert_eq!(px.rgba8_bytes(), [159, 96, 9, 16]);
        // 3: B = 15, A = 16, S = (240 + 16)/256 = 1:
        //    R = round(159·0.625 + 255·0.375·0.5) = round(99.375 + 47.8125) = 147,
        //    G = round(96·0.625 + 255·0.375·0.25) = round(60 + 23.90625) = 84.
        let (px, sat) = accumulate(BlendMode::Rgba8, &frags);
        assert_eq!(px.rgba8_bytes(), [147, 84, 15, 16]);
        assert!(!sat);
        assert_eq!(BlendMode::Rgba8.sum_beta(&px), 1.0);
        assert_eq!(
            BlendMode::Rgba8.resolve(&px),
            Some((147.0 / 255.0, 84.0 / 255.0))
        );
    }

    #[test]
    fn blend_of_nothing_resolves_to_none() {
        for mode in BlendMode::ALL {
            let px = Accum::default();
            assert_eq!(mode.resolve(&px), None, "{}", mode.name());
            // beta = 0 changes nothing; in rgba8 neither does a beta whose code is 0.
            let (px, _) = accumulate(mode, &[frag(0.0, 1.0, 1.0)]);
            assert_eq!(
                (px, mode.resolve(&px)),
                (Accum::default(), None),
                "{}",
                mode.name()
            );
            let (px, _) = accumulate(mode, &[frag(0.5, 0.25, 0.75), frag(0.0, 1.0, 1.0)]);
            assert_eq!(
                px,
                accumulate(mode, &[frag(0.5, 0.25, 0.75)]).0,
                "{}",
                mode.name()
            );
        }
        let (px, _) = accumulate(BlendMode::Rgba8, &[frag(1.0 / 513.0, 1.0, 1.0)]);
        assert_eq!(BlendMode::Rgba8.resolve(&px), None);
        assert_eq!(ExactAccum::default().resolve(), None);
    }

    #[test]
    fn rgba8_packing_round_trips_every_beta_code() {
        for b in 0..=255u8 {
            let (hi, lo) = pack_beta(b);
            assert!(hi < 16 && lo < 16, "{b}");
            assert_eq!(16 * u32::from(hi) + u32::from(lo), u32::from(b));
            assert_eq!(beta_code(f64::from(b) / 256.0), b);
            // One fragment alone decodes to its code.
            let (px, _) = accumulate(BlendMode::Rgba8, &[frag(f64::from(b) / 256.0, 0.5, 0.5)]);
            assert_eq!(BlendMode::Rgba8.sum_beta(&px), f64::from(b) / 256.0);
        }
        // beta = 1 would be code 256: it is stored as 255.
        assert_eq!(beta_code(1.0), 255);
        assert_eq!(beta_code(0.0), 0);
        assert_eq!(beta_code(1.0 / 513.0), 0);
        assert_eq!(beta_code(1.0 / 511.0), 1);
    }

    #[test]
    fn rgba8_saturates_at_the_overlap_count_the_packing_predicts() {
        for b in 1..=255u8 {
            let (hi, lo) = pack_beta(b);
            // m equal fragments add m·n to a nibble channel; it saturates once m·n > 255, at
            // m = floor(255/n) + 1. The first channel to saturate decides.
            let m_star = [hi, lo]
                .into_iter()
                .filter(|&n| n > 0)
                .map(|n| 255 / u32::from(n) + 1)
                .min()
                .unwrap();
            let f = frag(f64::from(b) / 256.0, 0.75, 0.25);
            let mut px = Accum::default();
            for m in 1..m_star {
                assert!(
                    !BlendMode::Rgba8.blend(&mut px, f).saturated,
                    "b {b}, fragment {m}"
                );
            }
            let bytes = px.rgba8_bytes();
            assert_eq!(u32::from(bytes[2]), (m_star - 1) * u32::from(hi), "b {b}");
            assert_eq!(u32::from(bytes[3]), (m_star - 1) * u32::from(lo), "b {b}");
            assert!(
                BlendMode::Rgba8.blend(&mut px, f).saturated,
                "b {b}, fragment {m_star}"
            );
        }
        // β = 1 (code 255 = (15, 15)): 17 fragments fit, the 18th saturates both.
        let (_, sat) = accumulate(BlendMode::Rgba8, &[frag(1.0, 1.0, 1.0); 17]);
        assert!(!sat);
        let (px, sat) = accumulate(BlendMode::Rgba8, &[frag(1.0, 1.0, 1.0); 18]);
        assert!(sat);
        assert_eq!(px.rgba8_bytes()[2..], [255, 255]);
    }

    #[test]
    fn rgba8_saturated_pixel_stays_in_range() {
        // Once Σβ is stuck, each new fragment's full weight lands on a sum that did not
        // grow: the clamp keeps the averages in [0, 1].
        let mut px = Accum::default();
        let mut n_saturated = 0;
        for i in 0..64 {
            let f = frag(1.0, f64::from(i % 2), f64::from((i + 1) % 2));
            n_saturated += usize::from(BlendMode::Rgba8.blend(&mut px, f).saturated);
            let (d, s) = BlendMode::Rgba8.resolve(&px).unwrap();
            assert!((0.0..=1.0).contains(&d) && (0.0..=1.0).contains(&s));
        }
        assert_eq!(n_saturated, 64 - 17);
    }

    #[test]
    fn f32_incremental_form_agrees_with_the_direct_average() {
        let mut rng = SplitMix64::new(0x5eed_0001);
        let mut worst = 0.0f64;
        for _ in 0..20_000 {
            let frags = stream(&mut rng);
            let mut exact = ExactAccum::default();
            frags.iter().for_each(|&f| exact.add(f));
            let (px, _) = accumulate(BlendMode::F32, &frags);
            let (d, s) = BlendMode::F32.resolve(&px).unwrap();
            let (ed, es) = exact.resolve().unwrap();
            worst = worst.max((d - ed).abs()).max((s - es).abs());
            assert!((BlendMode::F32.sum_beta(&px) - exact.sum_beta()).abs() < 1e-5);
        }
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn blend_error_is_ordered_f32_f16_rgba8() {
        let mut rng = SplitMix64::new(0x5eed_0002);
        let mut error = [0.0f64; 3];
        let mut n_resolved = [0u32; 3];
        let mut n_all_codes_zero = 0;
        for _ in 0..20_000 {
            let frags = stream(&mut rng);
            let mut exact = ExactAccum::default();
            frags.iter().for_each(|&f| exact.add(f));
            let (ed, es) = exact.resolve().unwrap();
            n_all_codes_zero += u32::from(frags.iter().all(|f| beta_code(f.beta) == 0));
            for (k, mode) in [BlendMode::F32, BlendMode::F16, BlendMode::Rgba8]
                .into_iter()
                .enumerate()
            {
                let (px, sat) = accumulate(mode, &frags);
                // At most 16 fragments of code <= 255 (nibbles <= 15): 240 fits in a byte.
                assert!(!sat);
                // A pixel rgba8 drops (every beta < 1/512) is a hole, not an average: the
                // averages' error is over the pixels each mode resolves.
                if let Some((d, s)) = mode.resolve(&px) {
                    error[k] += ((d - ed).abs() + (s - es).abs()) / 2.0;
                    n_resolved[k] += 1;
                }
            }
        }
        assert_eq!(n_resolved[..2], [20_000, 20_000]);
        assert_eq!(n_resolved[2], 20_000 - n_all_codes_zero);
        let [f32_err, f16_err, rgba8_err] = [0, 1, 2].map(|k| error[k] / f64::from(n_resolved[k]));
        // Each step down loses at least an order of magnitude: f32 ~1e-8, f16 ~1e-4 (11-bit
        // significands), rgba8 ~1e-3 (8-bit words and 8-bit betas).
        assert!(10.0 * f32_err < f16_err, "f32 {f32_err:e}, f16 {f16_err:e}");
        assert!(
            5.0 * f16_err < rgba8_err,
            "f16 {f16_err:e}, rgba8 {rgba8_err:e}"
        );
        assert!(rgba8_err < 4.0 / 255.0, "rgba8 {rgba8_err:e}");
    }
}
