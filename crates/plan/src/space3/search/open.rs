//! The search's open list and its set of opened points.
//!
//! Each expansion's candidates with finite values are kept in increasing value (ties in the
//! directions' order; the best first, the rest sorted when the second is asked for) in one
//! shared buffer; the heap holds each expansion's best candidate not yet taken, and taking
//! one puts its next on the heap. This is the order in which a list of every candidate would
//! give them up, at a fraction of the list's work: a clear descent takes one candidate per
//! expansion.

use envfield_grid::Point3m;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// FxHash's multiply-rotate over the opened set's keys (packed lattice cells, hashed once per
/// candidate): std's SipHash guards against chosen keys, which a search never meets, at
/// several times the cost.
#[derive(Default)]
struct LatticeHasher(u64);

impl LatticeHasher {
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
}

impl Hasher for LatticeHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.add(u64::from(b)));
    }
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
}

/// The lattice cell of `p` at spacing `cell` (rounded to the nearest), its three indices
/// packed in 21 bits each: cells 2^21 apart on an axis (kilometres at any step a body takes)
/// would share a key.
pub(super) fn lattice_key(p: Point3m, cell: f32) -> u64 {
    // Half away from zero, as f32::round, without a call into libm.
    let index = |v: f32| {
        let x = v / cell;
        (x + 0.5f32.copysign(x)) as i64 as u64 & 0x1F_FFFF
    };
    (index(p[0]) << 42) | (index(p[1]) << 21) | index(p[2])
}

/// The points opened so far, by their lattice cell of half a step: a point within `s / 2` of
/// one already opened is not opened again.
pub(super) struct Opened {
    cell: f32,
    keys: HashSet<u64, BuildHasherDefault<LatticeHasher>>,
}

impl Opened {
    /// No point opened, on a lattice of `cell`.
    pub(super) fn new(cell: f32) -> Self {
        Self {
            cell,
            keys: HashSet::default(),
        }
    }

    /// Whether a point in `p`'s cell was opened.
    #[inline]
    pub(super) fn contains(&self, p: Point3m) -> bool {
        self.keys.contains(&lattice_key(p, self.cell))
    }

    /// Marks `p`'s cell opened.
    #[inline]
    pub(super) fn insert(&mut self, p: Point3m) {
        self.keys.insert(lattice_key(p, self.cell));
    }
}

/// One expansion's candidates: `pending[first..first + len]`, from the opened point `parent`.
#[derive(Clone, Copy, Debug)]
struct Expansion {
    parent: usize,
    first: usize,
    len: usize,
    /// Whether `pending[first + 1..first + len]` is sorted yet (the best is first always).
    sorted: bool,
}

/// The open list: every expansion's candidates not yet taken, best first.
#[derive(Default)]
pub(super) struct OpenList {
    expansions: Vec<Expansion>,
    pending: Vec<(f32, Point3m)>,
    /// Each entry (value, expansion, candidate) packed into one ordered word: the heap's
    /// compares are then one integer compare, in the tuple's order.
    heap: BinaryHeap<Reverse<u128>>,
}

impl OpenList {
    /// The best candidate not yet taken and the opened point whose expansion gave it; `None`
    /// when every candidate was taken.
    #[inline]
    pub(super) fn pop(&mut self) -> Option<(Point3m, usize)> {
        let Reverse(entry) = self.heap.pop()?;
        let (e, k) = unpack_open(entry);
        let x = &mut self.expansions[e];
        if k + 1 < x.len {
            if !x.sorted {
                // Its second candidate is asked for: the rest is sorted now (most expansions
                // of a clear descent give up their best alone).
                self.pending[x.first + 1..x.first + x.len].sort_by(|a, b| a.0.total_cmp(&b.0));
                x.sorted = true;
            }
            let (v, _) = self.pending[x.first + k + 1];
            self.heap.push(Reverse(pack_open(v, e, k + 1)));
        }
        Some((self.pending[x.first + k].1, x.parent))
    }

    /// Puts the expansion of opened point `parent` on the list: its `candidates` with finite
    /// `values` (whether one was opened already is asked when it comes off the list: most
    /// never do).
    #[inline]
    pub(super) fn push(&mut self, parent: usize, candidates: &[Point3m], values: Vec<f32>) {
        let first = self.pending.len();
        self.pending.extend(
            candidates
                .iter()
                .zip(values)
                .filter(|&(_, v)| v.is_finite())
                .map(|(&c, v)| (v, c)),
        );
        let len = self.pending.len() - first;
        if len == 0 {
            return;
        }
        // The best candidate first (the first of the least values, where a stable sort puts
        // it), the rest in the directions' order until one of them is asked for, then sorted
        // stably: the order a stable sort of them all gives.
        let best = (first..self.pending.len())
            .min_by(|&a, &b| self.pending[a].0.total_cmp(&self.pending[b].0))
            .expect("a candidate");
        self.pending[first..=best].rotate_right(1);
        let e = self.expansions.len();
        self.heap
            .push(Reverse(pack_open(self.pending[first].0, e, 0)));
        self.expansions.push(Expansion {
            parent,
            first,
            len,
            sorted: len <= 2,
        });
    }
}

/// An open-list entry: `value` in `f32::total_cmp`'s order (its bits, the sign bit flipped
/// for positives and every bit for negatives), then the expansion `e` and its candidate `k`,
/// in one word ordered as the triple.
pub(super) fn pack_open(value: f32, e: usize, k: usize) -> u128 {
    let bits = value.to_bits();
    let ordered = if bits >> 31 == 1 {
        !bits
    } else {
        bits | 0x8000_0000
    };
    (u128::from(ordered) << 96) | ((e as u128) << 32) | k as u128
}

/// The expansion and candidate of an open-list entry ([`pack_open`]).
pub(super) fn unpack_open(entry: u128) -> (usize, usize) {
    (
        (entry >> 32) as u64 as usize,
        (entry & 0xFFFF_FFFF) as usize,
    )
}
