//! The lattices a march runs on: a dense padded grid, or a table of free cells, each telling
//! the marcher where a record's neighbours are ([`Links`]).

use super::{MAX_PADDED_CELLS, PAD};

pub(super) struct Lattice<const N: usize> {
    pub(super) dims: [usize; N],
    pub(super) strides: [usize; N],
    pub(super) len: usize,
}

impl<const N: usize> Lattice<N> {
    /// The padded lattice of a grid of `dims`, or `None` past [`MAX_PADDED_CELLS`].
    pub(super) fn new(dims: [usize; N]) -> Option<Self> {
        let mut strides = [0; N];
        let mut acc = 1usize;
        for k in (0..N).rev() {
            strides[k] = acc;
            acc = acc.checked_mul(dims[k].checked_add(2 * PAD)?)?;
        }
        (acc <= MAX_PADDED_CELLS).then_some(Self {
            dims,
            strides,
            len: acc,
        })
    }

    #[inline]
    pub(super) fn padded(&self, cell: [usize; N]) -> usize {
        (0..N).map(|k| (cell[k] + PAD) * self.strides[k]).sum()
    }

    /// The cell of padded index `i` (the inverse of [`Lattice::padded`] on the grid's cells).
    pub(super) fn cell(&self, i: usize) -> [usize; N] {
        std::array::from_fn(|k| (i / self.strides[k]) % (self.dims[k] + 2 * PAD) - PAD)
    }

    /// Calls `f(original_index, padded_index)` for every cell in C order.
    pub(super) fn for_each(&self, mut f: impl FnMut(usize, usize)) {
        self.for_each_row(|o, i, n| {
            for j in 0..n {
                f(o + j, i + j);
            }
        });
    }

    /// Calls `f(original_start, padded_start, length)` for every row along the last axis, in
    /// C order: a row is contiguous in both layouts, so a loop over it can be vectorised.
    pub(super) fn for_each_row(&self, mut f: impl FnMut(usize, usize, usize)) {
        let inner = self.dims[N - 1];
        let mut idx = [0usize; N];
        let mut orig = 0;
        loop {
            f(orig, self.padded(idx), inner);
            orig += inner;
            // Advance the odometer over all axes but the last.
            let mut k = N - 1;
            loop {
                if k == 0 {
                    return;
                }
                k -= 1;
                idx[k] += 1;
                if idx[k] < self.dims[k] {
                    break;
                }
                idx[k] = 0;
            }
        }
    }
}

/// How the marcher finds a cell's neighbours among its records.
pub(super) trait Links<const N: usize> {
    /// The record of `q`'s neighbour along axis `k`, above it (`up`) or below: a blocked
    /// record where it has none. `q` is a real cell, or (dense lattices) a cell of the
    /// first padding layer.
    fn next(&self, q: usize, k: usize, up: bool) -> usize;
}

/// A dense padded lattice: neighbours are a stride apart, and the two padding layers answer
/// for the cells a real cell's stencil reaches beyond the grid.
pub(super) struct Strides<const N: usize>(pub(super) [usize; N]);

impl<const N: usize> Links<N> for Strides<N> {
    #[inline(always)]
    fn next(&self, q: usize, k: usize, up: bool) -> usize {
        if up {
            q + self.0[k]
        } else {
            q - self.0[k]
        }
    }
}

/// The free cells of a 3D grid alone (`FreeCells3`): each record's six neighbours looked up
/// in a table, the last record a blocked one that is its own neighbour everywhere.
pub(super) struct Table<'a>(pub(super) &'a [[u32; 6]]);

impl Links<3> for Table<'_> {
    #[inline(always)]
    fn next(&self, q: usize, k: usize, up: bool) -> usize {
        self.0[q][2 * k + usize::from(up)] as usize
    }
}
