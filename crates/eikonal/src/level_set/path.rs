//! The way back down a marched field: from any cell to the zero contour.

use super::MAX_DIMENSIONS;
use crate::{EikonalError, Result};

fn invalid(reason: String) -> EikonalError {
    EikonalError::LevelSet(reason)
}

/// The path from `start` down `values` (a distance or travel time marched from a zero
/// contour; signed distances are taken by magnitude) to the contour, as points in index
/// coordinates (fractional, one per step, `start` first).
///
/// Each step follows the field's gradient, read from the cells around the point
/// (multilinear), half a cell long in the axis of smallest spacing, and is kept only where the
/// field is lower there; where the cells around are not all `reached` (beside a mask) or the
/// step does not go down, the path moves to the lowest neighbour cell (any of the `3^n - 1`
/// around). It ends within half a step of the contour, or at a cell with no lower neighbour.
/// Values are strictly decreasing along the path, so it always ends.
///
/// # Errors
/// [`EikonalError::LevelSet`] for lengths that do not match `shape`, a spacing that is not
/// positive, or a start off the grid or on a cell the march did not reach.
pub fn descend(
    shape: &[usize],
    values: &[f64],
    reached: &[bool],
    dx: &[f64],
    start: &[f64],
) -> Result<Vec<Vec<f64>>> {
    let nd = shape.len();
    if nd == 0 || nd > MAX_DIMENSIONS {
        return Err(invalid(format!(
            "a field has 1 to {MAX_DIMENSIONS} axes, not {nd}"
        )));
    }
    let cells: usize = shape.iter().product();
    for (what, len) in [("values", values.len()), ("reached", reached.len())] {
        if len != cells {
            return Err(invalid(format!(
                "{what} has {len} entries but the {shape:?} grid has {cells} cells"
            )));
        }
    }
    let dx: Vec<f64> = if dx.is_empty() {
        vec![1.0; nd]
    } else {
        dx.to_vec()
    };
    if dx.len() != nd || dx.iter().any(|&d| !(d > 0.0 && d.is_finite())) {
        return Err(invalid(format!(
            "the spacing {dx:?} must be one positive number per axis of the {shape:?} grid"
        )));
    }
    if start.len() != nd
        || start
            .iter()
            .zip(shape)
            .any(|(&s, &n)| !(s >= -0.5 && s <= n as f64 - 0.5))
    {
        return Err(invalid(format!(
            "the start {start:?} is not a point of the {shape:?} grid"
        )));
    }
    let field = Field {
        shape,
        values,
        reached,
        dx: &dx,
    };
    let first = field.nearest(start);
    if !reached[first] {
        return Err(invalid(format!(
            "the start {start:?} lies on a cell the march did not reach (masked or cut off)"
        )));
    }
    let h = 0.5 * dx.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut x = start.to_vec();
    let mut value = field
        .interpolate(&x)
        .map(|(v, _)| v)
        .unwrap_or(values[first].abs());
    let mut path = vec![x.clone()];
    // Every step lowers the value; a cell step lowers it to another cell's value, so the
    // steps are bounded by a few per cell.
    for _ in 0..cells.saturating_mul(4).max(16) {
        if value <= 0.5 * h {
            break;
        }
        let mut moved = false;
        if let Some((_, grad)) = field.interpolate(&x) {
            let norm = grad.iter().map(|g| g * g).sum::<f64>().sqrt();
            if norm > 0.0 {
                let next: Vec<f64> = (0..nd).map(|a| x[a] - h * grad[a] / norm / dx[a]).collect();
                if let Some((v, _)) = field.interpolate(&next) {
                    if v < value {
                        x = next;
                        value = v;
                        moved = true;
                    }
                }
            }
        }
        if !moved {
            let here = field.nearest(&x);
            match field.lowest_neighbour(here) {
                Some(n) if values[n].abs() < value => {
                    x = field.coords(n).iter().map(|&c| c as f64).collect();
                    value = values[n].abs();
                }
                _ => break,
            }
        }
        path.push(x.clone());
    }
    Ok(path)
}

struct Field<'a> {
    shape: &'a [usize],
    values: &'a [f64],
    reached: &'a [bool],
    dx: &'a [f64],
}

impl Field<'_> {
    fn index(&self, c: &[usize]) -> usize {
        c.iter().zip(self.shape).fold(0, |i, (&c, &n)| i * n + c)
    }

    fn coords(&self, mut i: usize) -> Vec<usize> {
        let mut c = vec![0; self.shape.len()];
        for a in (0..self.shape.len()).rev() {
            c[a] = i % self.shape[a];
            i /= self.shape[a];
        }
        c
    }

    fn nearest(&self, x: &[f64]) -> usize {
        let c: Vec<usize> = x
            .iter()
            .zip(self.shape)
            .map(|(&v, &n)| (v.round().max(0.0) as usize).min(n - 1))
            .collect();
        self.index(&c)
    }

    /// The multilinear value of the field's magnitude at `x` and its gradient (per metre),
    /// where the cells around `x` are all on the grid and reached.
    fn interpolate(&self, x: &[f64]) -> Option<(f64, Vec<f64>)> {
        let nd = self.shape.len();
        let mut base = vec![0usize; nd];
        let mut t = vec![0.0; nd];
        for a in 0..nd {
            let n = self.shape[a];
            if n == 1 {
                if x[a].abs() > 1e-9 {
                    return None;
                }
                continue;
            }
            if !(x[a] >= 0.0 && x[a] <= (n - 1) as f64) {
                return None;
            }
            let b = (x[a].floor() as usize).min(n - 2);
            base[a] = b;
            t[a] = x[a] - b as f64;
        }
        let mut value = 0.0;
        let mut grad = vec![0.0; nd];
        let mut c = vec![0usize; nd];
        for corner in 0..1usize << nd {
            let mut w = 1.0;
            for a in 0..nd {
                let up = corner >> a & 1 == 1;
                if up && self.shape[a] == 1 {
                    w = 0.0;
                }
                c[a] = base[a] + up as usize;
                w *= if up { t[a] } else { 1.0 - t[a] };
            }
            if self
                .shape
                .iter()
                .enumerate()
                .any(|(a, &n)| n == 1 && corner >> a & 1 == 1)
            {
                continue;
            }
            let i = self.index(&c);
            if !self.reached[i] {
                return None;
            }
            let v = self.values[i].abs();
            value += w * v;
            for g in 0..nd {
                if self.shape[g] == 1 {
                    continue;
                }
                let mut wg = 1.0 / self.dx[g];
                for a in 0..nd {
                    let up = corner >> a & 1 == 1;
                    if a == g {
                        wg *= if up { 1.0 } else { -1.0 };
                    } else {
                        wg *= if up { t[a] } else { 1.0 - t[a] };
                    }
                }
                grad[g] += wg * v;
            }
        }
        Some((value, grad))
    }

    /// The reached cell among the `3^n - 1` around `i` with the lowest magnitude.
    fn lowest_neighbour(&self, i: usize) -> Option<usize> {
        let nd = self.shape.len();
        let c = self.coords(i);
        let mut best: Option<(f64, usize)> = None;
        let mut offset = vec![-1i64; nd];
        let mut n = vec![0usize; nd];
        'outer: loop {
            let mut ok = offset.iter().any(|&o| o != 0);
            for a in 0..nd {
                let v = c[a] as i64 + offset[a];
                if v < 0 || v >= self.shape[a] as i64 {
                    ok = false;
                    break;
                }
                n[a] = v as usize;
            }
            if ok {
                let k = self.index(&n);
                if self.reached[k] {
                    let v = self.values[k].abs();
                    if best.is_none_or(|(b, _)| v < b) {
                        best = Some((v, k));
                    }
                }
            }
            for a in 0..nd {
                if offset[a] < 1 {
                    offset[a] += 1;
                    continue 'outer;
                }
                offset[a] = -1;
            }
            break;
        }
        best.map(|(_, k)| k)
    }
}
