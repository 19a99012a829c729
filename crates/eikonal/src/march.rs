//! The fast-marching core, shared by 2D and 3D through a const number of axes.
//!
//! Cells live in a padded array (two blocked cells on every side), so the first- and
//! second-order stencils never need bounds checks.

use crate::heap::{unpack, IndexedHeap, Rec, BLOCKED, FAR, KNOWN};

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

struct Lattice<const N: usize> {
    dims: [usize; N],
    strides: [usize; N],
    len: usize,
}

impl<const N: usize> Lattice<N> {
    /// The padded lattice of a grid of `dims`, or `None` past [`MAX_PADDED_CELLS`].
    fn new(dims: [usize; N]) -> Option<Self> {
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
    fn padded(&self, cell: [usize; N]) -> usize {
        (0..N).map(|k| (cell[k] + PAD) * self.strides[k]).sum()
    }

    /// The cell of padded index `i` (the inverse of [`Lattice::padded`] on the grid's cells).
    fn cell(&self, i: usize) -> [usize; N] {
        std::array::from_fn(|k| (i / self.strides[k]) % (self.dims[k] + 2 * PAD) - PAD)
    }

    /// Calls `f(original_index, padded_index)` for every cell in C order.
    fn for_each(&self, mut f: impl FnMut(usize, usize)) {
        self.for_each_row(|o, i, n| {
            for j in 0..n {
                f(o + j, i + j);
            }
        });
    }

    /// Calls `f(original_start, padded_start, length)` for every row along the last axis, in
    /// C order: a row is contiguous in both layouts, so a loop over it can be vectorised.
    fn for_each_row(&self, mut f: impl FnMut(usize, usize, usize)) {
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
trait Links<const N: usize> {
    /// The record of `q`'s neighbour along axis `k`, above it (`up`) or below: a blocked
    /// record where it has none. `q` is a real cell, or (dense lattices) a cell of the
    /// first padding layer.
    fn next(&self, q: usize, k: usize, up: bool) -> usize;
}

/// A dense padded lattice: neighbours are a stride apart, and the two padding layers answer
/// for the cells a real cell's stencil reaches beyond the grid.
struct Strides<const N: usize>([usize; N]);

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
struct Table<'a>(&'a [[u32; 6]]);

impl Links<3> for Table<'_> {
    #[inline(always)]
    fn next(&self, q: usize, k: usize, up: bool) -> usize {
        self.0[q][2 * k + usize::from(up)] as usize
    }
}

struct Marcher<const N: usize, const ARITY: usize, L: Links<N>> {
    /// Where each record's neighbours are.
    links: L,
    /// Per cell: the accepted value (infinity for every other cell, so the stencil reads values
    /// without looking at the state) and the state tag. f32 keeps the working set small (the
    /// stencil is memory-bound on large grids); arithmetic is in f64. Tentative values live in
    /// the heap.
    recs: Vec<Rec>,
    /// Travel time across one cell (spacing / speed) per padded cell, when speeds vary.
    tau: Option<Vec<f64>>,
    tau_uniform: f64,
    second_order: bool,
    /// The dense lattice's strides, where the next cell's stencil rows are prefetched (large
    /// dense grids only: on small ones, and over a table of free cells, every record is in the
    /// cache already, and the prefetches only cost time).
    prefetch: Option<[usize; N]>,
    heap: IndexedHeap<ARITY>,
}

impl<const N: usize, const ARITY: usize, L: Links<N>> Marcher<N, ARITY, L> {
    #[inline]
    fn tau(&self, i: usize) -> f64 {
        match &self.tau {
            Some(t) => t[i],
            None => self.tau_uniform,
        }
    }

    /// Solves `sum_k c_k (u - v_k)^2 = tau^2` over the upwind terms `(v, c, a1)` (an axis
    /// contributes `c (u - v)^2`; `a1` is its accepted neighbour, infinity where it has none),
    /// adding axes in increasing `v` while the solution exceeds the next `v`. The arithmetic is
    /// shifted by the smallest `v` so the quadratic stays well conditioned, and written with
    /// selects rather than branches: which case applies is data-dependent and unpredictable.
    ///
    /// Returns `None` when a quadratic has no real root or the result falls below an accepted
    /// neighbour it was built from (only possible with second-order terms).
    #[inline]
    fn solve(terms: [(f64, f64, f64); N], tau: f64) -> Option<f64> {
        let mut t = terms;
        // Sorting network on v with selects.
        let mut cswap = |i: usize, j: usize| {
            let (x, y) = (t[i], t[j]);
            let swap = x.0 > y.0;
            t[i] = if swap { y } else { x };
            t[j] = if swap { x } else { y };
        };
        match N {
            2 => cswap(0, 1),
            3 => {
                cswap(0, 1);
                cswap(1, 2);
                cswap(0, 1);
            }
            _ => {
                for i in 1..N {
                    for j in (1..=i).rev() {
                        cswap(j - 1, j);
                    }
                }
            }
        }
        let (v0, c0, a0) = t[0];
        // `c` is 1 (first order) or 2.25 (second order): 1 / sqrt(c) without a square root
        // and a division on the critical path.
        let mut u = v0 + tau * if c0 > 1.0 { 2.0 / 3.0 } else { 1.0 };
        let mut ok = true;
        let mut max_a1 = a0;
        let (mut sa, mut sb, mut sc) = (c0, 0.0, 0.0);
        for &(v, c, a1) in &t[1..] {
            let take = u > v;
            let d = v - v0;
            let (na, nb, nc) = (sa + c, sb + c * d, sc + c * d * d);
            let disc = nb * nb - na * (nc - tau * tau);
            let cand = v0 + (nb + disc.max(0.0).sqrt()) / na;
            ok &= !take || disc >= 0.0;
            u = if take { cand } else { u };
            max_a1 = if take { max_a1.max(a1) } else { max_a1 };
            sa = if take { na } else { sa };
            sb = if take { nb } else { sb };
            sc = if take { nc } else { sc };
        }
        (ok && u >= max_a1).then_some(u)
    }

    /// The tentative value of cell `q` from its accepted neighbours.
    #[inline(always)]
    fn estimate(&self, q: usize) -> f64 {
        let tau = self.tau(q);
        let recs = &self.recs[..];
        let mut a = [f64::INFINITY; N];
        let mut far = [0usize; N];
        for k in 0..N {
            let (below, above) = (self.links.next(q, k, false), self.links.next(q, k, true));
            // SAFETY: `q` is a real cell, so its neighbours and theirs are records (the two-cell
            // padding of a dense lattice; a table's blocked record).
            let (a_lo, a_hi) = unsafe {
                (
                    recs.get_unchecked(below).known as f64,
                    recs.get_unchecked(above).known as f64,
                )
            };
            let lo = a_lo <= a_hi;
            far[k] = if lo {
                self.links.next(below, k, false)
            } else {
                self.links.next(above, k, true)
            };
            a[k] = if lo { a_lo } else { a_hi };
        }
        let min_a1 = a.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        debug_assert!(
            min_a1.is_finite(),
            "estimate called without an accepted neighbour"
        );
        let first = a.map(|x| (x, 1.0, x));
        if self.second_order {
            let mut terms = first;
            for k in 0..N {
                // SAFETY: as above.
                let a2 = unsafe { recs.get_unchecked(far[k]).known as f64 };
                if a[k].is_finite() && a2 <= a[k] {
                    terms[k] = ((4.0 * a[k] - a2) * (1.0 / 3.0), 2.25, a[k]);
                }
            }
            if let Some(u) = Self::solve(terms, tau) {
                return u.min(min_a1 + tau);
            }
        }
        if N == 2 {
            // Closed form of the 2D first-order update (the common case), branch-light.
            let (lo, hi) = (a[0].min(a[1]), a[0].max(a[1]));
            let d = hi - lo;
            return if d >= tau {
                lo + tau
            } else {
                0.5 * (lo + hi + (2.0 * tau * tau - d * d).sqrt())
            };
        }
        if N == 3 {
            // Closed form of the 3D first-order update, with selects: sort the three upwind
            // values, then take one, two or all three axes as the solution passes each.
            let (x, y, z) = sort3(a[0], a[1], a[2]);
            let (d1, d2) = (y - x, z - x);
            let tau2 = tau * tau;
            let one = tau;
            let two = 0.5 * (d1 + (2.0 * tau2 - d1 * d1).max(0.0).sqrt());
            let s = d1 + d2;
            let three = (s + (s * s - 3.0 * (d1 * d1 + d2 * d2 - tau2)).max(0.0).sqrt()) / 3.0;
            let w = if one <= d1 {
                one
            } else if two <= d2 {
                two
            } else {
                three
            };
            return x + w;
        }
        // First order always has a real root once sorted (u > v implies a real crossing).
        Self::solve(first, tau)
            .unwrap_or(min_a1 + tau)
            .min(min_a1 + tau)
    }

    /// Asks the cache for the records the stencils around cell `c` will read (the cells two
    /// steps from it, three at second order, along each axis but the last, whose cells share
    /// `c`'s cache lines) while the current cell's neighbours are updated. `c` is the heap's
    /// next cell, so its records are usually in the cache by the time it is accepted: the
    /// front visits cells in order of value, not of address, and on large grids it outgrows
    /// the L2 cache (the gain is measured in `docs/performance.md`).
    #[inline(always)]
    fn prefetch_around(&self, c: usize, strides: [usize; N]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let base = self.recs.as_ptr();
            let reach = if self.second_order { 3 } else { 2 };
            for k in 0..N - 1 {
                let s = strides[k];
                for d in 1..=reach {
                    // `wrapping_add`/`wrapping_sub`: a prefetch of an address outside the
                    // array is harmless (it is a hint and never faults), and no reference is
                    // formed. SAFETY: `_mm_prefetch` has no memory-safety requirement.
                    unsafe {
                        _mm_prefetch::<_MM_HINT_T0>(base.wrapping_add(c + d * s) as *const i8);
                        _mm_prefetch::<_MM_HINT_T0>(
                            base.wrapping_sub(d * s).wrapping_add(c) as *const i8
                        );
                    }
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (c, strides);
    }

    /// The tentative value of cell `q` when its one accepted neighbour is `i`, its neighbour
    /// along axis `k` (below `q` when `up`): what [`Marcher::estimate`] computes with one
    /// finite upwind term, operation for operation, without reading the other axes.
    #[inline(always)]
    fn estimate_single(&self, q: usize, i: usize, k: usize, up: bool) -> f64 {
        let tau = self.tau(q);
        let recs = &self.recs[..];
        // SAFETY: `i` is a real cell, a record.
        let a = unsafe { recs.get_unchecked(i).known as f64 };
        let first = a + tau;
        if self.second_order {
            // SAFETY: the neighbour of a real cell is a record (padding or the blocked one).
            let a2 = unsafe { recs.get_unchecked(self.links.next(i, k, !up)).known as f64 };
            if a2 <= a {
                let u = (4.0 * a - a2) * (1.0 / 3.0) + tau * (2.0 / 3.0);
                if u >= a {
                    return u.min(first);
                }
            }
        }
        first
    }

    /// Debug builds (the tests): where `q` has exactly one accepted neighbour, the shortcut
    /// must give the full estimate's value bit for bit.
    #[cfg(debug_assertions)]
    fn check_single(&self, q: usize, u: f32) {
        let accepted = (0..N)
            .flat_map(|k| [self.links.next(q, k, false), self.links.next(q, k, true)])
            .filter(|&n| self.recs[n].tag == KNOWN)
            .count();
        if accepted == 1 {
            let full = self.estimate(q) as f32;
            assert_eq!(u.to_bits(), full.to_bits(), "cell {q}: {u} != {full}");
        }
    }

    #[inline(always)]
    fn update_neighbours(&mut self, i: usize) {
        for k in 0..N {
            for up in [false, true] {
                let q = self.links.next(i, k, up);
                // SAFETY: neighbours of a real cell are records.
                let tag = unsafe { self.recs.get_unchecked(q).tag };
                if tag == FAR {
                    // Every accepted cell updates its open neighbours when it is accepted, so
                    // a cell still far has no accepted neighbour but `i` (source cells, frozen
                    // together, are the exception: each of them updates its neighbours in turn
                    // afterwards, and the last update, a full one, sees them all).
                    let u = self.estimate_single(q, i, k, up) as f32;
                    #[cfg(debug_assertions)]
                    self.check_single(q, u);
                    self.heap.set(u, q as u32, &mut self.recs);
                } else if tag != KNOWN && tag != BLOCKED {
                    let u = self.estimate(q) as f32;
                    self.heap.set(u, q as u32, &mut self.recs);
                }
            }
        }
    }
}

/// The three values in increasing order (infinities last), with min/max only.
#[inline(always)]
fn sort3(a: f64, b: f64, c: f64) -> (f64, f64, f64) {
    let (lo, hi) = (a.min(b), a.max(b));
    let (mid, top) = (hi.min(c), hi.max(c));
    (lo.min(mid), lo.max(mid), top)
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

impl<const N: usize, const ARITY: usize, L: Links<N>> Marcher<N, ARITY, L> {
    /// Initialises the records around `p`'s sources and marches until the heap is empty, the
    /// stop cell is accepted or its band is passed. `record` maps a cell of the grid to its
    /// record, `cell_of` a real cell's record back to its cell.
    ///
    /// With a stop cell and a finite `p.detour`, the march keeps to the ways to the stop at
    /// most that much longer than the shortest (the causal domain restriction of Clawson,
    /// Cartee and Vladimirsky, 2014): a cell whose value plus its straight-line distance to
    /// the stop exceeds a bound on the shortest way plus the detour is left out. Along the
    /// characteristic from any cell back to the sources that sum never grows, so every cell a
    /// kept cell's value depends on is kept too, but at the edge, where the grid's stencil
    /// strays from the characteristic. The bound is the first accepted cell (every
    /// [`SIGHT_EVERY`]th, the sources first) that sees the stop in a straight line through
    /// free cells: its value plus that line. Until one does, every cell is marched. Returns
    /// the bound plus the detour that the cells kept (infinity: no cell was left out).
    fn run(
        &mut self,
        p: &Problem<'_, N>,
        record: impl Fn([usize; N]) -> usize,
        cell_of: impl Fn(usize) -> [usize; N],
    ) -> f32 {
        // Exact initialisation around each source.
        let r = p.source_radius as isize;
        let mut frozen = Vec::new();
        for src in p.sources {
            let si = record(*src);
            let side = 2 * r + 1;
            for code in 0..side.pow(N as u32) {
                let mut off = [0isize; N];
                let mut rest = code;
                for k in (0..N).rev() {
                    off[k] = rest % side - r;
                    rest /= side;
                }
                let mut cell = [0usize; N];
                let mut inside = true;
                for k in 0..N {
                    let c = src[k] as isize + off[k];
                    inside &= c >= 0 && (c as usize) < p.dims[k];
                    cell[k] = c.max(0) as usize;
                }
                if inside && line_of_sight(&self.recs, &record, *src, off) {
                    let ci = record(cell);
                    let len = off.iter().map(|&o| (o * o) as f64).sum::<f64>().sqrt();
                    let t = (len * 0.5 * (self.tau(si) + self.tau(ci))) as f32;
                    if t < self.recs[ci].known {
                        self.recs[ci].known = t;
                    }
                    frozen.push(ci);
                }
            }
        }
        for &i in &frozen {
            self.recs[i].tag = KNOWN;
        }
        let stop = p.stop_at.map(&record);
        let band = p.past_stop > 0.0;
        // The restriction's bound: a cell is kept while its value plus its straight line to
        // the stop is at most this. Infinite until a cell that sees the stop is accepted.
        let mut within = f32::INFINITY;
        let mut sighting = match p.stop_at {
            Some(target) if p.detour.is_finite() => Some(target),
            _ => None,
        };
        if let Some(target) = sighting {
            for &i in &self.frozen_in_order(&frozen) {
                let c = cell_of(i);
                if self.sees(&record, c, target) {
                    within = self.recs[i].known + straight(c, target, p.spacing) + p.detour;
                    sighting = None;
                    break;
                }
            }
        }
        // A stop cell among the sources is known already: the march ends there, or its band
        // counts from its value.
        let stop_known = stop.filter(|&s| self.recs[s].tag == KNOWN);
        let mut limit = stop_known.map_or(f32::INFINITY, |s| self.recs[s].known + p.past_stop);
        if band || stop_known.is_none() {
            for &i in &frozen {
                self.update_neighbours(i);
            }
            let mut accepted = 0usize;
            while let Some(entry) = self.heap.pop(&mut self.recs) {
                let (value, i) = unpack(entry);
                if value > limit {
                    break;
                }
                let i = i as usize;
                if within.is_finite() {
                    let target = p.stop_at.expect("a bound comes with a stop");
                    if value + straight(cell_of(i), target, p.spacing) > within {
                        // On no way to the stop short enough: never accepted, never queued
                        // again.
                        self.recs[i].tag = BLOCKED;
                        continue;
                    }
                }
                self.recs[i] = Rec {
                    known: value,
                    tag: KNOWN,
                };
                if let Some(target) = sighting {
                    accepted += 1;
                    if accepted % SIGHT_EVERY == 0 {
                        let c = cell_of(i);
                        if self.sees(&record, c, target) {
                            within = value + straight(c, target, p.spacing) + p.detour;
                            sighting = None;
                        }
                    }
                }
                if Some(i) == stop {
                    if !band {
                        break;
                    }
                    limit = value + p.past_stop;
                }
                if let Some(strides) = self.prefetch {
                    if let Some(next) = self.heap.peek_cell() {
                        self.prefetch_around(next as usize, strides);
                    }
                }
                self.update_neighbours(i);
            }
        }
        within
    }

    /// The frozen cells in increasing value (the source first), each once.
    fn frozen_in_order(&self, frozen: &[usize]) -> Vec<usize> {
        let mut cells = frozen.to_vec();
        cells.sort_by(|&a, &b| self.recs[a].known.total_cmp(&self.recs[b].known));
        cells.dedup();
        cells
    }

    /// Whether the straight line between the centres of cells `from` and `to` passes through
    /// enterable cells alone (a 3D-DDA walk of the cells it crosses, one axis at a time, so
    /// that every cell it visits shares a face with the last).
    fn sees(
        &self,
        record: &impl Fn([usize; N]) -> usize,
        from: [usize; N],
        to: [usize; N],
    ) -> bool {
        let mut at = from;
        let mut step = [0isize; N];
        // The parameter (0 at `from`, 1 at `to`) at which the line next crosses a face on
        // each axis, and how far apart those crossings are.
        let mut next = [f64::INFINITY; N];
        let mut delta = [f64::INFINITY; N];
        for k in 0..N {
            let d = to[k] as f64 - from[k] as f64;
            if d != 0.0 {
                step[k] = if d > 0.0 { 1 } else { -1 };
                delta[k] = 1.0 / d.abs();
                next[k] = 0.5 * delta[k];
            }
        }
        let steps: usize = (0..N).map(|k| from[k].abs_diff(to[k])).sum();
        for _ in 0..steps {
            if self.recs[record(at)].tag == BLOCKED {
                return false;
            }
            let mut k = 0;
            for j in 1..N {
                if next[j] < next[k] {
                    k = j;
                }
            }
            at[k] = (at[k] as isize + step[k]) as usize;
            next[k] += delta[k];
        }
        // Each axis is stepped exactly as often as its cells differ, so this is `to`.
        debug_assert_eq!(at, to);
        self.recs[record(at)].tag != BLOCKED
    }
}

/// How often (in accepted cells) a march that keeps to short ways looks for a cell that sees
/// its stop, until one does: a look walks the line's cells, about as many as a few
/// acceptances cost.
const SIGHT_EVERY: usize = 16;

/// The straight-line distance between cells `at` and `stop`, in the solve's units.
#[inline]
fn straight<const N: usize>(at: [usize; N], stop: [usize; N], spacing: f64) -> f32 {
    let d2: usize = (0..N).map(|k| at[k].abs_diff(stop[k]).pow(2)).sum();
    ((d2 as f64).sqrt() * spacing) as f32
}

/// Whether every cell of the box between `src` and `src + off` is enterable.
fn line_of_sight<const N: usize>(
    recs: &[Rec],
    record: impl Fn([usize; N]) -> usize,
    src: [usize; N],
    off: [isize; N],
) -> bool {
    let mut lo = [0usize; N];
    let mut hi = [0usize; N];
    for k in 0..N {
        let end = (src[k] as isize + off[k]) as usize;
        lo[k] = src[k].min(end);
        hi[k] = src[k].max(end);
    }
    let mut idx = lo;
    loop {
        if recs[record(idx)].tag == BLOCKED {
            return false;
        }
        let mut k = N;
        loop {
            if k == 0 {
                return true;
            }
            k -= 1;
            idx[k] += 1;
            if idx[k] <= hi[k] {
                break;
            }
            idx[k] = lo[k];
        }
    }
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
