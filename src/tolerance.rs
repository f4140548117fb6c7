//! The lembo path's tolerances, each with its type, default, accepted range and check in one
//! place: k, the midpoint error of the extreme method's walk (Martinelli 2006 section 5;
//! DESIGN.md §8), and Setup's perspective tolerance (`raster::refine`). `render`, `compare`
//! and a sweep's grid take their defaults from here and check a value with the function
//! here, each naming where the value came from; the stages only read a [`Tolerance`].

/// Tolerance k when none is given \[pixels\]: `render`'s and `compare`'s default, and a
/// sweep point's that sets none.
pub const DEFAULT_K_PX: f64 = 0.5;

/// Accepted range of the tolerance k \[pixels\] (DESIGN.md §8).
pub const K_RANGE: (f64, f64) = (1e-4, 64.0);

/// Checks a tolerance k \[pixels\]: it must lie in [`K_RANGE`] (so it is finite). The error
/// says what is accepted; the caller names the flag or field and the value as given.
pub fn check_k(k: f64) -> Result<f64, String> {
    let (lo, hi) = K_RANGE;
    if k >= lo && k <= hi {
        Ok(k)
    } else {
        Err(format!("k must be a number in [{lo}, {hi}] pixels"))
    }
}

/// What Setup's perspective tolerance is by default, as a fraction of k: with the walk's
/// error at most k and Setup's at most k/2, k bounds the end-to-end error of a fragment's
/// position to within 1.5 k.
pub const DEFAULT_PERSPECTIVE_FRACTION: f64 = 0.5;

/// The lembo path's tolerances \[pixels\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// k: the midpoint error of every segment of the walk (Martinelli 2006, section 5).
    pub k: f64,
    /// How far Setup's rebuilt screen quadratics may be from the true perspective projection
    /// before it splits a lembo (`raster::refine`, `--perspective-tol`);
    /// `None` is the paper's Setup, which projects six points and neither splits for
    /// perspective nor clips.
    pub perspective: Option<f64>,
}

impl Tolerance {
    /// k with the default perspective tolerance, k · [`DEFAULT_PERSPECTIVE_FRACTION`].
    pub fn new(k: f64) -> Self {
        Tolerance {
            k,
            perspective: Some(k * DEFAULT_PERSPECTIVE_FRACTION),
        }
    }

    /// These tolerances on a grid of `rows_per_pixel` rows a pixel (a multisampled frame's
    /// sample grid): k, a distance across the rows, in rows (that many times k); the
    /// perspective tolerance stays in pixels (Setup measures its error in pixels).
    pub fn on_grid(self, rows_per_pixel: u32) -> Self {
        Tolerance {
            k: self.k * rows_per_pixel as f64,
            ..self
        }
    }

    /// k with Setup as the paper has it (`--perspective-tol off`).
    pub fn paper(k: f64) -> Self {
        Tolerance {
            k,
            perspective: None,
        }
    }
}

impl From<f64> for Tolerance {
    /// k with the default perspective tolerance ([`Tolerance::new`]).
    fn from(k: f64) -> Self {
        Tolerance::new(k)
    }
}

/// Setup's perspective tolerance as a user sets it (`--perspective-tol PX|off`).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum PerspectiveTol {
    /// k · [`DEFAULT_PERSPECTIVE_FRACTION`].
    #[default]
    FollowK,
    /// A fixed tolerance \[pixels\], finite and > 0.
    Px(f64),
    /// The paper's Setup: no perspective split, no near-plane handling.
    Off,
}

impl PerspectiveTol {
    /// The tolerances for k \[pixels\].
    pub fn with_k(self, k: f64) -> Tolerance {
        match self {
            PerspectiveTol::FollowK => Tolerance::new(k),
            PerspectiveTol::Px(px) => Tolerance {
                k,
                perspective: Some(px),
            },
            PerspectiveTol::Off => Tolerance::paper(k),
        }
    }

    /// Parses `off` or a number of pixels; the error says what is accepted.
    pub fn parse(text: &str) -> Result<Self, String> {
        if text.trim() == "off" {
            return Ok(PerspectiveTol::Off);
        }
        match text.trim().parse::<f64>() {
            Ok(px) => PerspectiveTol::px(px),
            Err(_) => Err(format!(
                "must be `off` or a tolerance in pixels, a finite number > 0 (got `{text}`)"
            )),
        }
    }

    /// A fixed tolerance, refused unless finite and > 0.
    pub fn px(px: f64) -> Result<Self, String> {
        if px.is_finite() && px > 0.0 {
            Ok(PerspectiveTol::Px(px))
        } else {
            Err(format!(
                "must be `off` or a tolerance in pixels, a finite number > 0 (got {px})"
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_k_accepts_its_range_and_nothing_else() {
        let (lo, hi) = K_RANGE;
        for k in [lo, DEFAULT_K_PX, hi] {
            assert_eq!(check_k(k), Ok(k));
        }
        let why = "k must be a number in [0.0001, 64] pixels".to_string();
        for k in [0.0, 9e-5, 64.5, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(check_k(k), Err(why.clone()), "k = {k}");
        }
    }

    #[test]
    fn perspective_tol_follows_k_by_default() {
        assert_eq!(
            PerspectiveTol::default().with_k(0.5),
            Tolerance {
                k: 0.5,
                perspective: Some(0.25)
            }
        );
        assert_eq!(
            PerspectiveTol::parse(" off ")
                .unwrap()
                .with_k(2.0)
                .perspective,
            None
        );
        assert_eq!(PerspectiveTol::parse("0.1"), Ok(PerspectiveTol::Px(0.1)));
        for bad in ["0", "-1", "inf", "NaN", "x"] {
            assert!(
                PerspectiveTol::parse(bad)
                    .unwrap_err()
                    .starts_with("must be `off` or a tolerance in pixels"),
                "{bad}"
            );
        }
    }
}
