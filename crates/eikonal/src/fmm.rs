use crate::march::{check_size, march, Problem};
use crate::sources::check_sources;
use crate::{EikonalError, Result};
use envfield_grid::{Cell2, Cell3, Field2, Field3, FieldModel, Grid2, Grid3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Accuracy order of the fast-marching upwind stencil.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Order {
    /// First-order upwind differences (Sethian 1996). Monotone, never below the straight-line
    /// distance from a point source, never above the 4-connected path length.
    #[default]
    First,
    /// Second-order one-sided differences where the two cells behind a neighbour are accepted
    /// and monotone, first order elsewhere (Sethian 1999, as in scikit-fmm).
    Second,
}

impl Order {
    /// `1` or `2`.
    pub fn as_number(self) -> u8 {
        match self {
            Order::First => 1,
            Order::Second => 2,
        }
    }

    /// The order from `1` or `2`.
    ///
    /// # Errors
    /// [`EikonalError::InvalidConfig`] for any other number.
    pub fn from_number(n: u8) -> Result<Self> {
        match n {
            1 => Ok(Order::First),
            2 => Ok(Order::Second),
            _ => Err(EikonalError::InvalidConfig(format!(
                "order must be 1 or 2, got {n}"
            ))),
        }
    }
}

/// A fast-marching eikonal solver: `|grad T| = 1 / F` with `T = 0` at the sources.
///
/// With unit speed the result is the distance (in units of `spacing`) from the nearest source
/// along paths that avoid obstacles; with a speed map it is the travel time. Obstacles are never
/// entered; cells no front reaches are `f32::INFINITY`.
///
/// Cost: O(n log n) in the number of free cells, one pass, single-threaded per field (solve
/// many fields in parallel with [`FastMarching::solve2_many`]).
///
/// ```
/// use envfield_eikonal::{FastMarching, Order};
/// use envfield_grid::{Cell2, Grid2};
///
/// let grid = Grid2::new(64, 64)?;
/// let fmm = FastMarching { order: Order::Second, ..FastMarching::default() };
/// let field = fmm.solve2(&grid, &[Cell2::new(32, 32)])?;
/// let d = field.get(Cell2::new(32 + 20, 32 + 15)).unwrap();
/// assert!((d - 25.0).abs() < 0.3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FastMarching {
    /// Stencil order.
    pub order: Order,
    /// Grid spacing: the side of one cell in output units (> 0).
    pub spacing: f32,
    /// Cells within this many cells of a source along every axis, in clear line of sight (the
    /// whole box between them free), are initialised with the exact straight-line distance, so a
    /// point source's diagonal neighbour is sqrt 2 rather than the 1.707 a plain update gives.
    /// 0 disables it. Default 2.
    pub source_radius: usize,
}

impl Default for FastMarching {
    fn default() -> Self {
        Self {
            order: Order::First,
            spacing: 1.0,
            source_radius: 2,
        }
    }
}

/// Optional inputs of a 2D fast-marching solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolveOptions2<'a> {
    /// Per-cell speed (finite, >= 0; 0 marks a cell that is never entered). `None` = 1.
    pub speed: Option<&'a Field2>,
    /// Stop as soon as this cell is accepted; cells not yet accepted are left infinite.
    pub stop_at: Option<Cell2>,
    /// After `stop_at` is accepted, go on accepting cells up to this much above its value
    /// (in the solve's units; 0 stops at once): a band beyond it, for a search from that
    /// cell that may need to climb a little.
    pub past_stop: f32,
}

/// Optional inputs of a 3D fast-marching solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolveOptions3<'a> {
    /// Per-cell speed (finite, >= 0; 0 marks a cell that is never entered). `None` = 1.
    pub speed: Option<&'a Field3>,
    /// Stop as soon as this cell is accepted; cells not yet accepted are left infinite.
    pub stop_at: Option<Cell3>,
    /// As [`SolveOptions2::past_stop`].
    pub past_stop: f32,
    /// With `stop_at`: march only the cells on ways from the sources to it at most this much
    /// longer than the shortest (in the solve's units), the rest left infinite, for a search
    /// from `stop_at` that may go round what it meets. A cell is left out when its value plus
    /// its straight line to `stop_at` exceeds the shortest way's length plus this; the
    /// shortest is bounded from above as the march goes, by the first accepted cell found to
    /// see `stop_at` along a straight line of free cells (until one does, every cell is
    /// marched). The cells kept have the values of the whole march, but within a few cells
    /// of the edge, where a neighbour left out is missing from a stencil. Where that bound
    /// proves too short (`stop_at` left out, or within four cells of the edge), the solve
    /// marches again without it. `None` marches every way. Unit speed only.
    pub detour: Option<f32>,
}

pub(crate) fn check_band(past_stop: f32) -> Result<()> {
    if past_stop.is_nan() || past_stop < 0.0 {
        return Err(EikonalError::InvalidConfig(format!(
            "past_stop must be >= 0 (infinite marches on to the end), got {past_stop}"
        )));
    }
    Ok(())
}

/// Runs `march` on `problem`; where it kept to short ways and its bound fell short of the stop
/// (record `stop` of the values: left out, or within four cells of `spacing` of the kept
/// ways' edge, where a stencil may miss a cell left out; in `tests/properties.rs` values that
/// far inside are the whole march's), runs it again over every way.
pub(crate) fn march_kept<const N: usize>(
    problem: Problem<'_, N>,
    stop: Option<usize>,
    spacing: f32,
    march: impl Fn(&Problem<'_, N>) -> (Vec<f32>, f32),
) -> Vec<f32> {
    let (values, within) = march(&problem);
    let short = |s: usize| values[s].is_nan() || values[s] > within - 4.0 * spacing;
    if within.is_finite() && stop.is_some_and(short) {
        return march(&Problem {
            detour: f32::INFINITY,
            ..problem
        })
        .0;
    }
    values
}

/// The detour of [`SolveOptions3::detour`] (infinity without one), checked: >= 0, with a
/// stop cell, at unit speed.
pub(crate) fn check_detour(options: &SolveOptions3<'_>) -> Result<f32> {
    let Some(detour) = options.detour else {
        return Ok(f32::INFINITY);
    };
    let problem = if detour.is_nan() || detour < 0.0 {
        format!("detour must be >= 0 (infinite marches every way), got {detour}")
    } else if options.stop_at.is_none() {
        "detour keeps to the ways to stop_at: it needs stop_at".into()
    } else if options.speed.is_some() {
        "detour is for unit speed: drop the speed map or the detour".into()
    } else {
        return Ok(detour);
    };
    Err(EikonalError::InvalidConfig(problem))
}

fn check_speeds(values: &[f32], cell_name: impl Fn(usize) -> String) -> Result<()> {
    match values.iter().position(|v| !v.is_finite() || *v < 0.0) {
        Some(i) => Err(EikonalError::InvalidSpeed {
            cell: cell_name(i),
            value: values[i],
        }),
        None => Ok(()),
    }
}

impl FastMarching {
    /// A solver of the given order with the default spacing and source initialisation.
    pub fn with_order(order: Order) -> Self {
        Self {
            order,
            ..Self::default()
        }
    }

    /// With a speed map, distances past f32's range (tiny speeds) would come out as NaN:
    /// refuse them rather than return them. (With unit speed [`FastMarching::check_range`]
    /// rules the overflow out before the march, so the common case pays no scan.)
    fn check_finite(&self, values: &[f32]) -> Result<()> {
        if values.iter().any(|v| v.is_nan()) {
            return Err(EikonalError::InvalidConfig(format!(
                "distances overflow f32 with spacing {} on this grid (and its speeds): use a \
                 smaller spacing or larger speeds",
                self.spacing
            )));
        }
        Ok(())
    }

    /// With unit speed no distance exceeds `spacing x cells x 2`: refuse a spacing for which
    /// that bound leaves f32's range (a distance past it would read as unreachable).
    pub(crate) fn check_range(&self, cells: usize) -> Result<()> {
        if self.spacing as f64 * cells as f64 * 2.0 > f32::MAX as f64 {
            return Err(EikonalError::InvalidConfig(format!(
                "spacing {} is too large for a grid of {cells} cells: distances would overflow \
                 f32",
                self.spacing
            )));
        }
        Ok(())
    }

    pub(crate) fn validate(&self) -> Result<()> {
        if !(self.spacing.is_finite() && self.spacing > 0.0) {
            return Err(EikonalError::InvalidConfig(format!(
                "spacing must be finite and positive, got {}",
                self.spacing
            )));
        }
        if self.source_radius > 8 {
            return Err(EikonalError::InvalidConfig(format!(
                "source_radius must be at most 8, got {}",
                self.source_radius
            )));
        }
        Ok(())
    }

    /// The distance field of `grid` from the nearest of `sources`.
    ///
    /// # Errors
    /// [`EikonalError::NoSources`], [`EikonalError::SourceOutside`],
    /// [`EikonalError::SourceOnObstacle`], [`EikonalError::NoFreeCell`],
    /// [`EikonalError::InvalidConfig`], and [`EikonalError::GridTooLarge`] past about 4.29
    /// billion cells (65532² or 1620³).
    pub fn solve2(&self, grid: &Grid2, sources: &[Cell2]) -> Result<Field2> {
        self.solve2_with(grid, sources, SolveOptions2::default())
    }

    /// [`FastMarching::solve2`] with a speed map and/or an early stop.
    ///
    /// # Errors
    /// As [`FastMarching::solve2`], plus [`EikonalError::SpeedShape`] and
    /// [`EikonalError::InvalidSpeed`]; a source on a zero-speed cell is
    /// [`EikonalError::SourceOnObstacle`].
    pub fn solve2_with(
        &self,
        grid: &Grid2,
        sources: &[Cell2],
        options: SolveOptions2<'_>,
    ) -> Result<Field2> {
        self.validate()?;
        if options.speed.is_none() {
            self.check_range(grid.len())?;
        }
        let shape = format!("{}x{}", grid.rows(), grid.cols());
        check_size([grid.rows(), grid.cols()], &shape)?;
        if !grid.obstacles().contains(&false) {
            return Err(EikonalError::NoFreeCell);
        }
        if let Some(speed) = options.speed {
            if (speed.rows(), speed.cols()) != (grid.rows(), grid.cols()) {
                return Err(EikonalError::SpeedShape {
                    speed: format!("{}x{}", speed.rows(), speed.cols()),
                    grid: shape,
                });
            }
            check_speeds(speed.values(), |i| grid.cell(i).to_string())?;
        }
        let src = check_sources(
            sources,
            |s| grid.index(s),
            |i| grid.obstacles()[i],
            options.speed.map(Field2::values),
            &shape,
            |s, _| [s.row, s.col],
        )?;
        if let Some(stop) = options.stop_at {
            grid.check(stop)?;
        }
        check_band(options.past_stop)?;
        let (values, _) = march(&Problem {
            dims: [grid.rows(), grid.cols()],
            obstacles: grid.obstacles(),
            speed: options.speed.map(Field2::values),
            sources: &src,
            stop_at: options.stop_at.map(|c| [c.row, c.col]),
            past_stop: options.past_stop,
            detour: f32::INFINITY,
            spacing: self.spacing as f64,
            second_order: self.order == Order::Second,
            source_radius: self.source_radius,
        });
        if options.speed.is_some() {
            self.check_finite(&values)?;
        }
        Ok(Field2::new(grid.rows(), grid.cols(), values)?)
    }

    /// The distance field of a 3D `grid` from the nearest of `sources` (6-neighbour stencil).
    ///
    /// # Errors
    /// As [`FastMarching::solve2`].
    pub fn solve3(&self, grid: &Grid3, sources: &[Cell3]) -> Result<Field3> {
        self.solve3_with(grid, sources, SolveOptions3::default())
    }

    /// [`FastMarching::solve3`] with a speed map and/or an early stop.
    ///
    /// # Errors
    /// As [`FastMarching::solve2_with`].
    pub fn solve3_with(
        &self,
        grid: &Grid3,
        sources: &[Cell3],
        options: SolveOptions3<'_>,
    ) -> Result<Field3> {
        self.validate()?;
        if options.speed.is_none() {
            self.check_range(grid.len())?;
        }
        let [nx, ny, nz] = grid.shape();
        let shape = format!("{nx}x{ny}x{nz}");
        check_size(grid.shape(), &shape)?;
        if !grid.obstacles().contains(&false) {
            return Err(EikonalError::NoFreeCell);
        }
        if let Some(speed) = options.speed {
            if speed.shape() != grid.shape() {
                let [a, b, c] = speed.shape();
                return Err(EikonalError::SpeedShape {
                    speed: format!("{a}x{b}x{c}"),
                    grid: shape,
                });
            }
            check_speeds(speed.values(), |i| grid.cell(i).to_string())?;
        }
        let src = check_sources(
            sources,
            |s| grid.index(s),
            |i| grid.obstacles()[i],
            options.speed.map(Field3::values),
            &shape,
            |s, _| [s.x, s.y, s.z],
        )?;
        if let Some(stop) = options.stop_at {
            grid.check(stop)?;
        }
        check_band(options.past_stop)?;
        let problem = Problem {
            dims: grid.shape(),
            obstacles: grid.obstacles(),
            speed: options.speed.map(Field3::values),
            sources: &src,
            stop_at: options.stop_at.map(|c| [c.x, c.y, c.z]),
            past_stop: options.past_stop,
            detour: check_detour(&options)?,
            spacing: self.spacing as f64,
            second_order: self.order == Order::Second,
            source_radius: self.source_radius,
        };
        let stop = options.stop_at.and_then(|c| grid.index(c));
        let values = march_kept(problem, stop, self.spacing, march);
        if options.speed.is_some() {
            self.check_finite(&values)?;
        }
        Ok(Field3::new(grid.shape(), values)?)
    }

    /// One field per goal on the same grid, solved in parallel (rayon).
    ///
    /// # Errors
    /// The first error of any goal, as [`FastMarching::solve2`].
    pub fn solve2_many(&self, grid: &Grid2, goals: &[Cell2]) -> Result<Vec<Field2>> {
        goals.par_iter().map(|&g| self.solve2(grid, &[g])).collect()
    }

    /// One field per `(grid, goal)` pair, solved in parallel (rayon).
    ///
    /// # Errors
    /// The first error of any pair, as [`FastMarching::solve2`].
    pub fn solve2_batch(&self, problems: &[(&Grid2, Cell2)]) -> Result<Vec<Field2>> {
        problems
            .par_iter()
            .map(|&(g, goal)| self.solve2(g, &[goal]))
            .collect()
    }

    /// One field per goal on the same 3D grid, solved in parallel (rayon).
    ///
    /// # Errors
    /// The first error of any goal, as [`FastMarching::solve3`].
    pub fn solve3_many(&self, grid: &Grid3, goals: &[Cell3]) -> Result<Vec<Field3>> {
        goals.par_iter().map(|&g| self.solve3(grid, &[g])).collect()
    }
}

/// Fast marching as the exact oracle for planners: the field of `grid` for `goal`.
impl FieldModel for FastMarching {
    fn name(&self) -> &str {
        match self.order {
            Order::First => "fmm",
            Order::Second => "fmm2",
        }
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
        Ok(self.solve2(grid, &[goal])?)
    }

    fn predict_many(&self, problems: &[(&Grid2, Cell2)]) -> envfield_grid::Result<Vec<Field2>> {
        Ok(self.solve2_batch(problems)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bfs2;
    use envfield_grid::{Neighbourhood2, SplitMix64};

    /// Small enough for Miri (`miri.sh`), which checks the marcher's and the heap's unchecked
    /// indexing on every cell: random obstacles, a speed map, two sources, both orders, 2D and
    /// 3D. Sources are 0, the reachable cells (by the 4-connected graph) are finite, the others
    /// infinite, and no value is below the straight-line distance.
    #[test]
    fn small_grids_in_both_orders_and_dimensions() {
        let mut rng = SplitMix64::new(11);
        for case in 0..4 {
            let (rows, cols) = (6 + case, 9 - case);
            let mut grid = Grid2::new(rows, cols).unwrap();
            for i in 0..rows * cols {
                if rng.next_f64() < 0.25 {
                    grid.set_obstacle(grid.cell(i), true).unwrap();
                }
            }
            let sources = [Cell2::new(0, 0), Cell2::new(rows - 1, cols - 1)];
            for &s in &sources {
                grid.set_obstacle(s, false).unwrap();
            }
            let reach = bfs2(&grid, &sources, Neighbourhood2::Four).unwrap();
            let speed = Field2::new(
                rows,
                cols,
                (0..rows * cols).map(|_| 0.5 + rng.next_f32()).collect(),
            )
            .unwrap();
            for order in [Order::First, Order::Second] {
                let fmm = FastMarching::with_order(order);
                let options = SolveOptions2 {
                    speed: Some(&speed),
                    ..SolveOptions2::default()
                };
                for field in [
                    fmm.solve2(&grid, &sources).unwrap(),
                    fmm.solve2_with(&grid, &sources, options).unwrap(),
                ] {
                    for i in 0..rows * cols {
                        let c = grid.cell(i);
                        let (v, r) = (field.get(c).unwrap(), reach.get(c).unwrap());
                        assert_eq!(v.is_finite(), r.is_finite(), "{c} under {order:?}");
                        let straight = sources
                            .iter()
                            .map(|s| {
                                let (dr, dc) = (s.row.abs_diff(c.row), s.col.abs_diff(c.col));
                                ((dr * dr + dc * dc) as f32).sqrt()
                            })
                            .fold(f32::INFINITY, f32::min);
                        // Unit speed here is at most 1.5: the straight line at that speed.
                        assert!(v >= straight / 1.5 - 1e-4, "{c}: {v} < {straight}");
                    }
                    for &s in &sources {
                        assert_eq!(field.get(s), Some(0.0));
                    }
                }
            }
            let mut grid3 = Grid3::new(4, 5, 3).unwrap();
            grid3.set_obstacle(Cell3::new(1, 1, 1), true).unwrap();
            let field = FastMarching::with_order(Order::Second)
                .solve3(&grid3, &[Cell3::new(0, 0, 0)])
                .unwrap();
            assert!(field.values().iter().filter(|v| v.is_finite()).count() == 59);
        }
    }
}
