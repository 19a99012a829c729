//! [`TargetEncoding`]: how distances become network outputs and back. It is the one place
//! that encodes targets for training, encodes the distances a network computes, and decodes
//! predictions for inference.

use crate::{NetsError, Result};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The encoded value of obstacles and unreachable cells, in every encoding.
pub const BLOCKED: f32 = -1.0;

/// Below this raw output the reciprocal encoding decodes linearly (see
/// [`TargetEncoding::decode`]).
const FLOOR: f32 = 1e-3;

/// How reaching distances (in cells) are encoded as network outputs. Obstacles and
/// unreachable cells are [`BLOCKED`] (-1) in both encodings.
///
/// ```
/// use envfield_nets::TargetEncoding;
/// let linear: TargetEncoding = "linear:100".parse()?;
/// assert_eq!(linear.encode(25.0), 0.75);
/// assert_eq!(linear.decode(0.75), 25.0);
/// assert_eq!(linear.encode(f32::INFINITY), -1.0);
/// assert_eq!(TargetEncoding::Reciprocal.encode(1.0), 0.5);
/// # Ok::<(), envfield_nets::NetsError>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TargetEncoding {
    /// The paper's `1 / (1 + d)` (appendix A.4): the goal is 1 and far cells approach 0.
    /// Precise near the goal, but neighbouring cells 40 steps away differ by only 6e-4.
    /// Written `reciprocal`.
    #[default]
    Reciprocal,
    /// `1 - d / scale`, clamped at 0: every step changes the output by `1 / scale`, so
    /// descent far from the goal needs no more precision than near it. Written
    /// `linear:SCALE`.
    Linear {
        /// The distance (in cells) mapped to 0; pick it above the longest path.
        scale: f32,
    },
}

impl TargetEncoding {
    /// Encodes a distance in cells; an infinite or negative distance (blocked) is
    /// [`BLOCKED`].
    pub fn encode(self, distance: f32) -> f32 {
        if !(distance.is_finite() && distance >= 0.0) {
            return BLOCKED;
        }
        match self {
            Self::Reciprocal => 1.0 / (1.0 + distance),
            Self::Linear { scale } => (1.0 - distance / scale).max(0.0),
        }
    }

    /// [`TargetEncoding::encode`] on a tensor of distances the network computed, inside the
    /// graph (gradients flow): the reciprocal encoding of a negative distance is that of 0;
    /// the linear one continues its line on both sides. Blocked cells are the caller's (they
    /// carry no distance).
    ///
    /// # Errors
    /// Candle's errors.
    pub fn encode_tensor(self, distance: &candle_core::Tensor) -> Result<candle_core::Tensor> {
        Ok(match self {
            Self::Reciprocal => (distance.relu()? + 1.0)?.recip()?,
            Self::Linear { scale } => distance.affine(-1.0 / scale as f64, 1.0)?,
        })
    }

    /// Decodes a raw network output into a distance in cells, monotone (a larger output is
    /// never farther) above -0.5, halfway to the blocked value -1; below it, infinite.
    ///
    /// The reciprocal encoding inverts `1/t - 1` above a small floor (1e-3) and continues
    /// steeply linearly below it, so the decoded field still decreases wherever the raw
    /// output increases and descent on it follows the network. The linear one continues its
    /// line below 0.
    pub fn decode(self, t: f32) -> f32 {
        match self {
            Self::Reciprocal if t >= FLOOR => (1.0 / t - 1.0).max(0.0),
            Self::Reciprocal if t > -0.5 => (1.0 / FLOOR - 1.0) + (FLOOR - t) * 1e4,
            Self::Linear { scale } if t > -0.5 => ((1.0 - t) * scale).max(0.0),
            _ => f32::INFINITY,
        }
    }

    /// `d distance / d output` at output `t` (for gradients in distance units).
    pub fn slope(self, t: f32) -> f32 {
        match self {
            Self::Reciprocal if t >= FLOOR => -1.0 / (t * t),
            Self::Reciprocal => -1e4,
            Self::Linear { scale } => -scale,
        }
    }

    /// Checks the encoding's settings.
    ///
    /// # Errors
    /// [`NetsError::InvalidConfig`] for a linear scale that is not positive and finite.
    pub fn validate(self) -> Result<()> {
        match self {
            Self::Linear { scale } if !(scale.is_finite() && scale > 0.0) => {
                Err(NetsError::InvalidConfig(format!(
                    "encoding: the linear scale must be positive and finite (got {scale})"
                )))
            }
            _ => Ok(()),
        }
    }
}

impl fmt::Display for TargetEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Reciprocal => f.write_str("reciprocal"),
            Self::Linear { scale } => write!(f, "linear:{scale}"),
        }
    }
}

impl FromStr for TargetEncoding {
    type Err = NetsError;

    /// `reciprocal` or `linear:SCALE`.
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            NetsError::InvalidConfig(format!(
                "unknown encoding `{s}` (expected reciprocal or linear:SCALE)"
            ))
        };
        let encoding = match s.split_once(':') {
            None if s == "reciprocal" => Self::Reciprocal,
            Some(("linear", scale)) => Self::Linear {
                scale: scale.trim().parse().map_err(|_| bad())?,
            },
            _ => return Err(bad()),
        };
        encoding.validate()?;
        Ok(encoding)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_encodings_round_trip_and_block_the_unreachable() {
        for encoding in [
            TargetEncoding::Reciprocal,
            TargetEncoding::Linear { scale: 400.0 },
        ] {
            for d in [0.0f32, 0.5, 1.0, 7.25, 300.0] {
                let t = encoding.encode(d);
                assert!((0.0..=1.0).contains(&t), "{encoding} {d} -> {t}");
                let back = encoding.decode(t);
                assert!(
                    (back - d).abs() < 1e-3 * d.max(1.0),
                    "{encoding} {d} -> {back}"
                );
            }
            assert_eq!(encoding.encode(f32::INFINITY), BLOCKED);
            assert_eq!(encoding.encode(-1.0), BLOCKED);
            assert!(encoding.decode(BLOCKED).is_infinite());
            assert_eq!(
                encoding.to_string().parse::<TargetEncoding>().unwrap(),
                encoding
            );
        }
    }

    #[test]
    fn decoding_is_monotone_below_the_floor_and_bad_specs_are_refused() {
        let r = TargetEncoding::Reciprocal;
        let ts = [0.5f32, 1e-2, 1e-3, 5e-4, 0.0, -0.2, -0.49];
        for w in ts.windows(2) {
            assert!(r.decode(w[0]) < r.decode(w[1]), "{} vs {}", w[0], w[1]);
        }
        for bad in [
            "linear",
            "linear:0",
            "linear:-3",
            "linear:x",
            "cubic",
            "linear:inf",
        ] {
            assert!(bad.parse::<TargetEncoding>().is_err(), "{bad}");
        }
    }
}
