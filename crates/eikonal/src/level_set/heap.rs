//! The level-set marcher's priority queue: an indexed 4-ary min-heap of `(value, cell)`.
//!
//! Values are non-negative (absolute distances, times), so their bit patterns order like the
//! values and every comparison is an integer compare. A position table lets a queued value
//! move either way (second-order updates may raise one).

use crate::{EikonalError, Result};

const ARITY: usize = 4;
const ABSENT: u32 = u32::MAX;

#[derive(Clone, Copy)]
struct Entry {
    key: u64,
    cell: u32,
}

pub(super) struct Heap {
    entries: Vec<Entry>,
    position: Vec<u32>,
    self_test: bool,
}

#[inline]
fn key(value: f64) -> u64 {
    // Non-negative values (and +0 for -0) order as their bits; NaN sorts last.
    (value + 0.0).to_bits()
}

impl Heap {
    pub(super) fn new(cells: usize, self_test: bool) -> Self {
        Self {
            entries: Vec::with_capacity(1024),
            position: vec![ABSENT; cells],
            self_test,
        }
    }

    /// Queues `cell`, which is not queued, with `value`.
    pub(super) fn push(&mut self, cell: usize, value: f64) -> Result<()> {
        debug_assert_eq!(self.position[cell], ABSENT);
        let k = self.entries.len();
        let e = Entry {
            key: key(value),
            cell: cell as u32,
        };
        self.entries.push(e);
        self.sift_up(k, e);
        self.test()
    }

    /// Moves queued `cell` to `value`.
    pub(super) fn set(&mut self, cell: usize, value: f64) -> Result<()> {
        let k = self.position[cell];
        if k == ABSENT {
            return Err(EikonalError::LevelSet(format!(
                "internal: cell {cell} updated in the queue but not queued"
            )));
        }
        let k = k as usize;
        let e = Entry {
            key: key(value),
            cell: cell as u32,
        };
        if e.key < self.entries[k].key {
            self.sift_up(k, e);
        } else {
            self.sift_down(k, e);
        }
        self.test()
    }

    /// The smallest value queued.
    #[inline]
    pub(super) fn peek(&self) -> Option<f64> {
        self.entries.first().map(|e| f64::from_bits(e.key))
    }

    /// Takes the smallest `(cell, value)` off the queue.
    pub(super) fn pop(&mut self) -> Result<Option<(usize, f64)>> {
        let Some(&top) = self.entries.first() else {
            return Ok(None);
        };
        self.position[top.cell as usize] = ABSENT;
        let last = self.entries.pop().expect("not empty");
        if !self.entries.is_empty() {
            self.sift_down(0, last);
        }
        self.test()?;
        Ok(Some((top.cell as usize, f64::from_bits(top.key))))
    }

    #[inline]
    fn place(&mut self, k: usize, e: Entry) {
        self.entries[k] = e;
        self.position[e.cell as usize] = k as u32;
    }

    fn sift_up(&mut self, mut k: usize, e: Entry) {
        while k > 0 {
            let parent = (k - 1) / ARITY;
            let p = self.entries[parent];
            if e.key >= p.key {
                break;
            }
            self.place(k, p);
            k = parent;
        }
        self.place(k, e);
    }

    fn sift_down(&mut self, mut k: usize, e: Entry) {
        let n = self.entries.len();
        loop {
            let first = k * ARITY + 1;
            if first >= n {
                break;
            }
            let end = (first + ARITY).min(n);
            let mut best = first;
            let mut best_key = self.entries[first].key;
            for c in first + 1..end {
                let ck = self.entries[c].key;
                if ck < best_key {
                    best = c;
                    best_key = ck;
                }
            }
            if best_key >= e.key {
                break;
            }
            let child = self.entries[best];
            self.place(k, child);
            k = best;
        }
        self.place(k, e);
    }

    /// With `self_test`, checks that every entry is no smaller than its parent and that the
    /// position table points at it.
    fn test(&self) -> Result<()> {
        if !self.self_test {
            return Ok(());
        }
        for (k, e) in self.entries.iter().enumerate() {
            if self.position[e.cell as usize] as usize != k {
                return Err(EikonalError::LevelSet(format!(
                    "heap self-test: cell {} at position {k} is recorded at {}",
                    e.cell, self.position[e.cell as usize]
                )));
            }
            if k > 0 && self.entries[(k - 1) / ARITY].key > e.key {
                return Err(EikonalError::LevelSet(format!(
                    "heap self-test: position {k} is smaller than its parent"
                )));
            }
        }
        Ok(())
    }
}
