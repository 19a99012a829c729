//! The fast-marching core, shared by 2D and 3D through a const number of axes.
//!
//! Cells live in a padded array (two blocked cells on every side), so the first- and
//! second-order stencils never need bounds checks.

use crate::heap::IndexedHeap;

const FAR: u8 = 0;
const TRIAL: u8 = 1;
const KNOWN: u8 = 2;
const BLOCKED: u8 = 3;
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
    fn new(dims: [usize; N]) -> Self {
        let mut strides = [0; N];
        let mut acc = 1;
        for k in (0..N).rev() {
            strides[k] = acc;
            acc *= dims[k] + 2 * PAD;
        }
        Self {
            dims,
            strides,
            len: acc,
        }
    }

    #[inline]
    fn padded(&self, cell: [usize; N]) -> usize {
        (0..N).map(|k| (cell[k] + PAD) * self.strides[k]).sum()
    }

    /// Calls `f(original_index, padded_index)` for every cell in C order.
    fn for_each(&self, mut f: impl FnMut(usize, usize)) {
        let inner = self.dims[N - 1];
        let mut idx = [0usize; N];
        let mut orig = 0;
        loop {
            let base = self.padded(idx);
            for j in 0..inner {
                f(orig + j, base + j);
            }
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

struct Marcher<const N: usize> {
    strides: [usize; N],
    val: Vec<f64>,
    state: Vec<u8>,
    /// Travel time across one cell (spacing / speed) per padded cell, when speeds vary.
    tau: Option<Vec<f64>>,
    tau_uniform: f64,
    second_order: bool,
    heap: IndexedHeap,
}

impl<const N: usize> Marcher<N> {
    #[inline]
    fn tau(&self, i: usize) -> f64 {
        match &self.tau {
            Some(t) => t[i],
            None => self.tau_uniform,
        }
    }

    /// Solves `sum_j c_j (u - v_j)^2 = tau^2` over the upwind terms sorted by `v`, adding terms
    /// while the solution exceeds the next `v`. Returns the solution, how many terms it used,
    /// and whether every quadratic had a real root.
    #[inline]
    fn solve(terms: &mut [(f64, f64, f64)], tau: f64) -> (f64, usize, bool) {
        // Insertion sort by v: at most 3 terms.
        for i in 1..terms.len() {
            let mut j = i;
            while j > 0 && terms[j - 1].0 > terms[j].0 {
                terms.swap(j - 1, j);
                j -= 1;
            }
        }
        let (v0, c0, _) = terms[0];
        let mut u = v0 + tau / c0.sqrt();
        let (mut sa, mut sb, mut sc) = (c0, 0.0, 0.0);
        let mut used = 1;
        for &(v, c, _) in &terms[1..] {
            if u <= v {
                break;
            }
            let d = v - v0;
            sa += c;
            sb += c * d;
            sc += c * d * d;
            let disc = sb * sb - sa * (sc - tau * tau);
            if disc < 0.0 {
                return (u, used, false);
            }
            u = v0 + (sb + disc.sqrt()) / sa;
            used += 1;
        }
        (u, used, true)
    }

    /// The tentative value of cell `q` from its accepted neighbours.
    #[inline]
    fn estimate(&self, q: usize) -> f64 {
        let tau = self.tau(q);
        let mut first = [(0.0, 1.0, 0.0); N];
        let mut second = [(0.0, 1.0, 0.0); N];
        let mut n = 0;
        let mut min_a1 = f64::INFINITY;
        for k in 0..N {
            let s = self.strides[k];
            let (lo, hi) = (q - s, q + s);
            let a_lo = if self.state[lo] == KNOWN { self.val[lo] } else { f64::INFINITY };
            let a_hi = if self.state[hi] == KNOWN { self.val[hi] } else { f64::INFINITY };
            let (a1, n2) = if a_lo <= a_hi { (a_lo, lo - s) } else { (a_hi, hi + s) };
            if a1 == f64::INFINITY {
                continue;
            }
            min_a1 = min_a1.min(a1);
            first[n] = (a1, 1.0, a1);
            second[n] = if self.second_order && self.state[n2] == KNOWN && self.val[n2] <= a1 {
                ((4.0 * a1 - self.val[n2]) / 3.0, 2.25, a1)
            } else {
                (a1, 1.0, a1)
            };
            n += 1;
        }
        debug_assert!(n > 0, "estimate called without an accepted neighbour");
        if self.second_order {
            let terms = &mut second[..n];
            let (u, used, ok) = Self::solve(terms, tau);
            // Upwind check: the value must not fall below a neighbour it was built from.
            if ok && terms[..used].iter().all(|t| t.2 <= u) {
                return u.min(min_a1 + tau);
            }
        }
        let (u, _, _) = Self::solve(&mut first[..n], tau);
        u.min(min_a1 + tau)
    }

    #[inline]
    fn update_neighbours(&mut self, i: usize) {
        for k in 0..N {
            let s = self.strides[k];
            for q in [i - s, i + s] {
                let st = self.state[q];
                if st == FAR || st == TRIAL {
                    let u = self.estimate(q);
                    self.val[q] = u;
                    self.state[q] = TRIAL;
                    self.heap.set(q as u32, u);
                }
            }
        }
    }
}

/// Runs fast marching and returns the C-order values (f32; infinity where not reached).
pub(crate) fn march<const N: usize>(p: &Problem<'_, N>) -> Vec<f32> {
    let lat = Lattice::new(p.dims);
    let mut state = vec![BLOCKED; lat.len];
    let mut tau = p.speed.map(|_| vec![f64::INFINITY; lat.len]);
    lat.for_each(|o, i| {
        let speed = p.speed.map_or(1.0, |s| s[o]);
        if !p.obstacles[o] && speed > 0.0 {
            state[i] = FAR;
            if let Some(t) = tau.as_mut() {
                t[i] = p.spacing / speed as f64;
            }
        }
    });
    let mut m = Marcher::<N> {
        strides: lat.strides,
        val: vec![f64::INFINITY; lat.len],
        state,
        tau,
        tau_uniform: p.spacing,
        second_order: p.second_order,
        heap: IndexedHeap::new(lat.len),
    };

    // Exact initialisation around each source.
    let r = p.source_radius as isize;
    let mut frozen = Vec::new();
    for src in p.sources {
        let si = lat.padded(*src);
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
            if inside && line_of_sight(&m.state, &lat, *src, off) {
                let ci = lat.padded(cell);
                let len = off.iter().map(|&o| (o * o) as f64).sum::<f64>().sqrt();
                let t = len * 0.5 * (m.tau(si) + m.tau(ci));
                if t < m.val[ci] {
                    m.val[ci] = t;
                }
                frozen.push(ci);
            }
        }
    }
    for &i in &frozen {
        m.state[i] = KNOWN;
    }
    let stop = p.stop_at.map(|c| lat.padded(c));
    let stopped_early = stop.is_some_and(|s| m.state[s] == KNOWN);
    if !stopped_early {
        for &i in &frozen {
            m.update_neighbours(i);
        }
        while let Some(i) = m.heap.pop() {
            let i = i as usize;
            m.state[i] = KNOWN;
            if Some(i) == stop {
                break;
            }
            m.update_neighbours(i);
        }
    }

    let mut out = vec![f32::INFINITY; p.obstacles.len()];
    lat.for_each(|o, i| {
        if m.state[i] == KNOWN {
            out[o] = m.val[i] as f32;
        }
    });
    out
}

/// Whether every cell of the box between `src` and `src + off` is enterable.
fn line_of_sight<const N: usize>(
    state: &[u8],
    lat: &Lattice<N>,
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
        if state[lat.padded(idx)] == BLOCKED {
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
