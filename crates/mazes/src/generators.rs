//! Seeded maze generators of any size.

use crate::{MazeError, Result};
use envfield_grid::SplitMix64;
use envfield_grid::{Cell2, Grid2, Maze};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The VIN benchmark's gridworld generator (Tamar et al. 2016).
///
/// The goal is uniform in the interior; then `k` placement attempts, `k` uniform in
/// `1..=max_obs`, each a filled disc (radius `r` uniform in `1..=size_max`, or one cell when
/// `size_max` is 0) or a filled rectangle (sides uniform in `1..=size_max`) at a uniform
/// position, rejected if it covers the goal; a one-cell border; regenerated when no obstacle
/// landed.
///
/// A disc of radius `r` holds the cells at squared offset `dr² + dc² < r (r + 1)`: a plus of 5
/// cells for `r = 1` and 21 cells (rows of 3, 5, 5, 5, 3) for `r = 2`, the discs VIN's 28x28
/// mazes are made of. (Until November 2026 this generator drew `dr² + dc² <= r²`, a 13-cell
/// diamond for `r = 2`: 28x28 mazes came out with 16% obstacles against the 21% of VIN's
/// published test set.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Gridworld {
    /// Side of the square maze, border included (at least 4).
    pub size: usize,
    /// Most placement attempts.
    pub max_obs: usize,
    /// Largest disc radius / rectangle side; 0 places single cells.
    pub size_max: usize,
}

impl Gridworld {
    /// VIN's settings for 8, 16 and 28 (8: 30 attempts of single cells; 16: 40, size 1;
    /// 28: 50, size 2); other sizes scale `max_obs` and `size_max` with the side.
    pub fn vin(size: usize) -> Self {
        let (max_obs, size_max) = match size {
            0..=8 => (30, 0),
            9..=16 => (40, 1),
            17..=28 => (50, 2),
            n => (50 * n * n / (28 * 28), n / 14),
        };
        Self {
            size,
            max_obs,
            size_max,
        }
    }

    fn generate(&self, rng: &mut SplitMix64) -> Result<Maze> {
        let n = self.size;
        if n < 4 || self.max_obs == 0 {
            return Err(MazeError::InvalidConfig(format!(
                "gridworld needs size >= 4 and max_obs >= 1 (got {n}, {})",
                self.max_obs
            )));
        }
        loop {
            let goal = Cell2::new(1 + rng.below(n - 2), 1 + rng.below(n - 2));
            let mut obstacles = vec![false; n * n];
            let mut landed = 0;
            let attempts = 1 + rng.below(self.max_obs);
            for _ in 0..attempts {
                let mut shape = Vec::new();
                let (r0, c0) = (rng.below(n) as isize, rng.below(n) as isize);
                if self.size_max == 0 {
                    shape.push((r0, c0));
                } else if rng.below(2) == 0 {
                    let rad = 1 + rng.below(self.size_max) as isize;
                    shape.extend(disc(rad).map(|(dr, dc)| (r0 + dr, c0 + dc)));
                } else {
                    let (h, w) = (1 + rng.below(self.size_max), 1 + rng.below(self.size_max));
                    for dr in 0..h as isize {
                        for dc in 0..w as isize {
                            shape.push((r0 + dr, c0 + dc));
                        }
                    }
                }
                let cells: Vec<usize> = shape
                    .into_iter()
                    .filter(|&(r, c)| r >= 0 && c >= 0 && (r as usize) < n && (c as usize) < n)
                    .map(|(r, c)| r as usize * n + c as usize)
                    .collect();
                if cells.contains(&(goal.row * n + goal.col)) {
                    continue;
                }
                for i in cells {
                    let (r, c) = (i / n, i % n);
                    if r > 0 && c > 0 && r < n - 1 && c < n - 1 && !obstacles[i] {
                        landed += 1;
                    }
                    obstacles[i] = true;
                }
            }
            if landed == 0 {
                continue;
            }
            add_border(&mut obstacles, n, n);
            let grid = Grid2::from_obstacles(n, n, obstacles)?;
            return Ok(Maze {
                grid,
                start: None,
                goal: Some(goal),
            });
        }
    }
}

/// The offsets of a gridworld disc of radius `rad` (see [`Gridworld`]).
fn disc(rad: isize) -> impl Iterator<Item = (isize, isize)> {
    (-rad..=rad)
        .flat_map(move |dr| (-rad..=rad).map(move |dc| (dr, dc)))
        .filter(move |&(dr, dc)| dr * dr + dc * dc < rad * (rad + 1))
}

fn add_border(obstacles: &mut [bool], rows: usize, cols: usize) {
    for r in 0..rows {
        for c in 0..cols {
            if r == 0 || c == 0 || r == rows - 1 || c == cols - 1 {
                obstacles[r * cols + c] = true;
            }
        }
    }
}

/// The generators, by name: `gridworld`, `crossings`, `rooms`, `perfect`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GeneratorKind {
    /// [`Gridworld::vin`] of the size.
    Gridworld,
    /// Walls crossing the room with gaps (Minigrid SimpleCrossing style).
    Crossings,
    /// Rooms joined by doors, by recursive division (Minigrid FourRooms / MultiRoom style).
    Rooms,
    /// One-cell corridors by a recursive backtracker (a perfect maze: one path between cells).
    Perfect,
}

impl fmt::Display for GeneratorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            GeneratorKind::Gridworld => "gridworld",
            GeneratorKind::Crossings => "crossings",
            GeneratorKind::Rooms => "rooms",
            GeneratorKind::Perfect => "perfect",
        })
    }
}

impl FromStr for GeneratorKind {
    type Err = MazeError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "gridworld" => Ok(GeneratorKind::Gridworld),
            "crossings" => Ok(GeneratorKind::Crossings),
            "rooms" => Ok(GeneratorKind::Rooms),
            "perfect" => Ok(GeneratorKind::Perfect),
            _ => Err(MazeError::InvalidConfig(format!(
                "unknown generator {s:?} (expected gridworld, crossings, rooms or perfect)"
            ))),
        }
    }
}

/// A seeded maze generator: a kind and a side length.
///
/// ```
/// use envfield_mazes::{GeneratorKind, MazeGenerator};
///
/// let gen = MazeGenerator::new(GeneratorKind::Gridworld, 28)?;
/// let mazes = gen.generate_many(10, 42)?;
/// assert_eq!(mazes.len(), 10);
/// assert_eq!(mazes, gen.generate_many(10, 42)?); // seeded
/// assert!(mazes.iter().all(|m| m.goal.is_some()));
/// # Ok::<(), envfield_mazes::MazeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MazeGenerator {
    /// Which generator.
    pub kind: GeneratorKind,
    /// Side of the square maze, border included.
    pub size: usize,
}

impl MazeGenerator {
    /// A generator, checking the size (at least 5; at most 4096).
    ///
    /// # Errors
    /// [`MazeError::InvalidConfig`].
    pub fn new(kind: GeneratorKind, size: usize) -> Result<Self> {
        if !(5..=4096).contains(&size) {
            return Err(MazeError::InvalidConfig(format!(
                "maze size must be in 5..=4096, got {size}"
            )));
        }
        Ok(Self { kind, size })
    }

    /// One maze from `seed`. Every kind sets a goal on a free cell.
    ///
    /// # Errors
    /// [`MazeError::InvalidConfig`] for a size the generator cannot make.
    pub fn generate(&self, seed: u64) -> Result<Maze> {
        let mut rng = SplitMix64::new(seed);
        let n = self.size;
        let grid = match self.kind {
            GeneratorKind::Gridworld => return Gridworld::vin(n).generate(&mut rng),
            GeneratorKind::Crossings => crossings(n, 1 + rng.below(5), &mut rng)?,
            GeneratorKind::Rooms => rooms(n, &mut rng)?,
            GeneratorKind::Perfect => perfect(n, &mut rng)?,
        };
        let free: Vec<Cell2> = grid.free_cells().collect();
        let goal = free[rng.below(free.len())];
        Ok(Maze {
            grid,
            start: None,
            goal: Some(goal),
        })
    }

    /// `count` mazes; maze `i` comes from seed `seed * 1_000_003 + i`, so any maze of a set
    /// can be regenerated alone.
    ///
    /// # Errors
    /// As [`MazeGenerator::generate`].
    pub fn generate_many(&self, count: usize, seed: u64) -> Result<Vec<Maze>> {
        use rayon::prelude::*;
        (0..count as u64)
            .into_par_iter()
            .map(|i| self.generate(seed.wrapping_mul(1_000_003).wrapping_add(i)))
            .collect()
    }
}

/// Walls along even rows/columns across the room; every wall segment between two crossing
/// walls gets one gap at an odd position, so every region is joined to its neighbours.
fn crossings(n: usize, walls: usize, rng: &mut SplitMix64) -> Result<Grid2> {
    let mut obs = vec![false; n * n];
    add_border(&mut obs, n, n);
    let even: Vec<usize> = (2..n - 2).step_by(2).collect();
    if even.is_empty() {
        return Grid2::from_obstacles(n, n, obs).map_err(Into::into);
    }
    let (mut rows, mut cols) = (Vec::new(), Vec::new());
    for _ in 0..walls {
        let at = even[rng.below(even.len())];
        if rng.below(2) == 0 {
            if !rows.contains(&at) {
                rows.push(at);
            }
        } else if !cols.contains(&at) {
            cols.push(at);
        }
    }
    for &r in &rows {
        (0..n).for_each(|c| obs[r * n + c] = true);
    }
    for &c in &cols {
        (0..n).for_each(|r| obs[r * n + c] = true);
    }
    // One gap per segment of each wall between the walls that cross it.
    let gap = |lo: usize, hi: usize, rng: &mut SplitMix64| -> Option<usize> {
        let odd: Vec<usize> = (lo + 1..hi).filter(|x| x % 2 == 1).collect();
        (!odd.is_empty()).then(|| odd[rng.below(odd.len())])
    };
    let mut cuts_c: Vec<usize> = cols.clone();
    cuts_c.extend([0, n - 1]);
    cuts_c.sort_unstable();
    for &r in &rows {
        for w in cuts_c.windows(2) {
            if let Some(c) = gap(w[0], w[1], rng) {
                obs[r * n + c] = false;
            }
        }
    }
    let mut cuts_r: Vec<usize> = rows.clone();
    cuts_r.extend([0, n - 1]);
    cuts_r.sort_unstable();
    for &c in &cols {
        for w in cuts_r.windows(2) {
            if let Some(r) = gap(w[0], w[1], rng) {
                obs[r * n + c] = false;
            }
        }
    }
    Grid2::from_obstacles(n, n, obs).map_err(Into::into)
}

/// Recursive division into rooms at least 3 cells wide, one door per dividing wall. Walls
/// lie on even rows/columns and doors on odd ones, so a later wall never blocks a door.
fn rooms(n: usize, rng: &mut SplitMix64) -> Result<Grid2> {
    let mut obs = vec![false; n * n];
    add_border(&mut obs, n, n);
    // Rooms: interior rectangles [r0, r1) x [c0, c1) of free cells.
    let mut stack = vec![(1usize, n - 1, 1usize, n - 1, 0usize)];
    let max_depth = 1 + (n / 8).min(3);
    let pick = |lo: usize, hi: usize, parity: usize, rng: &mut SplitMix64| -> Option<usize> {
        let options: Vec<usize> = (lo..=hi).filter(|x| x % 2 == parity).collect();
        (!options.is_empty()).then(|| options[rng.below(options.len())])
    };
    while let Some((r0, r1, c0, c1, depth)) = stack.pop() {
        if depth >= max_depth {
            continue;
        }
        // Both rooms of a split keep at least 3 rows (columns).
        let row_wall = if r1 >= r0 + 7 {
            pick(r0 + 3, r1 - 4, 0, rng)
        } else {
            None
        };
        let col_wall = if c1 >= c0 + 7 {
            pick(c0 + 3, c1 - 4, 0, rng)
        } else {
            None
        };
        let horizontal = match (row_wall, col_wall) {
            (Some(_), Some(_)) => {
                (r1 - r0) > (c1 - c0) || ((r1 - r0) == (c1 - c0) && rng.below(2) == 0)
            }
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (None, None) => continue,
        };
        if horizontal {
            let r = row_wall.expect("checked");
            let door = pick(c0, c1 - 1, 1, rng).unwrap_or(c0);
            for c in c0..c1 {
                obs[r * n + c] = c != door;
            }
            stack.push((r0, r, c0, c1, depth + 1));
            stack.push((r + 1, r1, c0, c1, depth + 1));
        } else {
            let c = col_wall.expect("checked");
            let door = pick(r0, r1 - 1, 1, rng).unwrap_or(r0);
            for r in r0..r1 {
                obs[r * n + c] = r != door;
            }
            stack.push((r0, r1, c0, c, depth + 1));
            stack.push((r0, r1, c + 1, c1, depth + 1));
        }
    }
    Grid2::from_obstacles(n, n, obs).map_err(Into::into)
}

/// A perfect maze: corridors one cell wide on odd coordinates, carved by an iterative
/// recursive backtracker; an even size leaves its last row and column as wall.
fn perfect(n: usize, rng: &mut SplitMix64) -> Result<Grid2> {
    let mut obs = vec![true; n * n];
    let cells = (n - 1) / 2; // odd coordinates 1, 3, ..., 2*cells - 1
    let at = |i: usize, j: usize| (2 * i + 1) * n + (2 * j + 1);
    let mut seen = vec![false; cells * cells];
    let mut stack = vec![(0usize, 0usize)];
    seen[0] = true;
    obs[at(0, 0)] = false;
    while let Some(&(i, j)) = stack.last() {
        let mut options = [(0usize, 0usize); 4];
        let mut k = 0;
        for (di, dj) in [(-1isize, 0isize), (1, 0), (0, -1), (0, 1)] {
            let (ni, nj) = (i as isize + di, j as isize + dj);
            if ni >= 0
                && nj >= 0
                && (ni as usize) < cells
                && (nj as usize) < cells
                && !seen[ni as usize * cells + nj as usize]
            {
                options[k] = (ni as usize, nj as usize);
                k += 1;
            }
        }
        if k == 0 {
            stack.pop();
            continue;
        }
        let (ni, nj) = options[rng.below(k)];
        seen[ni * cells + nj] = true;
        obs[at(ni, nj)] = false;
        obs[(i + ni + 1) * n + (j + nj + 1)] = false; // the wall between
        stack.push((ni, nj));
    }
    Grid2::from_obstacles(n, n, obs).map_err(Into::into)
}

#[cfg(test)]
mod tests {
    use super::*;
    use envfield_eikonal::bfs2;
    use envfield_grid::Neighbourhood2;

    #[test]
    fn discs_are_vins_plus_and_21_cell_disc() {
        let plus: Vec<_> = disc(1).collect();
        assert_eq!(plus, vec![(-1, 0), (0, -1), (0, 0), (0, 1), (1, 0)]);
        let two: Vec<_> = disc(2).collect();
        assert_eq!(two.len(), 21);
        let widths: Vec<usize> = (-2..=2)
            .map(|dr| two.iter().filter(|&&(r, _)| r == dr).count())
            .collect();
        assert_eq!(widths, vec![3, 5, 5, 5, 3]);
    }

    fn connected(g: &Grid2) -> bool {
        let start = g.free_cells().next().unwrap();
        let d = bfs2(g, &[start], Neighbourhood2::Four).unwrap();
        g.free_cells().all(|c| d.get(c).unwrap().is_finite())
    }

    #[test]
    fn crossings_rooms_and_perfect_mazes_are_connected() {
        for seed in 0..40 {
            for (kind, n) in [
                (GeneratorKind::Crossings, 9),
                (GeneratorKind::Crossings, 11),
                (GeneratorKind::Rooms, 19),
                (GeneratorKind::Perfect, 21),
                (GeneratorKind::Perfect, 16),
            ] {
                let m = MazeGenerator::new(kind, n).unwrap().generate(seed).unwrap();
                assert!(connected(&m.grid), "{kind} {n} seed {seed}");
                assert!(m.grid.is_free(m.goal.unwrap()));
            }
        }
    }

    #[test]
    fn perfect_mazes_have_one_path_between_cells() {
        // A tree: free cells = corridor joints + 1 in a 4-connected perfect maze.
        let m = MazeGenerator::new(GeneratorKind::Perfect, 31)
            .unwrap()
            .generate(3)
            .unwrap();
        let g = &m.grid;
        let mut edges = 0;
        for c in g.free_cells() {
            edges += g.neighbours(c, Neighbourhood2::Four).count();
        }
        assert_eq!(edges / 2 + 1, g.free_count());
        let big = MazeGenerator::new(GeneratorKind::Perfect, 129)
            .unwrap()
            .generate(1)
            .unwrap();
        assert!(connected(&big.grid));
    }

    #[test]
    fn gridworld_matches_vin_obstacle_density() {
        for (n, lo, hi) in [(8usize, 0.16, 0.25), (16, 0.14, 0.26), (28, 0.18, 0.24)] {
            let mazes = MazeGenerator::new(GeneratorKind::Gridworld, n)
                .unwrap()
                .generate_many(400, 1)
                .unwrap();
            let interior = ((n - 2) * (n - 2) * mazes.len()) as f64;
            let mut obstacles = 0usize;
            for m in &mazes {
                for r in 1..n - 1 {
                    for c in 1..n - 1 {
                        obstacles += usize::from(m.grid.is_obstacle(Cell2::new(r, c)));
                    }
                }
                assert!(m.grid.is_free(m.goal.unwrap()));
            }
            let frac = obstacles as f64 / interior;
            println!("gridworld {n}x{n}: interior obstacle fraction {frac:.3}");
            assert!(
                (lo..hi).contains(&frac),
                "{n}: interior obstacle fraction {frac}"
            );
        }
    }
}
