//! The fast-marching core, shared by 2D and 3D through a const number of axes.
//!
//! Cells live in a padded array (two blocked cells on every side), so the first- and
//! second-order stencils never need bounds checks.

mod lattice;
mod marcher;
mod run;

use crate::heap::{IndexedHeap, Rec, BLOCKED, FAR, KNOWN};
use lattice::{Lattice, Strides, Table};
use marcher::Marcher;

const PAD: usize = 2;

/// One eikonal problem on an N-dimensional grid, already validated by the caller.
pub(crate) struct Problem<'a, const N: usize> {
    pub dims: [usize; N],
    /// C-order obstacle mask.
    pub obstacles: &'a [bool],
    /// C-order speeds (finite, >= 0; 0 = never entered), or `None` for unit speed.
    pub speed: Option<&'a [f32]>,
    pub sources: &'a [[usize; N]],
    pub stop_at: Option<[usize; N]>,
    /// How far above `stop_at`'s value the march goes on (0: it stops there).
    pub past_stop: f32,
    /// With `stop_at`: how much longer than the shortest a way to it may be and still be
    /// marched (infinity: every way). See [`Marcher::run`].
    pub detour: f32,
    pub spacing: f64,
    pub second_order: bool,
    /// Cells within this many cells (per axis) of a source, with a clear line of sight, get the
    /// exact straight-line distance.
    pub source_radius: usize,
}

/// Padded grids from this many cells on use the 4-ary heap (see `heap`) and prefetch.
const LARGE_GRID: usize = 1 << 16;

/// The most cells a padded grid may have: cells and heap positions are stored as `u32`, and the
/// three state tags take the values above this.
const MAX_PADDED_CELLS: usize = KNOWN as usize;

/// Whether a grid of `dims` (formatted as `shape` in the error) fits [`MAX_PADDED_CELLS`]:
/// whether [`march`] can lay it out.
pub(crate) fn check_size<const N: usize>(dims: [usize; N], shape: &str) -> crate::Result<()> {
    match Lattice::new(dims) {
        Some(_) => Ok(()),
        None => Err(crate::EikonalError::GridTooLarge {
            shape: shape.to_string(),
            limit: MAX_PADDED_CELLS,
        }),
    }
}

/// Runs fast marching and returns the C-order values (f32; infinity where not reached) and
/// the bound the march kept to ([`Marcher::run`]). The caller has checked the grid's size
/// with [`check_size`].
pub(crate) fn march<const N: usize>(p: &Problem<'_, N>) -> (Vec<f32>, f32) {
    let lat = Lattice::new(p.dims).expect("the solver checks the grid's size first");
    if lat.len >= LARGE_GRID {
        march_with::<N, 4>(p, lat)
    } else {
        march_with::<N, 2>(p, lat)
    }
}

thread_local! {
    /// The last march's cell records on this thread, kept for the next one: a fresh
    /// allocation as large as the grid comes from the system a zeroed page at a time, which
    /// cost a small grid's solve as much as its marching.
    static SPARE: std::cell::Cell<Vec<Rec>> = const { std::cell::Cell::new(Vec::new()) };
}

/// The most records [`SPARE`] keeps between solves (8 MB).
const SPARE_MAX: usize = 1 << 20;

fn march_with<const N: usize, const ARITY: usize>(
    p: &Problem<'_, N>,
    lat: Lattice<N>,
) -> (Vec<f32>, f32) {
    let mut recs = SPARE.take();
    recs.clear();
    recs.resize(
        lat.len,
        Rec {
            known: f32::INFINITY,
            tag: BLOCKED,
        },
    );
    let mut tau = p.speed.map(|_| vec![f64::INFINITY; lat.len]);
    if p.speed.is_none() {
        // Unit speed, the common case: a branch-free pass a row at a time.
        lat.for_each_row(|o, i, n| {
            for (r, &blocked) in recs[i..i + n].iter_mut().zip(&p.obstacles[o..o + n]) {
                r.tag = if blocked { BLOCKED } else { FAR };
            }
        });
    } else {
        lat.for_each(|o, i| {
            let speed = p.speed.map_or(1.0, |s| s[o]);
            if !p.obstacles[o] && speed > 0.0 {
                recs[i].tag = FAR;
                if let Some(t) = tau.as_mut() {
                    t[i] = p.spacing / speed as f64;
                }
            }
        });
    }
    let mut m = Marcher::<N, ARITY, _> {
        links: Strides(lat.strides),
        recs,
        tau,
        tau_uniform: p.spacing,
        second_order: p.second_order,
        prefetch: (lat.len >= LARGE_GRID).then_some(lat.strides),
        heap: IndexedHeap::new(),
    };
    let within = m.run(p, |cell| lat.padded(cell), |i| lat.cell(i));

    // Rows come in C order, so the output is written once, front to back.
    let mut out = Vec::with_capacity(p.obstacles.len());
    lat.for_each_row(|o, i, n| {
        debug_assert_eq!(o, out.len());
        out.extend(m.recs[i..i + n].iter().map(|r| r.known));
    });
    if m.recs.len() <= SPARE_MAX {
        SPARE.set(m.recs);
    }
    (out, within)
}

/// Runs fast marching over the free cells of a 3D grid alone and returns their values in
/// `links`' order (infinity where not reached). `links` holds each free cell's six neighbours
/// (below and above along x, y, z) as record numbers, the last entry a blocked cell that is
/// its own neighbour everywhere; `record` maps a cell of the grid to its record (the blocked
/// one for an obstacle), `cell_of` a record to its cell. The same arithmetic as [`march`] in
/// the same order, so the values (and the bound) are [`march`]'s bit for bit.
pub(crate) fn march_free(
    p: &Problem<'_, 3>,
    links: &[[u32; 6]],
    record: impl Fn([usize; 3]) -> usize,
    cell_of: impl Fn(usize) -> [usize; 3],
) -> (Vec<f32>, f32) {
    debug_assert!(p.speed.is_none(), "the free cells' march is for unit speed");
    let n = links.len();
    let mut recs = SPARE.take();
    recs.clear();
    recs.resize(
        n,
        Rec {
            known: f32::INFINITY,
            tag: FAR,
        },
    );
    recs[n - 1].tag = BLOCKED;
    // The 4-ary heap, however few the cells: on a room's region (3 435 voxels) it marched
    // 17% faster than the 2-ary one, which the dense march keeps for its small grids.
    let mut m = Marcher::<3, 4, _> {
        links: Table(links),
        recs,
        tau: None,
        tau_uniform: p.spacing,
        second_order: p.second_order,
        prefetch: None,
        heap: IndexedHeap::new(),
    };
    let within = m.run(p, record, cell_of);
    let out = m.recs[..n - 1].iter().map(|r| r.known).collect();
    if m.recs.len() <= SPARE_MAX {
        SPARE.set(m.recs);
    }
    (out, within)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_past_32_bit_cell_numbers_are_refused() {
        assert!(check_size([1024, 1024], "1024x1024").is_ok());
        assert!(check_size([1620, 1620, 1620], "1620^3").is_ok());
        // (65532 + 4)^2 = 2^32 padded cells, above the limit of 2^32 - 3.
        let err = check_size([65532, 65532], "65532x65532").unwrap_err();
        assert!(err.to_string().contains("65532x65532"), "{err}");
        assert!(check_size([65528, 65532], "").is_ok()); // 65532 * 65536 = 2^32 - 2^18
        assert!(check_size([1630, 1630, 1630], "").is_err());
        assert!(check_size([usize::MAX, 2], "").is_err()); // overflow is an error too
    }
}
