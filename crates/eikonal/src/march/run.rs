//! One march: the exact start around the sources, then cells accepted in order of value
//! until the heap is empty, the stop cell is accepted or its band is passed, kept to the ways
//! to the stop at most so much longer than the shortest where asked.

use super::lattice::Links;
use super::marcher::Marcher;
use super::Problem;
use crate::heap::{unpack, Rec, BLOCKED, KNOWN};

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
    pub(super) fn run(
        &mut self,
        p: &Problem<'_, N>,
        record: impl Fn([usize; N]) -> usize,
        cell_of: impl Fn(usize) -> [usize; N],
    ) -> f32 {
        let frozen = self.freeze_sources(p, &record);
        let stop = p.stop_at.map(&record);
        let band = p.past_stop > 0.0;
        // The restriction's bound: a cell is kept while its value plus its straight line to
        // the stop is at most this. Infinite until a cell that sees the stop is accepted.
        let mut bound = Bound {
            within: f32::INFINITY,
            sighting: p.stop_at.filter(|_| p.detour.is_finite()),
            accepted: 0,
        };
        if let Some(target) = bound.sighting {
            for &i in &self.frozen_in_order(&frozen) {
                let c = cell_of(i);
                if self.sees(&record, c, target) {
                    bound.found(self.recs[i].known, c, target, p);
                    break;
                }
            }
        }
        // A stop cell among the sources is known already: the march ends there, or its band
        // counts from its value.
        let stop_known = stop.filter(|&s| self.recs[s].tag == KNOWN);
        if !band && stop_known.is_some() {
            return bound.within;
        }
        let mut limit = stop_known.map_or(f32::INFINITY, |s| self.recs[s].known + p.past_stop);
        for &i in &frozen {
            self.update_neighbours(i);
        }
        while let Some(entry) = self.heap.pop(&mut self.recs) {
            let (value, i) = unpack(entry);
            if value > limit {
                break;
            }
            let i = i as usize;
            if let Some(target) = p.stop_at.filter(|_| bound.within.is_finite()) {
                if value + straight(cell_of(i), target, p.spacing) > bound.within {
                    // On no way to the stop short enough: never accepted, never queued again.
                    self.recs[i].tag = BLOCKED;
                    continue;
                }
            }
            self.recs[i] = Rec {
                known: value,
                tag: KNOWN,
            };
            if let Some(target) = bound.sighting {
                bound.accepted += 1;
                if bound.accepted % SIGHT_EVERY == 0 {
                    let c = cell_of(i);
                    if self.sees(&record, c, target) {
                        bound.found(value, c, target, p);
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
        bound.within
    }

    /// The exact start: every cell within `p.source_radius` cells (per axis) of a source that
    /// sees it through a box of enterable cells gets the straight-line distance, and is
    /// frozen (known). The frozen cells, a cell once per source that reaches it.
    fn freeze_sources(
        &mut self,
        p: &Problem<'_, N>,
        record: &impl Fn([usize; N]) -> usize,
    ) -> Vec<usize> {
        let r = p.source_radius as isize;
        let side = 2 * r + 1;
        let mut frozen = Vec::new();
        for src in p.sources {
            let si = record(*src);
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
                if inside && line_of_sight(&self.recs, record, *src, off) {
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
        frozen
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

/// The bound a march that keeps to short ways keeps to, while it looks for it.
struct Bound<const N: usize> {
    /// A cell is kept while its value plus its straight line to the stop is at most this.
    within: f32,
    /// The stop, until a cell that sees it is found.
    sighting: Option<[usize; N]>,
    /// Cells accepted while looking.
    accepted: usize,
}

impl<const N: usize> Bound<N> {
    /// Cell `c` of `value` sees the stop `target`: the bound is its value plus that line plus
    /// the detour, and the looking ends.
    fn found(&mut self, value: f32, c: [usize; N], target: [usize; N], p: &Problem<'_, N>) {
        self.within = value + straight(c, target, p.spacing) + p.detour;
        self.sighting = None;
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
    record: &impl Fn([usize; N]) -> usize,
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
