//! Seeded synthetic obstacle layouts for tests and benchmarks.

use crate::{Grid2, Grid3, Result};

/// SplitMix64: a tiny seeded generator, enough for reproducible layouts without a dependency.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`, from the top 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[0, 1)`, from the top 24 bits (every value exact in f32).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 11) as u128 * n as u128) >> 53) as usize
    }
}

/// A `rows x cols` grid with random axis-aligned squares (side 1..=`max_side`) dropped until at
/// least `fraction` of the cells are obstacles; the cells in `keep_free` are cleared at the end.
///
/// # Errors
/// [`crate::GridError::InvalidShape`] for a zero dimension; [`crate::GridError::Invalid`] for a
/// fraction outside `[0, 0.95]` or `max_side == 0`.
pub fn scatter_squares2(
    rows: usize,
    cols: usize,
    fraction: f64,
    max_side: usize,
    seed: u64,
    keep_free: &[crate::Cell2],
) -> Result<Grid2> {
    Grid2::new(rows, cols)?;
    let mask = scatter_boxes([rows, cols], fraction, max_side, seed)?;
    let mut g = Grid2::from_obstacles(rows, cols, mask)?;
    for &c in keep_free {
        g.set_obstacle(c, false)?;
    }
    Ok(g)
}

/// The 3D counterpart of [`scatter_squares2`]: random cubes (side 1..=`max_side`).
///
/// # Errors
/// As [`scatter_squares2`].
pub fn scatter_cubes3(
    shape: [usize; 3],
    fraction: f64,
    max_side: usize,
    seed: u64,
    keep_free: &[crate::Cell3],
) -> Result<Grid3> {
    Grid3::new(shape[0], shape[1], shape[2])?;
    let mask = scatter_boxes(shape, fraction, max_side, seed)?;
    let mut g = Grid3::from_obstacles(shape, mask)?;
    for &c in keep_free {
        g.set_obstacle(c, false)?;
    }
    Ok(g)
}

/// A C-order mask of `shape` with random axis-aligned boxes of equal sides (1..=`max_side`,
/// clipped at the border) set until at least `fraction` of the cells are set. Each box draws
/// its side, then its corner one axis at a time.
fn scatter_boxes<const N: usize>(
    shape: [usize; N],
    fraction: f64,
    max_side: usize,
    seed: u64,
) -> Result<Vec<bool>> {
    check_args(fraction, max_side)?;
    let len: usize = shape.iter().product();
    let mut rng = SplitMix64::new(seed);
    let target = (fraction * len as f64).ceil() as usize;
    let mut mask = vec![false; len];
    let mut filled = 0;
    while filled < target {
        let side = 1 + rng.below(max_side);
        let corner = shape.map(|d| rng.below(d));
        let extent: [usize; N] = std::array::from_fn(|k| side.min(shape[k] - corner[k]));
        // Visit the box with an odometer over its offsets.
        let mut off = [0usize; N];
        'boxes: loop {
            let i = (0..N).fold(0, |acc, k| acc * shape[k] + corner[k] + off[k]);
            filled += usize::from(!mask[i]);
            mask[i] = true;
            for k in (0..N).rev() {
                off[k] += 1;
                if off[k] < extent[k] {
                    continue 'boxes;
                }
                off[k] = 0;
            }
            break;
        }
    }
    Ok(mask)
}

fn check_args(fraction: f64, max_side: usize) -> Result<()> {
    if !(0.0..=0.95).contains(&fraction) || max_side == 0 {
        return Err(crate::GridError::Invalid(format!(
            "obstacle fraction must be in [0, 0.95] and max_side >= 1 (got {fraction}, {max_side})"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cell2;

    #[test]
    fn reaches_the_fraction_and_is_reproducible() {
        let c = Cell2::new(50, 50);
        let a = scatter_squares2(100, 100, 0.2, 4, 7, &[c]).unwrap();
        let b = scatter_squares2(100, 100, 0.2, 4, 7, &[c]).unwrap();
        assert_eq!(a, b);
        let frac = 1.0 - a.free_count() as f64 / a.len() as f64;
        assert!((0.199..0.21).contains(&frac), "{frac}");
        assert!(a.is_free(c));
        assert!(scatter_squares2(10, 10, 1.5, 2, 0, &[]).is_err());
    }
}
