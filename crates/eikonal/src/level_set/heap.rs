//! The level-set marcher's priority queue: an indexed 4-ary min-heap of `(value, cell)`, its
//! positions kept in the cells' own records.
//!
//! Values are non-negative (absolute distances, times), so their bit patterns order like the
//! values and every comparison is an integer compare. A queued value may move either way
//! (second-order updates may raise one). `pop` walks the hole at the top down to a leaf along
//! the smallest children, then sifts the last entry up from there ("bottom-up" deletion: the
//! last entry of a front belongs near the bottom, so this saves most comparisons). Which of
//! equal values comes first does not matter: the marcher freezes ties together.

use super::Rec;
use crate::{EikonalError, Result};

const ARITY: usize = 4;

#[derive(Clone, Copy)]
struct Entry {
    /// The value's magnitude, as bits.
    key: u64,
    cell: u32,
    /// Whether the value is negative (a signed distance inside the contour): the queue hands
    /// the signed value back without a second array.
    negative: bool,
}

impl Entry {
    #[inline(always)]
    fn new(cell: usize, value: f64) -> Self {
        Entry {
            key: key(value.abs()),
            cell: cell as u32,
            negative: value < 0.0,
        }
    }

    #[inline(always)]
    fn value(self) -> f64 {
        let v = f64::from_bits(self.key);
        if self.negative {
            -v
        } else {
            v
        }
    }
}

pub(super) struct Heap {
    entries: Vec<Entry>,
}

#[inline(always)]
fn key(value: f64) -> u64 {
    // Non-negative values (and +0 for -0) order as their bits; NaN sorts last.
    (value + 0.0).to_bits()
}

impl Heap {
    pub(super) fn new() -> Self {
        Self {
            entries: Vec::with_capacity(4096),
        }
    }

    /// Queues `cell`, which is not queued, with the signed `value` (ordered by magnitude).
    #[inline]
    pub(super) fn push(&mut self, cell: usize, value: f64, recs: &mut [Rec]) {
        let k = self.entries.len();
        let e = Entry::new(cell, value);
        self.entries.push(e);
        self.sift_up(k, e, recs);
    }

    /// Moves queued `cell` to the signed `value`.
    #[inline]
    pub(super) fn set(&mut self, cell: usize, value: f64, recs: &mut [Rec]) {
        let k = recs[cell].pos as usize;
        let e = Entry::new(cell, value);
        if e.key < self.entries[k].key {
            self.sift_up(k, e, recs);
        } else {
            self.sift_down(k, e, recs);
        }
    }

    /// The smallest magnitude queued.
    #[inline]
    pub(super) fn peek(&self) -> Option<f64> {
        self.entries.first().map(|e| f64::from_bits(e.key))
    }

    /// The cell of the smallest value queued.
    #[inline]
    pub(super) fn peek_cell(&self) -> Option<usize> {
        self.entries.first().map(|e| e.cell as usize)
    }

    /// Takes the `(cell, signed value)` of the smallest magnitude off the queue.
    #[inline]
    pub(super) fn pop(&mut self, recs: &mut [Rec]) -> Option<(usize, f64)> {
        let top = *self.entries.first()?;
        let last = self.entries.pop().expect("not empty");
        let n = self.entries.len();
        if n > 0 {
            // The hole walks down along the smallest children to a leaf...
            let mut k = 0;
            loop {
                let first = k * ARITY + 1;
                if first >= n {
                    break;
                }
                let best = self.smallest_child(first, n);
                let child = self.entries[best];
                self.place(k, child, recs);
                k = best;
            }
            // ...and the last entry rises from there to its place.
            self.sift_up(k, last, recs);
        }
        Some((top.cell as usize, top.value()))
    }

    #[inline(always)]
    fn smallest_child(&self, first: usize, n: usize) -> usize {
        if first + ARITY <= n {
            let c = &self.entries[first..first + ARITY];
            let a = if c[1].key < c[0].key { 1 } else { 0 };
            let b = if c[3].key < c[2].key { 3 } else { 2 };
            first + if c[b].key < c[a].key { b } else { a }
        } else {
            let mut best = first;
            for c in first + 1..n {
                if self.entries[c].key < self.entries[best].key {
                    best = c;
                }
            }
            best
        }
    }

    #[inline(always)]
    fn place(&mut self, k: usize, e: Entry, recs: &mut [Rec]) {
        self.entries[k] = e;
        recs[e.cell as usize].pos = k as u32;
    }

    #[inline]
    fn sift_up(&mut self, mut k: usize, e: Entry, recs: &mut [Rec]) {
        while k > 0 {
            let parent = (k - 1) / ARITY;
            let p = self.entries[parent];
            if e.key >= p.key {
                break;
            }
            self.place(k, p, recs);
            k = parent;
        }
        self.place(k, e, recs);
    }

    #[inline]
    fn sift_down(&mut self, mut k: usize, e: Entry, recs: &mut [Rec]) {
        let n = self.entries.len();
        loop {
            let first = k * ARITY + 1;
            if first >= n {
                break;
            }
            let best = self.smallest_child(first, n);
            if self.entries[best].key >= e.key {
                break;
            }
            let child = self.entries[best];
            self.place(k, child, recs);
            k = best;
        }
        self.place(k, e, recs);
    }

    /// Checks that every entry is no smaller than its parent and that its cell's record points
    /// at it (the `self_test` option, after every operation).
    pub(super) fn check(&self, recs: &[Rec]) -> Result<()> {
        for (k, e) in self.entries.iter().enumerate() {
            let pos = recs[e.cell as usize].pos as usize;
            if pos != k {
                return Err(EikonalError::March(format!(
                    "heap self-test: cell {} at position {k} is recorded at {pos}",
                    e.cell
                )));
            }
            if k > 0 && self.entries[(k - 1) / ARITY].key > e.key {
                return Err(EikonalError::March(format!(
                    "heap self-test: position {k} is smaller than its parent"
                )));
            }
        }
        Ok(())
    }
}
