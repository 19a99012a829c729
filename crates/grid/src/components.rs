//! Connected components: one labelling routine for 2D and 3D grids and any other graph.

use crate::{Grid2, Grid3};

/// Connected components of a set of nodes: `labels[i]` is the component of node `i`
/// (`usize::MAX` for nodes outside the set) and `sizes[k]` the nodes of component `k`,
/// numbered in the order of their lowest node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Components {
    /// Each node's component, `usize::MAX` outside the set.
    pub labels: Vec<usize>,
    /// Each component's size.
    pub sizes: Vec<usize>,
}

impl Components {
    /// Labels the components of the nodes with `on[i]`, whose neighbours `neighbours(i, visit)`
    /// passes to `visit`. O(nodes + edges), no recursion.
    pub fn label(on: &[bool], mut neighbours: impl FnMut(usize, &mut dyn FnMut(usize))) -> Self {
        let mut labels = vec![usize::MAX; on.len()];
        let mut sizes = Vec::new();
        let mut stack = Vec::new();
        for start in 0..on.len() {
            if !on[start] || labels[start] != usize::MAX {
                continue;
            }
            let k = sizes.len();
            let mut size = 0;
            labels[start] = k;
            stack.push(start);
            while let Some(i) = stack.pop() {
                size += 1;
                neighbours(i, &mut |j| {
                    if on[j] && labels[j] == usize::MAX {
                        labels[j] = k;
                        stack.push(j);
                    }
                });
            }
            sizes.push(size);
        }
        Self { labels, sizes }
    }

    /// The largest component (the last of equal ones, as `Iterator::max_by_key` gives it),
    /// `None` for an empty set.
    pub fn largest(&self) -> Option<usize> {
        (0..self.sizes.len()).max_by_key(|&k| self.sizes[k])
    }

    /// How many components there are.
    pub fn count(&self) -> usize {
        self.sizes.len()
    }
}

impl Grid2 {
    /// The 4-connected components of the free cells (indices as [`Grid2::index`] gives).
    /// O(cells).
    pub fn free_components(&self) -> Components {
        let (rows, cols) = (self.rows(), self.cols());
        let on: Vec<bool> = self.obstacles().iter().map(|&o| !o).collect();
        Components::label(&on, |i, visit| {
            let (r, c) = (i / cols, i % cols);
            if r > 0 {
                visit(i - cols);
            }
            if r + 1 < rows {
                visit(i + cols);
            }
            if c > 0 {
                visit(i - 1);
            }
            if c + 1 < cols {
                visit(i + 1);
            }
        })
    }
}

impl Grid3 {
    /// The 26-connected components of the free voxels (indices as [`Grid3::index`] gives).
    /// O(voxels).
    pub fn free_components(&self) -> Components {
        let on: Vec<bool> = self.obstacles().iter().map(|&o| !o).collect();
        Components::label(&on, |i, visit| self.around(i, visit))
    }

    /// Passes to `visit` the index of each voxel of the up to 26 around the voxel of index `i`
    /// (free or not; `i` itself not).
    pub fn around(&self, i: usize, mut visit: impl FnMut(usize)) {
        let [nx, ny, nz] = self.shape();
        let (x, y, z) = (i / (ny * nz), (i / nz) % ny, i % nz);
        for a in x.saturating_sub(1)..(x + 2).min(nx) {
            for b in y.saturating_sub(1)..(y + 2).min(ny) {
                for c in z.saturating_sub(1)..(z + 2).min(nz) {
                    let j = (a * ny + b) * nz + c;
                    if j != i {
                        visit(j);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{parse_mazes, Cell3};

    #[test]
    fn walls_split_components_and_diagonals_join_voxels() {
        let maze = &parse_mazes("#####\n#.#.#\n#.#.#\n#####\n").unwrap()[0];
        let c = maze.grid.free_components();
        assert_eq!(c.sizes, vec![2, 2]);
        assert_eq!(
            c.labels[maze.grid.index(crate::Cell2::new(1, 1)).unwrap()],
            0
        );
        assert_eq!(c.labels[0], usize::MAX);
        let mut g = Grid3::new(3, 3, 3).unwrap();
        for i in 0..27 {
            g.set_obstacle(g.cell(i), true).unwrap();
        }
        g.set_obstacle(Cell3::new(0, 0, 0), false).unwrap();
        g.set_obstacle(Cell3::new(1, 1, 1), false).unwrap();
        g.set_obstacle(Cell3::new(2, 0, 2), false).unwrap();
        let c = g.free_components();
        assert_eq!(c.count(), 1);
        assert_eq!(c.largest(), Some(0));
    }
}
