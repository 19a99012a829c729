//! [`FreeCells3`]: a 3D grid's free cells alone, numbered and linked to their neighbours once,
//! so that fast marching over a sparse region (a few thousand free voxels in a room's box of
//! tens of thousands) costs its free cells, not its box.

use crate::march::{check_size, march_free, Problem};
use crate::sources::check_sources;
use crate::{EikonalError, FastMarching, Order, Result, SolveOptions3};
use envfield_grid::{Cell3, Grid3};

/// The free cells of a [`Grid3`], numbered in the grid's C order, each with its six
/// neighbours: made once per grid, then marched from any goal by
/// [`FastMarching::solve3_free`], whose cost grows with the cells it accepts and not with the
/// grid's box.
///
/// ```
/// use envfield_eikonal::{FastMarching, FreeCells3};
/// use envfield_grid::{Cell3, Grid3};
///
/// let mut grid = Grid3::new(20, 20, 4)?;
/// for x in 0..20 {
///     for y in 0..20 {
///         for z in 1..4 {
///             grid.set_obstacle(Cell3::new(x, y, z), true)?;
///         }
///     }
/// }
/// let cells = FreeCells3::new(&grid)?;
/// assert_eq!(cells.len(), 400);
/// let values = FastMarching::default().solve3_free(&cells, &[Cell3::new(0, 0, 0)], Default::default())?;
/// let far = cells.number(Cell3::new(19, 0, 0)).unwrap();
/// assert!((values[far] - 19.0).abs() < 1e-4);
/// // The same values as the dense solve, bit for bit.
/// let dense = FastMarching::default().solve3(&grid, &[Cell3::new(0, 0, 0)])?;
/// assert_eq!(dense.get(Cell3::new(19, 0, 0)), Some(values[far]));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct FreeCells3 {
    shape: [usize; 3],
    /// Each free cell's index in the grid, ascending.
    cells: Vec<u32>,
    /// Each grid cell's number among the free cells, [`u32::MAX`] for an obstacle.
    numbers: Vec<u32>,
    /// Each free cell's neighbours below and above along x, y and z, as numbers; the last
    /// entry is an obstacle that is its own neighbour everywhere (number `len()`).
    links: Vec<[u32; 6]>,
}

impl FreeCells3 {
    /// The free cells of `grid`.
    ///
    /// # Errors
    /// [`EikonalError::NoFreeCell`] for a grid without one; [`EikonalError::GridTooLarge`]
    /// for a grid fast marching cannot index.
    pub fn new(grid: &Grid3) -> Result<Self> {
        let shape = grid.shape();
        let [nx, ny, nz] = shape;
        check_size(shape, &format!("{nx}x{ny}x{nz}"))?;
        let obstacles = grid.obstacles();
        let cells: Vec<u32> = (0..obstacles.len())
            .filter(|&i| !obstacles[i])
            .map(|i| i as u32)
            .collect();
        if cells.is_empty() {
            return Err(EikonalError::NoFreeCell);
        }
        let none = cells.len() as u32;
        let mut numbers = vec![u32::MAX; obstacles.len()];
        for (k, &i) in cells.iter().enumerate() {
            numbers[i as usize] = k as u32;
        }
        let strides = [ny * nz, nz, 1];
        let mut links = Vec::with_capacity(cells.len() + 1);
        for &i in &cells {
            let i = i as usize;
            let at = [i / (ny * nz), (i / nz) % ny, i % nz];
            let mut next = [none; 6];
            for axis in 0..3 {
                if at[axis] > 0 {
                    next[2 * axis] = numbers[i - strides[axis]].min(none);
                }
                if at[axis] + 1 < shape[axis] {
                    next[2 * axis + 1] = numbers[i + strides[axis]].min(none);
                }
            }
            links.push(next);
        }
        links.push([none; 6]);
        Ok(Self {
            shape,
            cells,
            numbers,
            links,
        })
    }

    /// How many free cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether there is none (never, for a value [`FreeCells3::new`] made).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The grid's shape.
    pub fn shape(&self) -> [usize; 3] {
        self.shape
    }

    /// The number of `cell` among the free cells, or `None` for an obstacle or a cell outside
    /// the grid.
    pub fn number(&self, cell: Cell3) -> Option<usize> {
        self.number_at(self.grid_index(cell)?)
    }

    /// The C-order index of `cell` in the grid, or `None` outside it.
    fn grid_index(&self, cell: Cell3) -> Option<usize> {
        let [nx, ny, nz] = self.shape;
        (cell.x < nx && cell.y < ny && cell.z < nz).then(|| (cell.x * ny + cell.y) * nz + cell.z)
    }

    /// The number of the cell at C-order `index` in the grid, or `None` for an obstacle or an
    /// index past the grid.
    #[inline]
    pub fn number_at(&self, index: usize) -> Option<usize> {
        match self.numbers.get(index) {
            Some(&k) if k != u32::MAX => Some(k as usize),
            _ => None,
        }
    }

    /// The grid cell of free cell `number` (panics past [`FreeCells3::len`]).
    pub fn cell(&self, number: usize) -> Cell3 {
        let [_, ny, nz] = self.shape;
        let i = self.index(number);
        Cell3::new(i / (ny * nz), (i / nz) % ny, i % nz)
    }

    /// The grid's C-order index of free cell `number` (panics past [`FreeCells3::len`]).
    pub fn index(&self, number: usize) -> usize {
        self.cells[number] as usize
    }

    /// The free cells' C-order indices in the grid, ascending (cell `k`'s is entry `k`).
    pub fn indices(&self) -> &[u32] {
        &self.cells
    }

    /// Bytes it keeps.
    pub fn bytes(&self) -> usize {
        4 * (self.cells.len() + self.numbers.len()) + 24 * self.links.len()
    }
}

impl FastMarching {
    /// [`FastMarching::solve3_with`] over the free cells alone: the values of every free
    /// cell of `cells`, in its numbering (infinity where not reached), bit for bit those of
    /// the dense solve. Made for many solves over one sparse grid: the dense solve touches
    /// every cell of the box twice per solve, this one only the cells it reaches.
    ///
    /// # Errors
    /// As [`FastMarching::solve3_with`]; [`EikonalError::InvalidConfig`] for a speed map (the
    /// free cells' march is for unit speed: use [`FastMarching::solve3_with`]).
    pub fn solve3_free(
        &self,
        cells: &FreeCells3,
        sources: &[Cell3],
        options: SolveOptions3<'_>,
    ) -> Result<Vec<f32>> {
        self.validate()?;
        if options.speed.is_some() {
            return Err(EikonalError::InvalidConfig(
                "solve3_free marches at unit speed; a speed map needs solve3_with".into(),
            ));
        }
        let [nx, ny, nz] = cells.shape;
        self.check_range(nx * ny * nz)?;
        let shape = format!("{nx}x{ny}x{nz}");
        let src = check_sources(
            sources,
            |s| cells.grid_index(s),
            |i| cells.number_at(i).is_none(),
            None,
            &shape,
            |s, _| [s.x, s.y, s.z],
        )?;
        if let Some(stop) = options.stop_at {
            if cells.grid_index(stop).is_none() {
                return Err(envfield_grid::GridError::OutOfBounds {
                    cell: stop.to_string(),
                    shape,
                }
                .into());
            }
        }
        crate::fmm::check_band(options.past_stop)?;
        let none = cells.len();
        let record = |c: [usize; 3]| cells.number(Cell3::new(c[0], c[1], c[2])).unwrap_or(none);
        let problem = Problem {
            dims: cells.shape,
            obstacles: &[],
            speed: None,
            sources: &src,
            stop_at: options.stop_at.map(|c| [c.x, c.y, c.z]),
            past_stop: options.past_stop,
            detour: crate::fmm::check_detour(&options)?,
            spacing: self.spacing as f64,
            second_order: self.order == Order::Second,
            source_radius: self.source_radius,
        };
        let cell_of = |k: usize| {
            let c = cells.cell(k);
            [c.x, c.y, c.z]
        };
        let stop = options.stop_at.and_then(|c| cells.number(c));
        Ok(crate::fmm::march_kept(problem, stop, self.spacing, |p| {
            march_free(p, &cells.links, record, cell_of)
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_grid::SplitMix64;

    /// Random sparse and dense grids, both orders, a stop with and without a band, sources
    /// on the faces: the free cells' march gives the dense march's values bit for bit.
    #[test]
    fn the_free_cells_march_is_the_dense_march_bit_for_bit() {
        let mut rng = SplitMix64::new(5);
        for case in 0..6 {
            let shape = [7 + case, 9 - case, 3 + case % 3];
            let mut grid = Grid3::new(shape[0], shape[1], shape[2]).unwrap();
            let density = [0.2, 0.5, 0.7][case % 3];
            for i in 0..grid.len() {
                if rng.next_f64() < density {
                    grid.set_obstacle(grid.cell(i), true).unwrap();
                }
            }
            let source = Cell3::new(0, shape[1] - 1, case % shape[2]);
            grid.set_obstacle(source, false).unwrap();
            let cells = FreeCells3::new(&grid).unwrap();
            let stop = (0..grid.len())
                .rev()
                .map(|i| grid.cell(i))
                .find(|&c| grid.is_free(c))
                .unwrap();
            for order in [Order::First, Order::Second] {
                let fmm = FastMarching {
                    spacing: 0.1,
                    ..FastMarching::with_order(order)
                };
                for options in [
                    SolveOptions3::default(),
                    SolveOptions3 {
                        stop_at: Some(stop),
                        ..Default::default()
                    },
                    SolveOptions3 {
                        stop_at: Some(stop),
                        past_stop: 0.25,
                        ..Default::default()
                    },
                    SolveOptions3 {
                        stop_at: Some(stop),
                        past_stop: 0.25,
                        detour: Some(0.2),
                        ..Default::default()
                    },
                    SolveOptions3 {
                        stop_at: Some(stop),
                        detour: Some(0.0),
                        ..Default::default()
                    },
                ] {
                    let dense = fmm.solve3_with(&grid, &[source], options).unwrap();
                    let free = fmm.solve3_free(&cells, &[source], options).unwrap();
                    assert_eq!(free.len(), cells.len());
                    for i in 0..grid.len() {
                        let c = grid.cell(i);
                        let d = dense.get(c).unwrap();
                        match cells.number(c) {
                            Some(k) => {
                                assert_eq!((cells.index(k), cells.cell(k)), (i, c));
                                assert_eq!(d.to_bits(), free[k].to_bits(), "{c} {order:?}");
                            }
                            None => assert!(d.is_infinite()),
                        }
                    }
                }
            }
        }
    }

    /// A slab (a floor two cells high) with a wall between the goal and the stop, so that the
    /// goal does not see the stop and the march's bound comes from a cell past the wall's end.
    fn walled_slab() -> (Grid3, Cell3, Cell3) {
        let mut grid = Grid3::new(60, 40, 2).unwrap();
        for y in 0..30 {
            for z in 0..2 {
                grid.set_obstacle(Cell3::new(30, y, z), true).unwrap();
            }
        }
        (grid, Cell3::new(25, 25, 0), Cell3::new(50, 8, 1))
    }

    /// The ways at most `detour` longer than the shortest: where they pass, the values are
    /// the whole march's; far off them nothing is marched; the stop's value is the whole
    /// march's bit for bit.
    #[test]
    fn a_march_kept_to_short_ways_keeps_their_values_and_leaves_the_rest() {
        let (grid, goal, stop) = walled_slab();
        let cells = FreeCells3::new(&grid).unwrap();
        let fmm = FastMarching {
            spacing: 0.1,
            ..FastMarching::with_order(Order::Second)
        };
        let whole = fmm
            .solve3_free(&cells, &[goal], Default::default())
            .unwrap();
        let at = |values: &[f32], c: Cell3| values[cells.number(c).unwrap()];
        let shortest = at(&whole, stop);
        // Round the wall's end: longer than the straight line, so the goal cannot see it.
        let line = 0.1 * ((25.0f32 * 25.0) + 17.0 * 17.0 + 1.0).sqrt();
        assert!(shortest > line + 0.5, "{shortest} {line}");
        let banded = SolveOptions3 {
            stop_at: Some(stop),
            past_stop: 1.0,
            ..Default::default()
        };
        let band = fmm.solve3_free(&cells, &[goal], banded).unwrap();
        let kept = SolveOptions3 {
            detour: Some(1.0),
            ..banded
        };
        let short = fmm.solve3_free(&cells, &[goal], kept).unwrap();
        assert_eq!(at(&short, stop).to_bits(), shortest.to_bits());
        let finite = |v: &[f32]| v.iter().filter(|x| x.is_finite()).count();
        assert!(
            3 * finite(&short) < 2 * finite(&band),
            "{} of {} cells",
            finite(&short),
            finite(&band)
        );
        let (mut inner, mut outer) = (0, 0);
        for k in 0..cells.len() {
            let c = cells.cell(k);
            let line = 0.1
                * (((c.x.abs_diff(stop.x).pow(2)
                    + c.y.abs_diff(stop.y).pow(2)
                    + c.z.abs_diff(stop.z).pow(2)) as f32)
                    .sqrt());
            let way = whole[k] + line;
            if way <= shortest + 0.7 {
                // On a way 0.7 m longer at most, three cells inside the edge.
                inner += 1;
                assert!(
                    (short[k] - whole[k]).abs() < 1e-3,
                    "{c}: {} {}",
                    short[k],
                    whole[k]
                );
            } else if way > shortest + 1.5 && c.x > 35 {
                // Past the wall, marched after the bound was found.
                outer += 1;
                assert!(short[k].is_infinite(), "{c}: {}", short[k]);
            }
        }
        assert!(inner > 300 && outer > 300, "{inner} {outer}");
        // The dense solve leaves out the same cells, bit for bit.
        let dense = fmm.solve3_with(&grid, &[goal], kept).unwrap();
        for k in 0..cells.len() {
            assert_eq!(
                dense.get(cells.cell(k)).unwrap().to_bits(),
                short[k].to_bits()
            );
        }
    }

    /// A corridor one cell wide that climbs in steps: the straight line along it sees the stop,
    /// but the 6-neighbour march goes along it at each step's length, longer than the line,
    /// so the bound falls short of the stop and the solve marches again without it.
    #[test]
    fn a_bound_short_of_the_stop_marches_every_way_again() {
        let n = 20;
        let mut grid =
            Grid3::from_obstacles([n + 1, n + 1, 1], vec![true; (n + 1) * (n + 1)]).unwrap();
        for i in 0..n {
            grid.set_obstacle(Cell3::new(i, i, 0), false).unwrap();
            grid.set_obstacle(Cell3::new(i + 1, i, 0), false).unwrap();
        }
        grid.set_obstacle(Cell3::new(n, n, 0), false).unwrap();
        let (goal, stop) = (Cell3::new(0, 0, 0), Cell3::new(n, n, 0));
        let cells = FreeCells3::new(&grid).unwrap();
        let fmm = FastMarching::default();
        let plain = SolveOptions3 {
            stop_at: Some(stop),
            past_stop: 1.0,
            ..Default::default()
        };
        let every = fmm.solve3_free(&cells, &[goal], plain).unwrap();
        let stop_k = cells.number(stop).unwrap();
        // Longer than the line plus the detour: a bound from the line alone misses it.
        assert!(
            every[stop_k] > (n as f32) * 2f32.sqrt() + 1.0,
            "{}",
            every[stop_k]
        );
        let kept = SolveOptions3 {
            detour: Some(1.0),
            ..plain
        };
        let again = fmm.solve3_free(&cells, &[goal], kept).unwrap();
        assert_eq!(
            again.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            every.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        let dense = fmm.solve3_with(&grid, &[goal], kept).unwrap();
        assert_eq!(dense.get(stop).unwrap().to_bits(), every[stop_k].to_bits());
        // A stop no way reaches stays infinite, with or without the detour.
        let mut apart = grid.clone();
        apart.set_obstacle(Cell3::new(10, 10, 0), true).unwrap();
        apart.set_obstacle(Cell3::new(11, 10, 0), true).unwrap();
        let cells = FreeCells3::new(&apart).unwrap();
        let cut = fmm.solve3_free(&cells, &[goal], kept).unwrap();
        assert!(cut[cells.number(stop).unwrap()].is_infinite());
    }

    #[test]
    fn bad_sources_stops_and_speed_maps_are_errors_naming_them() {
        let mut grid = Grid3::new(4, 4, 2).unwrap();
        grid.set_obstacle(Cell3::new(1, 1, 0), true).unwrap();
        let cells = FreeCells3::new(&grid).unwrap();
        assert_eq!(cells.len(), 31);
        assert_eq!(cells.number(Cell3::new(1, 1, 0)), None);
        assert_eq!(cells.number(Cell3::new(9, 0, 0)), None);
        let fmm = FastMarching::default();
        let e = |r: Result<Vec<f32>>| r.unwrap_err().to_string();
        let at = |c| fmm.solve3_free(&cells, &[c], Default::default());
        assert!(e(at(Cell3::new(1, 1, 0))).contains("(1, 1, 0)"));
        assert!(e(at(Cell3::new(4, 0, 0))).contains("outside"));
        assert!(e(fmm.solve3_free(&cells, &[], Default::default())).contains("no source"));
        let off = SolveOptions3 {
            stop_at: Some(Cell3::new(0, 7, 0)),
            ..Default::default()
        };
        assert!(e(fmm.solve3_free(&cells, &[Cell3::new(0, 0, 0)], off)).contains("outside"));
        let speed = envfield_grid::Field3::new([4, 4, 2], vec![1.0; 32]).unwrap();
        let with_speed = SolveOptions3 {
            speed: Some(&speed),
            ..Default::default()
        };
        assert!(
            e(fmm.solve3_free(&cells, &[Cell3::new(0, 0, 0)], with_speed)).contains("solve3_with")
        );
        let from = [Cell3::new(0, 0, 0)];
        let stop = Some(Cell3::new(3, 3, 1));
        for (detour, stop_at, expect) in [
            (f32::NAN, stop, "detour must be >= 0"),
            (-0.5, stop, "detour must be >= 0"),
            (1.0, None, "needs stop_at"),
        ] {
            let options = SolveOptions3 {
                stop_at,
                detour: Some(detour),
                ..Default::default()
            };
            assert!(
                e(fmm.solve3_free(&cells, &from, options)).contains(expect),
                "{expect}"
            );
            let dense = fmm.solve3_with(&grid, &from, options);
            assert!(matches!(dense, Err(EikonalError::InvalidConfig(m)) if m.contains(expect)));
        }
        let speed = envfield_grid::Field3::new([4, 4, 2], vec![1.0; 32]).unwrap();
        let both = SolveOptions3 {
            speed: Some(&speed),
            stop_at: stop,
            detour: Some(1.0),
            ..Default::default()
        };
        let dense = fmm.solve3_with(&grid, &from, both).unwrap_err().to_string();
        assert!(dense.contains("detour is for unit speed"), "{dense}");
        let walls = Grid3::from_obstacles([2, 2, 1], vec![true; 4]).unwrap();
        assert!(FreeCells3::new(&walls).is_err());
    }
}
