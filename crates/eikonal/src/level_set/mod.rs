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
//! assert_eq!(d.values, [-1.75, -1.25, -0.75, -0.25, 0.25, 0.75, 1.25, 1.75]);
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
        let mut m = Marcher::new(self, options, Kind::Distance)?;
        m.march()?;
        Ok(m.finish())
    }

    /// The time the front leaving the zero contour takes to reach every cell at `speed` (one
    /// value per cell; cells slower than machine epsilon are not entered).
    ///
    /// # Errors
    /// As [`LevelSet::distance`], and for a `speed` of another length or a NaN speed.
    pub fn travel_time(&self, speed: &[f64], options: &LevelSetOptions) -> Result<Marched> {
        check_values(self.phi.len(), speed, "speed", false)?;
        let mut m = Marcher::new(self, options, Kind::Travel { speed })?;
        for (flag, &s) in m.flags.iter_mut().zip(speed) {
            if s < f64::EPSILON {
                *flag = MASK;
            }
        }
        m.march()?;
        Ok(m.finish())
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
        let kind = Kind::Extension {
            speed,
            ext_mask,
            velocity: vec![0.0; self.phi.len()],
        };
        let mut m = Marcher::new(self, options, kind)?;
        m.march()?;
        let velocity = match &mut m.kind {
            Kind::Extension { velocity, .. } => {
                let mut v = std::mem::take(velocity);
                for (v, &f) in v.iter_mut().zip(&m.flags) {
                    if f != FROZEN {
                        *v = f64::MAX;
                    }
                }
                v
            }
            _ => unreachable!("the marcher was made for extension"),
        };
        Ok(Extended {
            distance: m.finish(),
            velocity,
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

/// The grid's geometry: shape, strides, spacing and which axes wrap.
struct Geometry {
    nd: usize,
    shape: [usize; MAX_DIMENSIONS],
    stride: [usize; MAX_DIMENSIONS],
    dx: [f64; MAX_DIMENSIONS],
    /// `1 / dx^2` per axis.
    idx2: [f64; MAX_DIMENSIONS],
    periodic: [bool; MAX_DIMENSIONS],
}

impl Geometry {
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
        let mut g = Geometry {
            nd,
            shape: [1; MAX_DIMENSIONS],
            stride: [0; MAX_DIMENSIONS],
            dx: [1.0; MAX_DIMENSIONS],
            idx2: [1.0; MAX_DIMENSIONS],
            periodic: [false; MAX_DIMENSIONS],
        };
        g.shape[..nd].copy_from_slice(shape);
        let mut s = 1usize;
        for a in (0..nd).rev() {
            g.stride[a] = s;
            s = s
                .checked_mul(shape[a])
                .filter(|&n| n < u32::MAX as usize)
                .ok_or_else(|| invalid(format!("the {shape:?} grid has too many cells")))?;
        }
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
                g.dx[a] = d;
                g.idx2[a] = 1.0 / d / d;
            }
        }
        if !options.periodic.is_empty() {
            if options.periodic.len() != nd {
                return Err(invalid(format!(
                    "periodic names {} axes for a grid of {nd} axes",
                    options.periodic.len()
                )));
            }
            g.periodic[..nd].copy_from_slice(&options.periodic);
        }
        Ok(g)
    }

    fn cells(&self) -> usize {
        self.stride[0] * self.shape[0]
    }

    #[inline]
    fn coords(&self, i: usize) -> [usize; MAX_DIMENSIONS] {
        let mut c = [0; MAX_DIMENSIONS];
        let mut rem = i;
        for a in 0..self.nd - 1 {
            c[a] = rem / self.stride[a];
            rem -= c[a] * self.stride[a];
        }
        c[self.nd - 1] = rem;
        c
    }

    /// The cell `step` cells from `i` (at `c`) along `axis`: wrapped on a periodic axis,
    /// `None` off the grid.
    #[inline]
    fn step(
        &self,
        i: usize,
        c: &[usize; MAX_DIMENSIONS],
        axis: usize,
        step: isize,
    ) -> Option<usize> {
        let n = self.shape[axis] as isize;
        let to = c[axis] as isize + step;
        if self.periodic[axis] {
            let w = to.rem_euclid(n);
            return Some(i - c[axis] * self.stride[axis] + w as usize * self.stride[axis]);
        }
        if to < 0 || to >= n {
            return None;
        }
        Some((i as isize + step * self.stride[axis] as isize) as usize)
    }
}

enum Kind<'a> {
    Distance,
    Travel {
        speed: &'a [f64],
    },
    Extension {
        speed: &'a [f64],
        ext_mask: Option<&'a [bool]>,
        velocity: Vec<f64>,
    },
}

struct Marcher<'a> {
    g: Geometry,
    phi: &'a [f64],
    flags: Vec<u8>,
    dist: Vec<f64>,
    order: Order,
    narrow: f64,
    self_test: bool,
    kind: Kind<'a>,
}

/// Second-order weights: `(3/2)^2` and one third.
const AA: f64 = 9.0 / 4.0;
const ONE_THIRD: f64 = 1.0 / 3.0;

impl<'a> Marcher<'a> {
    fn new(set: &LevelSet<'a>, options: &LevelSetOptions, kind: Kind<'a>) -> Result<Self> {
        let g = Geometry::new(set.shape, options)?;
        let n = g.cells();
        check_values(n, set.phi, "phi", false)
            .map_err(|e| invalid(format!("{e} (the grid is {:?})", set.shape)))?;
        if !(options.narrow >= 0.0) {
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
        Ok(Self {
            g,
            phi: set.phi,
            flags,
            dist: vec![0.0; n],
            order: options.order,
            narrow: options.narrow,
            self_test: options.self_test,
            kind,
        })
    }

    fn finish(self) -> Marched {
        let reached: Vec<bool> = self.flags.iter().map(|&f| f == FROZEN).collect();
        let mut values = self.dist;
        for (v, &r) in values.iter_mut().zip(&reached) {
            if !r {
                *v = f64::MAX;
            }
        }
        Marched { values, reached }
    }

    /// A neighbour `step` cells along `axis`, unless it is off the grid or (on an axis that
    /// does not wrap) flagged `unless`.
    #[inline]
    fn neighbour(
        &self,
        i: usize,
        c: &[usize; MAX_DIMENSIONS],
        axis: usize,
        step: isize,
        unless: u8,
    ) -> Option<usize> {
        let n = self.g.step(i, c, axis, step)?;
        if !self.g.periodic[axis] && self.flags[n] == unless {
            return None;
        }
        Some(n)
    }

    /// A frozen neighbour `step` cells along `axis`.
    #[inline]
    fn frozen(
        &self,
        i: usize,
        c: &[usize; MAX_DIMENSIONS],
        axis: usize,
        step: isize,
    ) -> Option<usize> {
        self.neighbour(i, c, axis, step, MASK)
            .filter(|&n| self.flags[n] == FROZEN)
    }

    fn march(&mut self) -> Result<()> {
        self.freeze_contour()?;
        let mut heap = Heap::new(self.flags.len(), self.self_test);
        self.first_band(&mut heap)?;
        if !self.flags.contains(&FROZEN) {
            return Err(EikonalError::NoZeroContour);
        }
        let mut batch = Vec::new();
        while let Some((cell, value)) = heap.pop()? {
            if self.narrow != 0.0 && value > self.narrow {
                break;
            }
            batch.clear();
            self.freeze(cell)?;
            batch.push(cell);
            while heap.peek() == Some(value) {
                let (cell, _) = heap.pop()?.expect("peeked");
                self.freeze(cell)?;
                batch.push(cell);
            }
            for &cell in &batch {
                self.update_around(cell, &mut heap)?;
            }
        }
        Ok(())
    }

    fn freeze(&mut self, i: usize) -> Result<()> {
        self.flags[i] = FROZEN;
        if matches!(self.kind, Kind::Extension { .. }) {
            self.extend_to(i)?;
        }
        Ok(())
    }

    /// Updates the neighbours of a newly frozen cell (and, at second order, the cells two
    /// steps out beyond a frozen neighbour).
    fn update_around(&mut self, cell: usize, heap: &mut Heap) -> Result<()> {
        let c = self.g.coords(cell);
        for axis in 0..self.g.nd {
            for step in [-1isize, 1] {
                if let Some(n) = self.neighbour(cell, &c, axis, step, FROZEN) {
                    match self.flags[n] {
                        NARROW => {
                            let d = self.update(n)?;
                            if d != 0.0 {
                                heap.set(n, d.abs())?;
                                self.dist[n] = d;
                            }
                        }
                        FAR => {
                            let d = self.update(n)?;
                            if d != 0.0 {
                                self.dist[n] = d;
                                self.flags[n] = NARROW;
                                heap.push(n, d.abs())?;
                            }
                        }
                        _ => {}
                    }
                }
                if self.order == Order::Second && self.frozen(cell, &c, axis, step).is_some() {
                    if let Some(n2) = self.neighbour(cell, &c, axis, 2 * step, FROZEN) {
                        if self.flags[n2] == NARROW {
                            let d = self.update_second(n2)?;
                            if d != 0.0 {
                                heap.set(n2, d.abs())?;
                                self.dist[n2] = d;
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// The far cells beside the frozen contour, queued with their first values.
    fn first_band(&mut self, heap: &mut Heap) -> Result<()> {
        for i in 0..self.flags.len() {
            if self.flags[i] != FAR {
                continue;
            }
            let c = self.g.coords(i);
            let touches = (0..self.g.nd).any(|axis| {
                [-1, 1]
                    .iter()
                    .any(|&s| self.frozen(i, &c, axis, s).is_some())
            });
            if touches {
                self.flags[i] = NARROW;
                let d = self.update(i)?;
                self.dist[i] = d;
                heap.push(i, d.abs())?;
            }
        }
        Ok(())
    }

    fn update(&self, i: usize) -> Result<f64> {
        match self.order {
            Order::First => Ok(self.update_first(i)),
            Order::Second => self.update_second(i),
        }
    }

    /// The right root of `a t^2 + b t + c = rhs` for cell `i`: the distance takes the root on
    /// `phi`'s side, the travel time the larger; `None` without a real root.
    #[inline]
    fn quadratic(&self, i: usize, a: f64, b: f64, c: f64) -> Option<f64> {
        let (c, larger) = match &self.kind {
            Kind::Travel { speed } => (c - 1.0 / (speed[i] * speed[i]), true),
            _ => (c - 1.0, self.phi[i] > f64::EPSILON),
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

    fn update_first(&self, i: usize) -> f64 {
        let c = self.g.coords(i);
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..self.g.nd {
            let mut value = f64::MAX;
            for step in [-1, 1] {
                if let Some(n) = self.frozen(i, &c, axis, step) {
                    if self.dist[n].abs() < value.abs() {
                        value = self.dist[n];
                    }
                }
            }
            if value < f64::MAX {
                let w = self.g.idx2[axis];
                a += w;
                b -= w * 2.0 * value;
                cc += w * (value * value);
            }
        }
        // Without a real root, the minimum of the quadratic is the nearer answer.
        self.quadratic(i, a, b, cc).unwrap_or(-b / (2.0 * a))
    }

    fn update_second(&self, i: usize) -> Result<f64> {
        if let Kind::Travel { .. } = self.kind {
            let t = self.travel_second(i, 0);
            if t == f64::INFINITY {
                return Err(invalid(format!(
                    "no second-order update reaches flat index {i}"
                )));
            }
            return Ok(t);
        }
        let c = self.g.coords(i);
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..self.g.nd {
            let (v1, v2) = self.upwind_pair(i, &c, axis, false);
            self.accumulate(axis, v1, v2, &mut a, &mut b, &mut cc);
        }
        Ok(self
            .quadratic(i, a, b, cc)
            .unwrap_or_else(|| self.update_first(i)))
    }

    /// Along `axis`: the frozen neighbour nearest the contour, and the frozen cell beyond it
    /// where it is no nearer (`f64::MAX` for either when missing). The travel time counts the
    /// far cell negative when `phi` changes sign on the way.
    #[inline]
    fn upwind_pair(
        &self,
        i: usize,
        c: &[usize; MAX_DIMENSIONS],
        axis: usize,
        travel: bool,
    ) -> (f64, f64) {
        let mut v1 = f64::MAX;
        let mut v2 = f64::MAX;
        for step in [-1, 1] {
            let Some(n) = self.frozen(i, c, axis, step) else {
                continue;
            };
            if self.dist[n].abs() < v1.abs() {
                v1 = self.dist[n];
                if let Some(n2) = self.frozen(i, c, axis, 2 * step) {
                    let d2 = self.dist[n2];
                    if (d2 <= v1 && v1 >= 0.0) || (d2 >= v1 && v1 <= 0.0) {
                        v2 = d2;
                        if travel
                            && (self.phi[n2] * self.phi[n] < 0.0
                                || self.phi[n2] * self.phi[i] < 0.0)
                        {
                            v2 = -v2;
                        }
                    }
                }
            }
        }
        (v1, v2)
    }

    #[inline]
    fn accumulate(&self, axis: usize, v1: f64, v2: f64, a: &mut f64, b: &mut f64, c: &mut f64) {
        let w = self.g.idx2[axis];
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
        let c = self.g.coords(i);
        let (mut a, mut b, mut cc) = (0.0, 0.0, 0.0);
        for axis in 0..self.g.nd {
            if avoid & (1 << axis) != 0 {
                continue;
            }
            let (v1, v2) = self.upwind_pair(i, &c, axis, true);
            self.accumulate(axis, v1, v2, &mut a, &mut b, &mut cc);
        }
        if let Some(t) = self.quadratic(i, a, b, cc) {
            return t;
        }
        if avoid.count_ones() as usize == self.g.nd {
            return f64::INFINITY;
        }
        let mut best: Option<f64> = None;
        for axis in 0..self.g.nd {
            if avoid & (1 << axis) != 0 {
                continue;
            }
            let t = self.travel_second(i, avoid | (1 << axis));
            // The first answer stands unless a later one is smaller (as std::min_element).
            best = Some(match best {
                Some(b) if !(t < b) => b,
                _ => t,
            });
        }
        best.unwrap_or(f64::INFINITY)
    }

    /// Freezes the cells on the zero contour and beside it.
    fn freeze_contour(&mut self) -> Result<()> {
        let n = self.flags.len();
        let speed = match &self.kind {
            Kind::Extension { speed, .. } => Some(*speed),
            _ => None,
        };
        for i in 0..n {
            if self.flags[i] != MASK && self.phi[i] == 0.0 {
                self.flags[i] = FROZEN;
                self.dist[i] = 0.0;
                if let (Some(s), Kind::Extension { velocity, .. }) = (speed, &mut self.kind) {
                    velocity[i] = s[i];
                }
            }
        }
        for i in 0..n {
            if self.flags[i] != FAR {
                continue;
            }
            let c = self.g.coords(i);
            let p = self.phi[i];
            let mut ldist = [0.0f64; MAX_DIMENSIONS];
            let mut lspeed = [0.0f64; MAX_DIMENSIONS];
            let mut borders = false;
            for axis in 0..self.g.nd {
                for step in [-1, 1] {
                    let Some(nb) = self.neighbour(i, &c, axis, step, MASK) else {
                        continue;
                    };
                    let q = self.phi[nb];
                    if p * q < 0.0 {
                        borders = true;
                        let d = self.g.dx[axis] * p / (p - q);
                        if ldist[axis] == 0.0 || ldist[axis] > d {
                            ldist[axis] = d;
                            if let Kind::Extension {
                                speed, ext_mask, ..
                            } = &self.kind
                            {
                                let masked = |k: usize| ext_mask.is_some_and(|m| m[k]);
                                lspeed[axis] = if masked(i) {
                                    speed[nb]
                                } else if masked(nb) {
                                    speed[i]
                                } else {
                                    speed[i] + d / self.g.dx[axis] * (speed[nb] - speed[i])
                                };
                            }
                        }
                    }
                }
            }
            if !borders {
                continue;
            }
            if let Kind::Extension { velocity, .. } = &mut self.kind {
                let (mut num, mut den) = (0.0, 0.0);
                for axis in 0..self.g.nd {
                    if ldist[axis] != 0.0 {
                        let w = 1.0 / (ldist[axis] * ldist[axis]);
                        num += lspeed[axis] * w;
                        den += w;
                    }
                }
                if den == 0.0 {
                    return Err(invalid(format!(
                        "the extension velocity on the contour at flat index {i} divides by zero"
                    )));
                }
                velocity[i] = num / den;
            }
            let mut dsum = 0.0;
            for &d in &ldist[..self.g.nd] {
                if d > 0.0 {
                    dsum += 1.0 / d / d;
                }
            }
            let d = (1.0 / dsum).sqrt();
            self.dist[i] = match self.kind {
                Kind::Travel { speed } => (d / speed[i]).abs(),
                _ if p < 0.0 => -d,
                _ => d,
            };
            self.flags[i] = FROZEN;
        }
        Ok(())
    }

    /// The extension velocity of a newly frozen cell from its frozen neighbours, weighted by
    /// how far each lies upwind (grad v . grad d = 0).
    fn extend_to(&mut self, i: usize) -> Result<()> {
        let c = self.g.coords(i);
        let (mut num, mut den) = (0.0, 0.0);
        let Kind::Extension { velocity, .. } = &self.kind else {
            return Ok(());
        };
        for axis in 0..self.g.nd {
            let mut ld = 0.0f64;
            let mut ls = 0.0f64;
            for step in [-1, 1] {
                if let Some(n) = self.frozen(i, &c, axis, step) {
                    let d = self.dist[i] - self.dist[n];
                    if (ld == 0.0 || ld > d) && d.abs() > f64::EPSILON {
                        ld = d;
                        ls = velocity[n];
                    }
                }
            }
            num += ld.abs() * ls * self.g.idx2[axis];
            den += ld.abs() * self.g.idx2[axis];
        }
        if den == 0.0 {
            return Err(invalid(format!(
                "the extension velocity at flat index {i} divides by zero: no frozen neighbour \
                 lies upwind"
            )));
        }
        if let Kind::Extension { velocity, .. } = &mut self.kind {
            velocity[i] = num / den;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
