//! Seeded synthetic obstacle layouts (random squares and cubes), for tests and benchmarks.

use crate::{Grid2, Grid3, Result, SplitMix64};

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
