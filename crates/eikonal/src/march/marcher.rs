//! The marcher: its records, heap and stencils (first and second order), and how an accepted
//! cell updates its neighbours.

use super::lattice::Links;
use crate::heap::{IndexedHeap, Rec, BLOCKED, FAR, KNOWN};

pub(super) struct Marcher<const N: usize, const ARITY: usize, L: Links<N>> {
    /// Where each record's neighbours are.
    pub(super) links: L,
    /// Per cell: the accepted value (infinity for every other cell, so the stencil reads values
    /// without looking at the state) and the state tag. f32 keeps the working set small (the
    /// stencil is memory-bound on large grids); arithmetic is in f64. Tentative values live in
    /// the heap.
    pub(super) recs: Vec<Rec>,
    /// Travel time across one cell (spacing / speed) per padded cell, when speeds vary.
    pub(super) tau: Option<Vec<f64>>,
    pub(super) tau_uniform: f64,
    pub(super) second_order: bool,
    /// The dense lattice's strides, where the next cell's stencil rows are prefetched (large
    /// dense grids only: on small ones, and over a table of free cells, every record is in the
    /// cache already, and the prefetches only cost time).
    pub(super) prefetch: Option<[usize; N]>,
    pub(super) heap: IndexedHeap<ARITY>,
}

impl<const N: usize, const ARITY: usize, L: Links<N>> Marcher<N, ARITY, L> {
    #[inline]
    pub(super) fn tau(&self, i: usize) -> f64 {
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
    /// the L2 cache (the gain is measured in `docs/notes/performance-history.md`).
    #[inline(always)]
    pub(super) fn prefetch_around(&self, c: usize, strides: [usize; N]) {
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
    pub(super) fn update_neighbours(&mut self, i: usize) {
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
