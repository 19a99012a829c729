//! Exact shortest-path distances on the move graph of a grid.

use crate::sources::check_sources;
use crate::{EikonalError, Result};
use envfield_grid::{
    Cell2, Cell3, Field2, Field3, FieldModel, Grid2, Grid3, Neighbourhood2, Neighbourhood3,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::collections::{BinaryHeap, VecDeque};

#[derive(PartialEq)]
struct Entry(f64, usize);
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed: BinaryHeap is a max-heap.
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// The sources' cell indices, after the checks of [`check_sources`] and a grid with a free cell.
fn source_indices<C: Copy + std::fmt::Display>(
    sources: &[C],
    index: impl Fn(C) -> Option<usize>,
    obstacles: &[bool],
    shape: &str,
) -> Result<Vec<usize>> {
    if sources.is_empty() {
        return Err(EikonalError::NoSources);
    }
    if !obstacles.contains(&false) {
        return Err(EikonalError::NoFreeCell);
    }
    check_sources(sources, index, |i| obstacles[i], None, shape, |_, i| i)
}

/// Dijkstra over cells: `neighbours(i, push)` calls `push(j, step_cost)` for each move from `i`.
fn dijkstra(
    n: usize,
    sources: &[usize],
    neighbours: impl Fn(usize, &mut dyn FnMut(usize, f64)),
) -> Vec<f32> {
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        dist[s] = 0.0;
        heap.push(Entry(0.0, s));
    }
    while let Some(Entry(d, i)) = heap.pop() {
        if done[i] {
            continue;
        }
        done[i] = true;
        neighbours(i, &mut |j, w| {
            let nd = d + w;
            if nd < dist[j] {
                dist[j] = nd;
                heap.push(Entry(nd, j));
            }
        });
    }
    dist.into_iter().map(|d| d as f32).collect()
}

fn bfs(n: usize, sources: &[usize], neighbours: impl Fn(usize, &mut dyn FnMut(usize))) -> Vec<f32> {
    let mut dist = vec![u32::MAX; n];
    let mut queue = VecDeque::new();
    for &s in sources {
        dist[s] = 0;
        queue.push_back(s);
    }
    while let Some(i) = queue.pop_front() {
        let d = dist[i] + 1;
        neighbours(i, &mut |j| {
            if dist[j] == u32::MAX {
                dist[j] = d;
                queue.push_back(j);
            }
        });
    }
    dist.into_iter()
        .map(|d| {
            if d == u32::MAX {
                f32::INFINITY
            } else {
                d as f32
            }
        })
        .collect()
}

/// Exact shortest-path length from the nearest source to every cell of a 2D grid, moving under
/// `nb` with orthogonal steps costing 1 and diagonal steps `diagonal_cost`. Unreachable cells
/// and obstacles are infinite. O(n log n) in the number of free cells.
///
/// # Errors
/// [`EikonalError::NoSources`], [`EikonalError::SourceOutside`],
/// [`EikonalError::SourceOnObstacle`], [`EikonalError::NoFreeCell`], and
/// [`EikonalError::InvalidConfig`] for a diagonal cost that is not finite and positive.
pub fn dijkstra2(
    grid: &Grid2,
    sources: &[Cell2],
    nb: Neighbourhood2,
    diagonal_cost: f32,
) -> Result<Field2> {
    if !(diagonal_cost.is_finite() && diagonal_cost > 0.0) {
        return Err(EikonalError::InvalidConfig(format!(
            "diagonal cost must be finite and positive, got {diagonal_cost}"
        )));
    }
    let shape = format!("{}x{}", grid.rows(), grid.cols());
    let src = source_indices(sources, |c| grid.index(c), grid.obstacles(), &shape)?;
    let values = dijkstra(grid.len(), &src, |i, push| {
        for (c, len) in grid.neighbours(grid.cell(i), nb) {
            let w = if len > 1.0 { diagonal_cost as f64 } else { 1.0 };
            push(c.row * grid.cols() + c.col, w);
        }
    });
    Ok(Field2::new(grid.rows(), grid.cols(), values)?)
}

/// The fewest moves under `nb` from the nearest source to every cell (breadth-first search);
/// infinite where unreachable. O(n).
///
/// # Errors
/// As [`dijkstra2`].
pub fn bfs2(grid: &Grid2, sources: &[Cell2], nb: Neighbourhood2) -> Result<Field2> {
    let shape = format!("{}x{}", grid.rows(), grid.cols());
    let src = source_indices(sources, |c| grid.index(c), grid.obstacles(), &shape)?;
    let values = bfs(grid.len(), &src, |i, push| {
        for (c, _) in grid.neighbours(grid.cell(i), nb) {
            push(c.row * grid.cols() + c.col);
        }
    });
    Ok(Field2::new(grid.rows(), grid.cols(), values)?)
}

/// Exact shortest-path length on a 3D grid under `nb`, each step costing its Euclidean length
/// (1, sqrt 2 or sqrt 3). O(n log n).
///
/// # Errors
/// As [`dijkstra2`].
pub fn dijkstra3(grid: &Grid3, sources: &[Cell3], nb: Neighbourhood3) -> Result<Field3> {
    let [a, b, c] = grid.shape();
    let src = source_indices(
        sources,
        |c| grid.index(c),
        grid.obstacles(),
        &format!("{a}x{b}x{c}"),
    )?;
    let values = dijkstra(grid.len(), &src, |i, push| {
        for (c, len) in grid.neighbours(grid.cell(i), nb) {
            push(grid.index(c).expect("neighbour inside"), len as f64);
        }
    });
    Ok(Field3::new(grid.shape(), values)?)
}

/// The fewest moves under `nb` on a 3D grid (breadth-first search). O(n).
///
/// # Errors
/// As [`dijkstra2`].
pub fn bfs3(grid: &Grid3, sources: &[Cell3], nb: Neighbourhood3) -> Result<Field3> {
    let [a, b, c] = grid.shape();
    let src = source_indices(
        sources,
        |c| grid.index(c),
        grid.obstacles(),
        &format!("{a}x{b}x{c}"),
    )?;
    let values = bfs(grid.len(), &src, |i, push| {
        for (c, _) in grid.neighbours(grid.cell(i), nb) {
            push(grid.index(c).expect("neighbour inside"));
        }
    });
    Ok(Field3::new(grid.shape(), values)?)
}

/// The exact graph-distance oracle: shortest path lengths under a neighbourhood, with
/// orthogonal steps 1 and diagonal steps sqrt 2. Implements [`FieldModel`].
///
/// ```
/// use envfield_eikonal::GraphDistance;
/// use envfield_grid::{parse_mazes, Cell2, FieldModel, MoveRule, Neighbourhood2};
///
/// // Only a diagonal gap joins the two halves: `vin` passes it, `strict` does not.
/// let maze = &parse_mazes("####\n#.##\n##G#\n####\n")?[0];
/// let goal = maze.goal.unwrap();
/// let vin = GraphDistance::new(Neighbourhood2::Eight(MoveRule::Vin)).predict(&maze.grid, goal)?;
/// assert!((vin.get(Cell2::new(1, 1)).unwrap() - 2f32.sqrt()).abs() < 1e-6);
/// let strict = GraphDistance::new(Neighbourhood2::Eight(MoveRule::Strict)).predict(&maze.grid, goal)?;
/// assert!(strict.get(Cell2::new(1, 1)).unwrap().is_infinite());
/// # Ok::<(), envfield_grid::GridError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GraphDistance {
    /// Which moves join cells.
    pub neighbourhood: Neighbourhood2,
}

impl GraphDistance {
    /// The oracle for `neighbourhood`.
    pub fn new(neighbourhood: Neighbourhood2) -> Self {
        Self { neighbourhood }
    }

    /// One field per goal, in parallel (rayon).
    ///
    /// # Errors
    /// The first error of any goal, as [`dijkstra2`].
    pub fn solve_many(&self, grid: &Grid2, goals: &[Cell2]) -> Result<Vec<Field2>> {
        goals
            .par_iter()
            .map(|&g| dijkstra2(grid, &[g], self.neighbourhood, std::f32::consts::SQRT_2))
            .collect()
    }
}

impl FieldModel for GraphDistance {
    fn name(&self) -> &str {
        "graph"
    }

    fn predict(&self, grid: &Grid2, goal: Cell2) -> envfield_grid::Result<Field2> {
        Ok(dijkstra2(
            grid,
            &[goal],
            self.neighbourhood,
            std::f32::consts::SQRT_2,
        )?)
    }
}
