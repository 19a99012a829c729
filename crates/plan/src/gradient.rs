use crate::{PlanError, Result};
use envfield_grid::{ContinuousField2, Point2};
use serde::{Deserialize, Serialize};

/// Settings of [`gradient_descent`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct GradientDescentConfig {
    /// Length of each step, in cells (> 0).
    pub step: f32,
    /// Most steps.
    pub max_steps: usize,
    /// Success radius around the goal, in cells (> 0).
    pub tolerance: f32,
}

impl Default for GradientDescentConfig {
    fn default() -> Self {
        Self {
            step: 0.25,
            max_steps: 10_000,
            tolerance: 0.5,
        }
    }
}

/// A continuous path and whether it reached the goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContinuousPath {
    /// The points visited, start first.
    pub points: Vec<Point2>,
    /// Whether the last point is within the tolerance of the goal.
    pub success: bool,
}

impl ContinuousPath {
    /// Total length, in cells.
    pub fn length(&self) -> f32 {
        self.points.windows(2).map(|w| w[0].distance(w[1])).sum()
    }
}

/// Gradient descent on a continuous, differentiable field (the paper's Fig. 3c): from `start`,
/// fixed-length steps against the gradient until within `tolerance` of `goal`, `max_steps`,
/// or a point where the field has no usable gradient (infinite, zero, or outside).
///
/// # Errors
/// [`PlanError::Invalid`] for bad settings or a start that is not finite; the field's own
/// errors for a start outside its domain.
pub fn gradient_descent(
    field: &dyn ContinuousField2,
    start: Point2,
    goal: Point2,
    cfg: &GradientDescentConfig,
) -> Result<ContinuousPath> {
    if !(cfg.step > 0.0 && cfg.step.is_finite() && cfg.tolerance > 0.0 && cfg.tolerance.is_finite())
    {
        return Err(PlanError::Invalid(format!(
            "gradient descent needs a positive step and tolerance (got {}, {})",
            cfg.step, cfg.tolerance
        )));
    }
    field.value(start)?;
    let mut points = vec![start];
    let mut p = start;
    for _ in 0..cfg.max_steps {
        if p.distance(goal) <= cfg.tolerance {
            break;
        }
        let Ok(Some((gr, gc))) = field.gradient(p) else {
            break;
        };
        let norm = gr.hypot(gc);
        if !(norm.is_finite() && norm > 1e-12) {
            break;
        }
        let next = Point2::new(p.row - cfg.step * gr / norm, p.col - cfg.step * gc / norm);
        match field.value(next) {
            Ok(v) if v.is_finite() => {
                p = next;
                points.push(p);
            }
            _ => break,
        }
    }
    let success = p.distance(goal) <= cfg.tolerance;
    Ok(ContinuousPath { points, success })
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_eikonal::{FastMarching, Order};
    use envfield_grid::{Cell2, Grid2};

    #[test]
    fn descends_a_distance_field_along_the_straight_line() {
        let grid = Grid2::new(40, 40).unwrap();
        let goal = Cell2::new(20, 22);
        let field = FastMarching::with_order(Order::Second)
            .solve2(&grid, &[goal])
            .unwrap();
        let start = Point2::new(3.0, 4.5);
        let path = gradient_descent(
            &field,
            start,
            goal.center(),
            &GradientDescentConfig::default(),
        )
        .unwrap();
        assert!(path.success);
        let straight = start.distance(goal.center());
        assert!(
            path.length() < straight * 1.03 + 0.5,
            "{} vs {straight}",
            path.length()
        );
    }

    #[test]
    fn walls_stop_it_and_bad_settings_are_errors() {
        let mut grid = Grid2::new(20, 20).unwrap();
        for r in 0..20 {
            grid.set_obstacle(Cell2::new(r, 10), true).unwrap();
        }
        let field = FastMarching::default()
            .solve2(&grid, &[Cell2::new(5, 15)])
            .unwrap();
        // The left half is unreachable: no gradient, no step, no success.
        let path = gradient_descent(
            &field,
            Point2::new(5.0, 3.0),
            Point2::new(5.0, 15.0),
            &GradientDescentConfig::default(),
        )
        .unwrap();
        assert!(!path.success && path.points.len() == 1);
        let bad = GradientDescentConfig {
            step: 0.0,
            ..Default::default()
        };
        assert!(
            gradient_descent(&field, Point2::new(5.0, 12.0), Point2::new(5.0, 15.0), &bad).is_err()
        );
        assert!(gradient_descent(
            &field,
            Point2::new(f32::NAN, 12.0),
            Point2::new(5.0, 15.0),
            &GradientDescentConfig::default()
        )
        .is_err());
    }
}
