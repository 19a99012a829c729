//! The priority queue of fast marching: an indexed d-ary min-heap (d = `ARITY`, 2 or 4) of
//! packed `(value, cell)` words.
//!
//! Fast marching spends about half its time here, so the layout is tuned. A tentative value is
//! a non-negative f32, whose bit pattern orders like the value, so an entry is one `u64`
//! (`value_bits << 32 | cell`) and every comparison is an integer compare. Each cell is queued
//! at most once; a position table lets its value move in either direction (second-order updates
//! may raise a tentative value). `pop` walks the hole down to a leaf along the smallest
//! children before sifting the last entry up ("bottom-up" deletion), which saves most
//! comparisons because the last entry of a front belongs near the bottom; in a full 4-ary node
//! the smallest child comes from a tree of compares (pairs, then their winners), as each level
//! of that walk waits on the previous one's choice. The marcher picks the
//! arity by grid size: 2 on small grids, where it runs fewer instructions than 4 or 8; 4 on
//! large ones, where a pop is a chain of dependent loads and cache misses (one per level, each
//! moving an entry and rewriting its cell's record), so half the levels beat fewer
//! comparisons. The measurements are in `docs/notes/performance-history.md`.

/// Per-cell record of the marcher: the accepted value (infinity until accepted) and a tag
/// that is the cell's heap position while it is queued, or one of [`FAR`], [`BLOCKED`],
/// [`KNOWN`]. One 8-byte record per cell, so a stencil touches one cache line per neighbour
/// rather than one per array.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(8))]
pub(crate) struct Rec {
    pub known: f32,
    pub tag: u32,
}

/// Not reached yet.
pub(crate) const FAR: u32 = u32::MAX;
/// An obstacle, a zero-speed cell or padding: never entered.
pub(crate) const BLOCKED: u32 = u32::MAX - 1;
/// Accepted.
pub(crate) const KNOWN: u32 = u32::MAX - 2;

pub(crate) struct IndexedHeap<const ARITY: usize> {
    entries: Vec<u64>,
}

/// Packs a non-negative finite value and a cell index into one ordered word.
#[inline]
pub(crate) fn pack(value: f32, cell: u32) -> u64 {
    debug_assert!(value >= 0.0 && value.is_finite());
    ((value.to_bits() as u64) << 32) | cell as u64
}

/// The value and cell of a packed entry.
#[inline]
pub(crate) fn unpack(entry: u64) -> (f32, u32) {
    (f32::from_bits((entry >> 32) as u32), entry as u32)
}

impl<const ARITY: usize> IndexedHeap<ARITY> {
    pub(crate) fn new() -> Self {
        Self {
            entries: Vec::with_capacity(1024),
        }
    }

    /// Queues `cell` with `value`, or moves it to `value` when it is queued already (its tag
    /// is then its position).
    #[inline]
    pub(crate) fn set(&mut self, value: f32, cell: u32, recs: &mut [Rec]) {
        let entry = pack(value, cell);
        let s = recs[cell as usize].tag;
        if s >= KNOWN {
            let k = self.entries.len();
            self.entries.push(entry);
            self.sift_up(k, entry, recs);
        } else if entry < self.entries[s as usize] {
            self.sift_up(s as usize, entry, recs);
        } else {
            self.sift_down(s as usize, entry, recs);
        }
    }

    /// Puts `entry` at heap position `k < entries.len()`.
    #[inline]
    fn place(&mut self, k: usize, entry: u64, recs: &mut [Rec]) {
        debug_assert!(k < self.entries.len() && ((entry as u32) as usize) < recs.len());
        // SAFETY: callers pass a position inside the heap, and every entry's cell was checked
        // against `recs` when `set` queued it.
        unsafe {
            *self.entries.get_unchecked_mut(k) = entry;
            recs.get_unchecked_mut(entry as u32 as usize).tag = k as u32;
        }
    }

    /// The smallest child of `k`, when it has one.
    #[inline]
    fn min_child(&self, k: usize) -> Option<(usize, u64)> {
        let n = self.entries.len();
        let first = ARITY * k + 1;
        if first >= n {
            return None;
        }
        let e = &self.entries[..];
        if ARITY == 4 && first + 4 <= n {
            // A full node: a tree of compares (two levels) rather than a chain of three, as
            // the walk down the heap waits on each level's choice.
            // SAFETY: `first + 4 <= n == e.len()`.
            let (c0, c1, c2, c3) = unsafe {
                (
                    *e.get_unchecked(first),
                    *e.get_unchecked(first + 1),
                    *e.get_unchecked(first + 2),
                    *e.get_unchecked(first + 3),
                )
            };
            let (k01, b01) = if c1 < c0 {
                (first + 1, c1)
            } else {
                (first, c0)
            };
            let (k23, b23) = if c3 < c2 {
                (first + 3, c3)
            } else {
                (first + 2, c2)
            };
            return Some(if b23 < b01 { (k23, b23) } else { (k01, b01) });
        }
        let end = (first + ARITY).min(n);
        let mut best = first;
        // SAFETY: `first < end <= n == e.len()`.
        let mut best_key = unsafe { *e.get_unchecked(first) };
        for c in first + 1..end {
            // SAFETY: as above.
            let key = unsafe { *e.get_unchecked(c) };
            if key < best_key {
                best = c;
                best_key = key;
            }
        }
        Some((best, best_key))
    }

    #[inline]
    fn sift_down(&mut self, mut k: usize, entry: u64, recs: &mut [Rec]) {
        while let Some((child, key)) = self.min_child(k) {
            if key >= entry {
                break;
            }
            self.place(k, key, recs);
            k = child;
        }
        self.place(k, entry, recs);
    }

    /// The cell of the entry of smallest value, without removing it.
    #[inline]
    pub(crate) fn peek_cell(&self) -> Option<u32> {
        self.entries.first().map(|&e| e as u32)
    }

    /// Removes and returns the entry of smallest value. The caller retags its cell.
    #[inline]
    pub(crate) fn pop(&mut self, recs: &mut [Rec]) -> Option<u64> {
        let top = *self.entries.first()?;
        let last = self.entries.pop().expect("non-empty");
        if !self.entries.is_empty() {
            let mut hole = 0;
            while let Some((child, key)) = self.min_child(hole) {
                self.place(hole, key, recs);
                hole = child;
            }
            self.sift_up(hole, last, recs);
        }
        Some(top)
    }

    #[inline]
    fn sift_up(&mut self, mut k: usize, entry: u64, recs: &mut [Rec]) {
        while k > 0 {
            let parent = (k - 1) / ARITY;
            // SAFETY: `parent < k < entries.len()`.
            let p = unsafe { *self.entries.get_unchecked(parent) };
            if p <= entry {
                break;
            }
            self.place(k, p, recs);
            k = parent;
        }
        self.place(k, entry, recs);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_entries_order_like_their_values() {
        let vals = [0.0f32, 1e-30, 0.5, 1.0, 1.0000001, 3.5, 1e30];
        for w in vals.windows(2) {
            assert!(pack(w[0], 7) < pack(w[1], 0));
        }
        assert_eq!(unpack(pack(2.5, 42)), (2.5, 42));
    }

    #[test]
    fn pops_many_pseudo_random_keys_in_order_after_moves() {
        pops_in_order_after_moves::<2>();
        pops_in_order_after_moves::<4>();
    }

    fn pops_in_order_after_moves<const ARITY: usize>() {
        // Miri interprets every access: fewer keys there, the same code paths.
        let n = if cfg!(miri) { 300u32 } else { 5000 };
        let mut h = IndexedHeap::<ARITY>::new();
        let mut recs = vec![
            Rec {
                known: f32::INFINITY,
                tag: FAR
            };
            n as usize
        ];
        let key = |i: u32| ((i as u64 * 2_654_435_761) % 10_007) as f32;
        for i in 0..n {
            h.set(key(i) + 20_000.0, i, &mut recs);
        }
        for i in (0..n).step_by(3) {
            h.set(key(i), i, &mut recs); // lower a third of them
        }
        for i in (1..n).step_by(3) {
            h.set(key(i) + 40_000.0, i, &mut recs); // raise another third
        }
        let mut last = 0u64;
        let mut count = 0;
        while let Some(e) = h.pop(&mut recs) {
            recs[(e as u32) as usize].tag = KNOWN;
            let (v, i) = unpack(e);
            let expect = key(i) + [0.0, 40_000.0, 20_000.0][(i % 3) as usize];
            assert_eq!(v, expect);
            assert!(e >= last);
            last = e;
            count += 1;
        }
        assert_eq!(count, n);
    }
}
