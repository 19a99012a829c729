//! Fast marching from the zero contour of a level-set function, on a grid of 1 to 12
//! dimensions: the signed distance, the travel time under a speed map and extension
//! velocities, with a spacing per axis, first or second order, a narrow band, periodic axes
//! and masked cells.
//!
//! This is the problem scikit-fmm solves, with its semantics point for point, so that its own
//! test suite passes against envfield's Python package (`python/`, `envfield.fmm`):
//!
//! - The front starts on the cells beside the zero contour: a cell whose neighbour along some
//!   axis has the opposite sign of `phi` sits at `dx * phi / (phi - phi_neighbour)` from the
//!   contour along that axis (the nearer side where both cross), and its distance combines
//!   the axes as `1 / sqrt(sum 1 / d_axis^2)`; a cell where `phi == 0` is 0.
//! - A cell's tentative value solves the upwind quadratic over each axis's frozen neighbour
//!   nearest the contour (in absolute value); at second order, where the cell two steps out
//!   is frozen and no nearer to the contour, the one-sided second-order difference. Where
//!   the quadratic has no real root, the distance falls back to first order (and first order
//!   to the minimum of the quadratic); the travel time drops one axis at a time and keeps the
//!   smallest answer.
//! - Cells whose values tie are frozen together before their neighbours are updated, and at
//!   second order a cell two steps beyond a newly frozen one is updated too.
//! - The march stops at the first cell beyond `narrow` (when it is not 0); masked cells,
//!   cells of speed below machine epsilon, and cells the march did not reach are reported
//!   as not reached.
//!
//! Point sources on an occupancy grid (the fields envfield learns) are [`crate::FastMarching`]'s
//! problem: its initialisation is exact around a point, where the zero contour of a cell set
//! to -1 is a small diamond around it.
//!
//! ```
//! use envfield_eikonal::level_set::{LevelSet, LevelSetOptions};
//!
//! // A 1D interface between the fourth and fifth cells, cells 0.5 apart.
//! let phi = [-1.0, -1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0];
//! let options = LevelSetOptions { dx: vec![0.5], ..LevelSetOptions::default() };
//! let d = LevelSet::new(&[8], &phi).distance(&options)?;
//! let want = [-1.75, -1.25, -0.75, -0.25, 0.25, 0.75, 1.25, 1.75];
//! assert!(d.values.iter().zip(want).all(|(v, w)| (v - w).abs() < 1e-12));
//! assert!(d.reached.iter().all(|&r| r));
//! # Ok::<(), envfield_eikonal::EikonalError>(())
//! ```

mod heap;
mod path;

pub use path::descend;

use crate::{EikonalError, Order, Result};
use heap::Heap;

/// The most axes a level set may have (as in scikit-fmm).
pub const MAX_DIMENSIONS: usize = 12;

const FAR: u8 = 0;
const NARROW: u8 = 1;
const FROZEN: u8 = 2;
const MASK: u8 = 3;
/// The state's bits of a cell's flags; the others keep `phi`'s sign, so that the march reads
/// it beside the state rather than from `phi`.
const STATE: u8 = 3;
const ABOVE_EPS: u8 = 4;
const POSITIVE: u8 = 8;
const NEGATIVE: u8 = 16;

/// How a level set is marched; the defaults are scikit-fmm's.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSetOptions {
    /// The cell length along each axis; empty means 1 on every axis.
    pub dx: Vec<f64>,
    /// First- or second-order upwind differences (default second, as scikit-fmm).
    pub order: Order,
    /// The narrow band's half-width: the march stops at the first value beyond it (in the
    /// units of the result: distance or time). 0 means no band.
    pub narrow: f64,
    /// Which axes wrap around; empty means none.
    pub periodic: Vec<bool>,
    /// Check the priority queue's invariant after every operation (slow; for tests).
    pub self_test: bool,
}

impl Default for LevelSetOptions {
    fn default() -> Self {
        Self {
            dx: Vec::new(),
            order: Order::Second,
            narrow: 0.0,
            periodic: Vec::new(),
            self_test: false,
        }
    }
}

/// A level-set function on a grid: its shape (row-major, the last axis fastest), its values
/// and the cells to leave out.
#[derive(Clone, Copy, Debug)]
pub struct LevelSet<'a> {
    /// The grid's size along each axis (1 to [`MAX_DIMENSIONS`] axes).
    pub shape: &'a [usize],
    /// `phi`, one value per cell; its zero contour is where the front starts.
    pub phi: &'a [f64],
    /// Cells never entered (true), as a masked array's mask.
    pub mask: Option<&'a [bool]>,
}

/// What a march found: one value per cell and whether the march reached it.
#[derive(Clone, Debug, PartialEq)]
pub struct Marched {
    /// The signed distance or the travel time; `f64::MAX` where not reached.
    pub values: Vec<f64>,
    /// False for masked cells, cells of (near) zero speed, and cells beyond the narrow band
    /// or cut off by the mask.
    pub reached: Vec<bool>,
}

/// The signed distance and the velocities extended from the zero contour.
#[derive(Clone, Debug, PartialEq)]
pub struct Extended {
    /// The signed distance (as [`LevelSet::distance`]).
    pub distance: Marched,
    /// The extension velocity of each cell; `f64::MAX` where not reached.
    pub velocity: Vec<f64>,
}

impl<'a> LevelSet<'a> {
    /// A level set with no mask.
    pub fn new(shape: &'a [usize], phi: &'a [f64]) -> Self {
        Self {
            shape,
            phi,
            mask: None,
        }
    }

    /// The same level set with `mask`'s true cells left out.
    pub fn with_mask(self, mask: &'a [bool]) -> Self {
        Self {
            mask: Some(mask),
            ..self
        }
    }

    /// The signed distance of every cell from the zero contour of `phi`, negative where `phi`
    /// is.
    ///
    /// # Errors
    /// [`EikonalError::LevelSet`] for a shape that does not match `phi` (or the mask), more
    /// than [`MAX_DIMENSIONS`] axes, a spacing that is not positive and finite, a `phi` that is
    /// not finite, a negative narrow band, or no zero contour at all.
    pub fn distance(&self, options: &LevelSetOptions) -> Result<Marched> {
        Ok(run(self, options, Kind::Distance, None, None)?.0)
    }

    /// The time the front leaving the zero contour takes to reach every cell at `speed` (one
    /// value per cell; cells slower than machine epsilon are not entered).
    ///
    /// # Errors
    /// As [`LevelSet::distance`], and for a `speed` of another length or a NaN speed.
    pub fn travel_time(&self, speed: &[f64], options: &LevelSetOptions) -> Result<Marched> {
        check_values(self.phi.len(), speed, "speed", true)?;
        Ok(run(self, options, Kind::Travel, Some(speed), None)?.0)
    }

    /// The signed distance, and `speed` extended from the zero contour along its normals
    /// (`grad v . grad d = 0`, Adalsteinsson and Sethian 1999). Where `ext_mask` is true the
    /// cell's own speed is left out of the value on the contour (its neighbour's is used).
    ///
    /// # Errors
    /// As [`LevelSet::travel_time`], for an `ext_mask` of another length, and where the
    /// extension divides by zero.
    pub fn extension_velocities(
        &self,
        speed: &[f64],
        ext_mask: Option<&[bool]>,
        options: &LevelSetOptions,
    ) -> Result<Extended> {
        check_values(self.phi.len(), speed, "speed", false)?;
        if let Some(e) = ext_mask {
            check_len(self.phi.len(), e.len(), "ext_mask")?;
        }
        let (distance, velocity) = run(self, options, Kind::Extension, Some(speed), ext_mask)?;
        Ok(Extended {
            distance,
            velocity: velocity.expect("the extension marcher extends"),
        })
    }
}

fn invalid(reason: String) -> EikonalError {
    EikonalError::LevelSet(reason)
}

fn check_len(cells: usize, len: usize, what: &str) -> Result<()> {
    if len != cells {
        return Err(invalid(format!(
            "{what} has {len} values but the grid has {cells} cells"
        )));
    }
    Ok(())
}

/// Refuses values of the wrong count, NaN anywhere, and (unless `infinite_ok`) infinities,
/// naming the first offending cell.
fn check_values(cells: usize, values: &[f64], what: &str, infinite_ok: bool) -> Result<()> {
    check_len(cells, values.len(), what)?;
    if let Some(i) = values
        .iter()
        .position(|v| v.is_nan() || (!infinite_ok && v.is_infinite()))
    {
        return Err(invalid(format!(
            "{what} is {} at flat index {i}; it must be {}",
            values[i],
            if infinite_ok { "a number" } else { "finite" }
        )));
    }
    Ok(())
}

/// Spacing and wrapping, checked.
struct Spacing {
    nd: usize,
    dx: [f64; MAX_DIMENSIONS],
    /// `1 / dx^2` per axis.
    idx2: [f64; MAX_DIMENSIONS],
    periodic: [bool; MAX_DIMENSIONS],
}

impl Spacing {
    fn new(shape: &[usize], options: &LevelSetOptions) -> Result<Self> {
        let nd = shape.len();
        if nd == 0 || nd > MAX_DIMENSIONS {
            return Err(invalid(format!(
                "a level set has 1 to {MAX_DIMENSIONS} axes, not {nd}"
            )));
        }
        if let Some(a) = shape.iter().position(|&s| s == 0) {
            return Err(invalid(format!("axis {a} of the grid has no cells")));
        }
        let mut cells = 1usize;
        for &n in shape {
            // Padded by two cells on each side, the grid must still number its cells in 32 bits.
            cells = cells
                .checked_mul(n + 4)
                .filter(|&c| c < u32::MAX as usize)
                .ok_or_else(|| invalid(format!("the {shape:?} grid has too many cells")))?;
        }
        let mut sp = Spacing {
            nd,
            dx: [1.0; MAX_DIMENSIONS],
            idx2: [1.0; MAX_DIMENSIONS],
            periodic: [false; MAX_DIMENSIONS],
        };
        if !options.dx.is_empty() {
            if options.dx.len() != nd {
                return Err(invalid(format!(
                    "{} spacings given for a grid of {nd} axes",
                    options.dx.len()
                )));
            }
            for (a, &d) in options.dx.iter().enumerate() {
                if !(d > 0.0 && d.is_finite()) {
                    return Err(invalid(format!(
                        "the spacing of axis {a} is {d}; it must be positive and finite"
                    )));
                }
                sp.dx[a] = d;
                sp.idx2[a] = 1.0 / d / d;
            }
        }
        if !options.periodic.is_empty() {
            if options.periodic.len() != nd {
                return Err(invalid(format!(
                    "periodic names {} axes for a grid of {nd} axes",
                    options.periodic.len()
                )));
            }
            sp.periodic[..nd].copy_from_slice(&options.periodic);
        }
        Ok(sp)
    }
}

/// How a cell finds its neighbours one and two steps along an axis.
trait Topology {
    /// The number of axes.
    fn nd(&self) -> usize;
    /// The cell `step` (±1 or ±2) cells from `i` along `axis`; `None` off the grid.
    fn step(&self, i: usize, axis: usize, step: isize) -> Option<usize>;
    /// Whether `axis` wraps around (its neighbours are taken whatever their flags).
    fn wraps(&self, axis: usize) -> bool;
    /// The caller's flat index of cell `i`.
    fn user_index(&self, i: usize) -> usize;
    /// One value per cell in the caller's order, `f` of each cell's index here.
    fn gather<U>(&self, f: impl FnMut(usize) -> U) -> Vec<U>;
    /// Asks the cache for the records around cell `i` that its neighbours' updates will read.
    #[inline(always)]
    fn prefetch_around(&self, _recs: &[Rec], _i: usize, _reach: usize) {}
}

/// A grid of `ND` axes, none wrapping, stored with two cells of masked padding on every
/// side: a neighbour is an offset, and the padding's flags stop the march at the border.
struct Padded<const ND: usize> {
    /// The padded grid's strides.
    stride: [usize; ND],
    shape: [usize; ND],
}

impl<const ND: usize> Padded<ND> {
    fn new(shape: &[usize]) -> Self {
        let mut p = Padded {
            stride: [0; ND],
            shape: [0; ND],
        };
        p.shape.copy_from_slice(shape);
        let mut s = 1;
        for a in (0..ND).rev() {
            p.stride[a] = s;
            s *= shape[a] + 4;
        }
        p
    }

    fn cells(&self) -> usize {
        self.stride[0] * (self.shape[0] + 4)
    }

    /// `(caller's start, padded start)` of every row along the last axis.
    fn rows(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let rows: usize = self.shape[..ND - 1].iter().product();
        let len = self.shape[ND - 1];
        let mut c = [0usize; ND];
        (0..rows).map(move |r| {
            let padded: usize = (0..ND).map(|a| (c[a] + 2) * self.stride[a]).sum();
            // The next row: an odometer over every axis but the last.
            for a in (0..ND.saturating_sub(1)).rev() {
                c[a] += 1;
                if c[a] < self.shape[a] {
                    break;
                }
                c[a] = 0;
            }
            (r * len, padded)
        })
    }

    /// The padded grid: `fill` on the padding, `f` of the caller's index elsewhere.
    fn fill<U: Copy>(&self, fill: U, mut f: impl FnMut(usize) -> U) -> Vec<U> {
        let len = self.shape[ND - 1];
        let mut out = vec![fill; self.cells()];
        for (s, d) in self.rows() {
            for (j, o) in out[d..d + len].iter_mut().enumerate() {
                *o = f(s + j);
            }
        }
        out
    }

    fn pad<T: Copy>(&self, src: &[T], fill: T) -> Vec<T> {
        self.fill(fill, |k| src[k])
    }
}

impl<const ND: usize> Topology for Padded<ND> {
    #[inline(always)]
    fn nd(&self) -> usize {
        ND
    }

    #[inline(always)]
    fn step(&self, i: usize, axis: usize, step: isize) -> Option<usize> {
        Some((i as isize + step * self.stride[axis] as isize) as usize)
    }

    #[inline(always)]
    fn wraps(&self, _axis: usize) -> bool {
        false
    }

    /// The cells `reach` steps along each axis but the last (whose cells share `i`'s cache
    /// lines): `i` is the queue's next cell, so its records are in the cache by the time it is
    /// frozen (the front visits cells in order of value, not of address).
    #[inline(always)]
    fn prefetch_around(&self, recs: &[Rec], i: usize, reach: usize) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let base = recs.as_ptr();
            for a in 0..ND - 1 {
                let s = self.stride[a];
                for d in 1..=reach {
                    // A prefetch is a hint that never faults; `wrapping_*` forms no reference.
                    // SAFETY: `_mm_prefetch` has no memory-safety requirement.
                    unsafe {
                        _mm_prefetch::<_MM_HINT_T0>(base.wrapping_add(i + d * s) as *const i8);
                        _mm_prefetch::<_MM_HINT_T0>(
                            base.wrapping_add(i).wrapping_sub(d * s) as *const i8
                        );
                    }
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (recs, i, reach);
    }

    fn gather<U>(&self, mut f: impl FnMut(usize) -> U) -> Vec<U> {
        let len = self.shape[ND - 1];
        let mut out = Vec::with_capacity(self.shape.iter().product());
        for (_, d) in self.rows() {
            out.extend((d..d + len).map(&mut f));
        }
        out
    }

    fn user_index(&self, mut i: usize) -> usize {
        let mut flat = 0;
        for a in 0..ND {
            let c = i / self.stride[a];
            i -= c * self.stride[a];
            flat = flat * self.shape[a] + (c - 2);
        }
        flat
    }
}

/// Any grid, some axes maybe wrapping: a neighbour's coordinate is read off its index.
struct Wrapped {
    nd: usize,
    shape: [usize; MAX_DIMENSIONS],
    stride: [usize; MAX_DIMENSIONS],
    periodic: [bool; MAX_DIMENSIONS],
}

impl Wrapped {
    fn new(shape: &[usize], sp: &Spacing) -> Self {
        let mut w = Wrapped {
            nd: shape.len(),
            shape: [1; MAX_DIMENSIONS],
            stride: [0; MAX_DIMENSIONS],
            periodic: sp.periodic,
        };
        w.shape[..shape.len()].copy_from_slice(shape);
        let mut s = 1;
        for a in (0..shape.len()).rev() {
            w.stride[a] = s;
            s *= shape[a];
        }
        w
    }
}

impl Topology for Wrapped {
    fn nd(&self) -> usize {
        self.nd
    }

    #[inline]
    fn step(&self, i: usize, axis: usize, step: isize) -> Option<usize> {
        let n = self.shape[axis] as isize;
        let c = (i / self.stride[axis]) as isize % n;
        let to = c + step;
        let to = if self.periodic[axis] {
            to.rem_euclid(n)
        } else if to < 0 || to >= n {
            return None;
        } else {
            to
        };
        Some((i as isize + (to - c) * self.stride[axis] as isize) as usize)
    }

    fn wraps(&self, axis: usize) -> bool {
        self.periodic[axis]
    }

    fn user_index(&self, i: usize) -> usize {
        i
    }

    fn gather<U>(&self, f: impl FnMut(usize) -> U) -> Vec<U> {
        let n = self.stride[0] * self.shape[0];
        (0..n).map(f).collect()
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Distance,
    Travel,
    Extension,
}

/// The values, where the march reached, and (for the extension) the velocities, in the
/// caller's layout.
type Outcome = (Marched, Option<Vec<f64>>);

/// Checks the input, lays the grid out (padded where it can be) and marches.
fn run(
    set: &LevelSet<'_>,
    options: &LevelSetOptions,
    kind: Kind,
    speed: Option<&[f64]>,
    ext_mask: Option<&[bool]>,
) -> Result<Outcome> {
    let sp = Spacing::new(set.shape, options)?;
    let n: usize = set.shape.iter().product();
    check_values(n, set.phi, "phi", false)
        .map_err(|e| invalid(format!("{e} (the grid is {:?})", set.shape)))?;
    if options.narrow.is_nan() || options.narrow < 0.0 {
        return Err(invalid(format!(
            "the narrow band is {}; it must be 0 (none) or positive",
            options.narrow
        )));
    }
    let mut flags = vec![FAR; n];
    if let Some(mask) = set.mask {
        check_len(n, mask.len(), "mask")?;
        for (f, &m) in flags.iter_mut().zip(mask) {
            if m {
                *f = MASK;
            }
        }
    }
    if kind == Kind::Travel {
        let speed = speed.expect("travel time has a speed");
        for (f, &s) in flags.iter_mut().zip(speed) {
            if s < f64::EPSILON {
                *f = MASK;
            }
        }
    }
    let input = Input {
        phi: set.phi,
        speed,
        ext_mask,
        flags,
    };
    let wraps = sp.periodic[..sp.nd].iter().any(|&p| p);
    match (wraps, sp.nd) {
        (false, 1) => padded::<1>(set.shape, sp, options, kind, input),
        (false, 2) => padded::<2>(set.shape, sp, options, kind, input),
        (false, 3) => padded::<3>(set.shape, sp, options, kind, input),
        _ => {
            let topo = Wrapped::new(set.shape, &sp);
            let arrays = (input.phi, input.speed, input.ext_mask);
            let recs = input
                .flags
                .iter()
                .zip(input.phi)
                .map(|(&f, &p)| Rec::new(f, p))
                .collect();
            Marcher::new(topo, sp, options, kind, recs, arrays).run()
        }
    }
}

/// The caller's arrays and the flags made from them.
struct Input<'a> {
    phi: &'a [f64],
    speed: Option<&'a [f64]>,
    ext_mask: Option<&'a [bool]>,
    flags: Vec<u8>,
}

fn padded<const ND: usize>(
    shape: &[usize],
    sp: Spacing,
    options: &LevelSetOptions,
    kind: Kind,
    input: Input<'_>,
) -> Result<Outcome> {
    let topo = Padded::<ND>::new(shape);
    let recs = topo.fill(Rec::new(MASK, 0.0), |k| {
        Rec::new(input.flags[k], input.phi[k])
    });
    let phi = topo.pad(input.phi, 0.0);
    let speed = input.speed.map(|s| topo.pad(s, 1.0));
    let ext_mask = input.ext_mask.map(|e| topo.pad(e, false));
    let arrays = (phi.as_slice(), speed.as_deref(), ext_mask.as_deref());
    Marcher::new(topo, sp, options, kind, recs, arrays).run()
}

struct Marcher<'a, T: Topology> {
    topo: T,
    sp: Spacing,
    phi: &'a [f64],
    speed: Option<&'a [f64]>,
    ext_mask: Option<&'a [bool]>,
    recs: Vec<Rec>,
    velocity: Vec<f64>,
    order: Order,
    narrow: f64,
    self_test: bool,
    kind: Kind,
}

/// One cell of the march: its frozen value, its queue position while queued, and its flags
/// (the state in the low bits, `phi`'s sign above), in one record so that a neighbour's state
/// and value share a cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Rec {
    /// The frozen value; `f64::MAX` until the cell is frozen (and for ever where it is
    /// masked), so that reading a neighbour's value needs no test of its state.
    known: f64,
    pos: u32,
    flags: u8,
}

impl Rec {
    /// A cell not yet frozen, in `state`, with `phi`'s sign.
    fn new(state: u8, phi: f64) -> Self {
        let mut flags = state;
        if phi > f64::EPSILON {
            flags |= ABOVE_EPS;
        }
        if phi > 0.0 {
            flags |= POSITIVE;
        } else if phi < 0.0 {
            flags |= NEGATIVE;
        }
        Rec {
            known: f64::MAX,
            pos: 0,
            flags,
        }
    }
}

/// Second-order weights: `(3/2)^2` and one third.
const AA: f64 = 9.0 / 4.0;
const ONE_THIRD: f64 = 1.0 / 3.0;

impl<'a, T: Topology> Marcher<'a, T> {
    fn new(
        topo: T,
        sp: Spacing,
        options: &LevelSetOptions,
        kind: Kind,
        recs: Vec<Rec>,
        (phi, speed, ext_mask): (&'a [f64], Option<&'a [f64]>, Option<&'a [bool]>),
    ) -> Self {
        let n = recs.len();
        Self {
            topo,
            sp,
            phi,
            speed,
            ext_mask,
            recs,
            velocity: if kind == Kind::Extension {
                vec![0.0; n]
            } else {
                Vec::new()
            },
            order: options.order,
            narrow: options.narrow,
            self_test: options.self_test,
            kind,
        }
    }

    /// Marches, then hands the values back in the caller's layout.
    fn run(mut self) -> Result<Outcome> {
        self.march()?;
        let recs = &self.recs;
        let values = self.topo.gather(|i| recs[i].known);
        let reached = self.topo.gather(|i| recs[i].flags & STATE == FROZEN);
        let velocity = (self.kind == Kind::Extension).then(|| {
            self.topo.gather(|i| {
                if recs[i].flags & STATE == FROZEN {
                    self.velocity[i]
                } else {
                    f64::MAX
                }
            })
        });
        Ok((Marched { values, reached }, velocity))
    }

    /// With `self_test`, the queue's invariant checked.
    #[inline(always)]
    fn checked(&self, heap: &Heap) -> Result<()> {
        if self.self_test {
            heap.check(&self.recs)
        } else {
            Ok(())
        }
    }

    #[inline(always)]
    fn state(&self, i: usize) -> u8 {
        self.recs[i].flags & STATE
    }

    #[inline(always)]
    fn set_state(&mut self, i: usize, state: u8) {
        self.recs[i].flags = self.recs[i].flags & !STATE | state;
    }

    /// Whether `phi` has strictly opposite signs at `a` and `b` (`phi[a] * phi[b] < 0`).
    #[inline(always)]
    fn opposite(&self, a: usize, b: usize) -> bool {
        let (fa, fb) = (self.recs[a].flags, self.recs[b].flags);
        (fa & POSITIVE != 0 && fb & NEGATIVE != 0) || (fa & NEGATIVE != 0 && fb & POSITIVE != 0)
    }

    /// A neighbour `step` cells along `axis`, unless it is off the grid or (on an axis that
    /// does not wrap) flagged `unless`.
    #[inline(always)]
    fn neighbour(&self, i: usize, axis: usize, step: isize, unless: u8) -> Option<usize> {
        let n = self.topo.step(i, axis, step)?;
        if !self.topo.wraps(axis) && self.state(n) == unless {
            return None;
        }
        Some(n)
    }

    /// The frozen value of the cell `step` cells along `axis` and that cell; `f64::MAX` where
    /// it is not frozen (or, with `usize::MAX`, off the grid).
    #[inline(always)]
    fn known(&self, i: usize, axis: usize, step: isize) -> (f64, usize) {
        match self.topo.step(i, axis, step) {
            Some(n) => (self.recs[n].known, n),
            None => (f64::MAX, usize::MAX),
        }
    }

    /// A frozen neighbour `step` cells along `axis`.
    #[inline(always)]
    fn frozen(&self, i: usize, axis: usize, step: isize) -> Option<usize> {
        self.neighbour(i, axis, step, MASK)
            .filter(|&n| self.state(n) == FROZEN)
    }

    fn march(&mut self) -> Result<()> {
        let contour = self.freeze_contour()?;
        if contour.is_empty() {
            return Err(EikonalError::NoZeroContour);
        }
        let mut heap = Heap::new();
        self.first_band(&contour, &mut heap)?;
        let mut batch = Vec::new();
        // Past the L2 cache the next cell's neighbourhood is fetched ahead.
        let prefetch = self.recs.len() >= 1 << 16;
        let reach = if self.order == Order::Second { 3 } else { 2 };
        while let Some((cell, signed)) = heap.pop(&mut self.recs) {
            self.checked(&heap)?;
            let value = signed.abs();
            if self.narrow != 0.0 && value > self.narrow {
                break;
            }
            batch.clear();
            self.freeze(cell, signed)?;
            batch.push(cell);
            while heap.peek() == Some(value) {
                let (cell, signed) = heap.pop(&mut self.recs).expect("peeked");
                self.checked(&heap)?;
                self.freeze(cell, signed)?;
                batch.push(cell);
            }
            if prefetch {
                if let Some(next) = heap.peek_cell() {
                    self.topo.prefetch_around(&self.recs, next, reach);
                }
            }
            for &cell in &batch {
                self.update_around(cell, &mut heap)?;
            }
        }
        Ok(())
    }

    #[inline]
    fn freeze(&mut self, i: usize, value: f64) -> Result<()> {
        self.recs[i].known = value;
        self.set_state(i, FROZEN);
        if self.kind == Kind::Extension {
            self.extend_to(i)?;
        }
        Ok(())
    }

    /// Updates the neighbours of a newly frozen cell (and, at second order, the cells two
    /// steps out beyond a frozen neighbour).
    fn update_around(&mut self, cell: usize, heap: &mut Heap) -> Result<()> {
        for axis in 0..self.topo.nd() {
            for step in [-1isize, 1] {
                if let Some(n) = self.neighbour(cell, axis, step, FROZEN) {
                    match self.state(n) {
                        NARROW => {
                            let d = self.update(n)?;
                            if d != 0.0 {
                                heap.set(n, d, &mut self.recs);
                                self.checked(heap)?;
                            }
                        }
                        FAR => {
                            let d = self.update(n)?;
                            if d != 0.0 {
                                self.set_state(n, NARROW);
                                heap.push(n, d, &mut self.recs);
                                self.checked(heap)?;
                            }
                        }
                        _ => {}
                    }
                }
                if self.order == Order::Second && self.known(cell, axis, step).0 != f64::MAX {
                    if let Some(n2) = self.neighbour(cell, axis, 2 * step, FROZEN) {
                        if self.state(n2) == NARROW {
                            let d = self.update_second(n2)?;
                            if d != 0.0 {
                                heap.set(n2, d, &mut self.recs);
                                self.checked(heap)?;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The far cells beside the frozen contour, queued with their first values.
    /// (A cell is beside a frozen one exactly when that one is beside it, so the band is
    /// found from the contour's cells rather than by a pass over the grid; the values depend
    /// only on the frozen cells, not on the order they are found in.)
    fn first_band(&mut self, contour: &[usize], heap: &mut Heap) -> Result<()> {
        for &f in contour {
            for axis in 0..self.topo.nd() {
                for step in [-1, 1] {
                    let Some(i) = self.topo.step(f, axis, step) else {
                        continue;
                    };
                    if self.state(i) == FAR {
                        self.set_state(i, NARROW);
                        let d = self.update(i)?;
                        heap.push(i, d, &mut self.recs);
                        self.checked(heap)?;
                    }
                }
            }
        }
        Ok(())
    }

    #[inline]
    fn update(&self, i: usize) -> Result<f64> {
        match self.order {
            Order::First => Ok(self.update_first(i)),
            Order::Second => self.update_second(i),
        }
    }

    /// The right root of `a t^2 + b t + c = rhs` for cell `i`: the distance takes the root on
    /// `phi`'s side, the travel time the larger; `None` without a real root.
    #[inline(always)]
    fn quadratic(&self, i: usize, a: f64, b: f64, c: f64) -> Option<f64> {
        let (c, larger) = match self.speed {
            Some(speed) if self.kind == Kind::Travel => (c - 1.0 / (speed[i] * speed[i]), true),
            _ => (c - 1.0, self.recs[i].flags & ABOVE_EPS != 0),
        };
        let det = b * b - 4.0 * a * c;
        if det >= 0.0 {
            Some(if larger {
                (-b + det.sqrt()) / 2.0 / a
            } else {
                (-b - det.sqrt()) / 2.0 / a
            })
        } else {
            None
        }
    }

    #[inline]
    fn update_first(&self, i: usize) -> f64 {
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..self.topo.nd() {
            // The frozen neighbour nearest the contour, the lower side on a tie (f64::MAX where
            // neither is frozen).
            let (below, _) = self.known(i, axis, -1);
            let (above, _) = self.known(i, axis, 1);
            let value = if above.abs() < below.abs() {
                above
            } else {
                below
            };
            if value < f64::MAX {
                let w = self.sp.idx2[axis];
                a += w;
                b -= w * 2.0 * value;
                cc += w * (value * value);
            }
        }
        // Without a real root, the minimum of the quadratic is the nearer answer.
        self.quadratic(i, a, b, cc).unwrap_or(-b / (2.0 * a))
    }

    #[inline]
    fn update_second(&self, i: usize) -> Result<f64> {
        if self.kind == Kind::Travel {
            let t = self.travel_second(i, 0);
            if t == f64::INFINITY {
                return Err(EikonalError::March(format!(
                    "no second-order update reaches flat index {}",
                    self.topo.user_index(i)
                )));
            }
            return Ok(t);
        }
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..self.topo.nd() {
            let (v1, v2) = self.upwind_pair(i, axis, false);
            self.accumulate(axis, v1, v2, &mut a, &mut b, &mut cc);
        }
        Ok(self
            .quadratic(i, a, b, cc)
            .unwrap_or_else(|| self.update_first(i)))
    }

    /// Along `axis`: the frozen neighbour nearest the contour, and the frozen cell beyond it
    /// where it is no nearer (`f64::MAX` for either when missing). The travel time counts the
    /// far cell negative when `phi` changes sign on the way.
    #[inline(always)]
    fn upwind_pair(&self, i: usize, axis: usize, travel: bool) -> (f64, f64) {
        let mut v1 = f64::MAX;
        let mut v2 = f64::MAX;
        // As scikit-fmm: the far cell is looked at on the side the near one is taken from, and
        // one found on the lower side stays when the upper side's near cell is nearer.
        for step in [-1, 1] {
            let (near, n) = self.known(i, axis, step);
            if near.abs() < v1.abs() {
                v1 = near;
                let (far, n2) = self.known(i, axis, 2 * step);
                if far != f64::MAX && ((far <= v1 && v1 >= 0.0) || (far >= v1 && v1 <= 0.0)) {
                    v2 = far;
                    if travel && (self.opposite(n2, n) || self.opposite(n2, i)) {
                        v2 = -v2;
                    }
                }
            }
        }
        (v1, v2)
    }

    #[inline(always)]
    fn accumulate(&self, axis: usize, v1: f64, v2: f64, a: &mut f64, b: &mut f64, c: &mut f64) {
        let w = self.sp.idx2[axis];
        if v2 < f64::MAX {
            let tp = ONE_THIRD * (4.0 * v1 - v2);
            *a += w * AA;
            *b -= w * 2.0 * AA * tp;
            *c += w * AA * (tp * tp);
        } else if v1 < f64::MAX {
            *a += w;
            *b -= w * 2.0 * v1;
            *c += w * (v1 * v1);
        }
    }

    /// The second-order travel time over the axes not in `avoid` (a bit set); where its
    /// quadratic has no root, the least over leaving out one more axis.
    fn travel_second(&self, i: usize, avoid: u32) -> f64 {
        let nd = self.topo.nd();
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..nd {
            if avoid & (1 << axis) != 0 {
                continue;
            }
            let (v1, v2) = self.upwind_pair(i, axis, true);
            self.accumulate(axis, v1, v2, &mut a, &mut b, &mut cc);
        }
        if let Some(t) = self.quadratic(i, a, b, cc) {
            return t;
        }
        if avoid.count_ones() as usize == nd {
            return f64::INFINITY;
        }
        let mut best: Option<f64> = None;
        for axis in 0..nd {
            if avoid & (1 << axis) != 0 {
                continue;
            }
            let t = self.travel_second(i, avoid | (1 << axis));
            // The first answer stands unless a later one is smaller (as std::min_element).
            best = Some(match best {
                Some(b) if t.partial_cmp(&b) != Some(std::cmp::Ordering::Less) => b,
                _ => t,
            });
        }
        best.unwrap_or(f64::INFINITY)
    }

    /// Freezes the cells on the zero contour and beside it.
    /// Returns the frozen cells. (One pass: whether a cell borders the contour depends on
    /// `phi` and the mask alone, not on which cells are frozen already.)
    fn freeze_contour(&mut self) -> Result<Vec<usize>> {
        let n = self.recs.len();
        let extend = self.kind == Kind::Extension;
        let mut contour = Vec::new();
        for i in 0..n {
            if self.state(i) == MASK {
                continue;
            }
            let p = self.phi[i];
            if p == 0.0 {
                self.set_state(i, FROZEN);
                self.recs[i].known = 0.0;
                if extend {
                    self.velocity[i] = self.speed.expect("extension has a speed")[i];
                }
                contour.push(i);
                continue;
            }
            let mut ldist = [0.0f64; MAX_DIMENSIONS];
            let mut lspeed = [0.0f64; MAX_DIMENSIONS];
            let mut borders = false;
            for axis in 0..self.topo.nd() {
                for step in [-1, 1] {
                    let Some(nb) = self.topo.step(i, axis, step) else {
                        continue;
                    };
                    let q = self.phi[nb];
                    // Masked cells (the padding among them, whose phi is 0) take no part,
                    // but on an axis that wraps (as scikit-fmm).
                    if p * q < 0.0 && (self.topo.wraps(axis) || self.state(nb) != MASK) {
                        borders = true;
                        let d = self.sp.dx[axis] * p / (p - q);
                        if ldist[axis] == 0.0 || ldist[axis] > d {
                            ldist[axis] = d;
                            if extend {
                                lspeed[axis] = self.contour_speed(i, nb, d, axis);
                            }
                        }
                    }
                }
            }
            if !borders {
                continue;
            }
            let nd = self.topo.nd();
            if extend {
                let (mut num, mut den) = (0.0, 0.0);
                for axis in 0..nd {
                    if ldist[axis] != 0.0 {
                        let w = 1.0 / (ldist[axis] * ldist[axis]);
                        num += lspeed[axis] * w;
                        den += w;
                    }
                }
                if den == 0.0 {
                    return Err(EikonalError::March(format!(
                        "the extension velocity on the contour at flat index {} divides by zero",
                        self.topo.user_index(i)
                    )));
                }
                self.velocity[i] = num / den;
            }
            let mut dsum = 0.0;
            for &d in &ldist[..nd] {
                if d > 0.0 {
                    dsum += 1.0 / d / d;
                }
            }
            let d = (1.0 / dsum).sqrt();
            self.recs[i].known = match (self.speed, self.kind) {
                (Some(speed), Kind::Travel) => (d / speed[i]).abs(),
                _ if p < 0.0 => -d,
                _ => d,
            };
            self.set_state(i, FROZEN);
            contour.push(i);
        }
        Ok(contour)
    }

    /// The speed on the contour between cell `i` and its neighbour `nb`, `d` from `i` along
    /// `axis`: interpolated, or the other cell's where one is in the extension mask.
    fn contour_speed(&self, i: usize, nb: usize, d: f64, axis: usize) -> f64 {
        let speed = self.speed.expect("extension has a speed");
        let masked = |k: usize| self.ext_mask.is_some_and(|m| m[k]);
        if masked(i) {
            speed[nb]
        } else if masked(nb) {
            speed[i]
        } else {
            speed[i] + d / self.sp.dx[axis] * (speed[nb] - speed[i])
        }
    }

    /// The extension velocity of a newly frozen cell from its frozen neighbours, weighted by
    /// how far each lies upwind (grad v . grad d = 0).
    fn extend_to(&mut self, i: usize) -> Result<()> {
        let (mut num, mut den) = (0.0, 0.0);
        for axis in 0..self.topo.nd() {
            let mut ld = 0.0f64;
            let mut ls = 0.0f64;
            for step in [-1, 1] {
                if let Some(n) = self.frozen(i, axis, step) {
                    let d = self.recs[i].known - self.recs[n].known;
                    if (ld == 0.0 || ld > d) && d.abs() > f64::EPSILON {
                        ld = d;
                        ls = self.velocity[n];
                    }
                }
            }
            num += ld.abs() * ls * self.sp.idx2[axis];
            den += ld.abs() * self.sp.idx2[axis];
        }
        if den == 0.0 {
            return Err(EikonalError::March(format!(
                "the extension velocity at flat index {} divides by zero: no frozen neighbour \
                 lies upwind",
                self.topo.user_index(i)
            )));
        }
        self.velocity[i] = num / den;
        Ok(())
    }
}

#[cfg(test)]
mod tests;
