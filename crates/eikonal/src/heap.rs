//! An indexed binary min-heap over cells: each cell is in the heap at most once and its key
//! can move in either direction (second-order updates may raise a tentative value).

const NONE: u32 = u32::MAX;

pub(crate) struct IndexedHeap {
    keys: Vec<f64>,
    items: Vec<u32>,
    /// Heap slot of each cell, or `NONE`.
    slot: Vec<u32>,
}

impl IndexedHeap {
    pub(crate) fn new(cells: usize) -> Self {
        Self {
            keys: Vec::with_capacity(1024),
            items: Vec::with_capacity(1024),
            slot: vec![NONE; cells],
        }
    }

    /// Inserts `item` with `key`, or moves it to `key` when it is already queued.
    #[inline]
    pub(crate) fn set(&mut self, item: u32, key: f64) {
        let s = self.slot[item as usize];
        if s == NONE {
            let k = self.keys.len();
            self.keys.push(key);
            self.items.push(item);
            self.slot[item as usize] = k as u32;
            self.sift_up(k);
        } else {
            let k = s as usize;
            let old = self.keys[k];
            self.keys[k] = key;
            if key < old {
                self.sift_up(k);
            } else {
                self.sift_down(k);
            }
        }
    }

    #[inline]
    pub(crate) fn pop(&mut self) -> Option<u32> {
        let top = *self.items.first()?;
        let last_key = self.keys.pop().expect("non-empty");
        let last_item = self.items.pop().expect("non-empty");
        self.slot[top as usize] = NONE;
        if !self.items.is_empty() {
            self.keys[0] = last_key;
            self.items[0] = last_item;
            self.slot[last_item as usize] = 0;
            self.sift_down(0);
        }
        Some(top)
    }

    #[inline]
    fn sift_up(&mut self, mut k: usize) {
        let key = self.keys[k];
        let item = self.items[k];
        while k > 0 {
            let parent = (k - 1) / 2;
            if self.keys[parent] <= key {
                break;
            }
            self.keys[k] = self.keys[parent];
            self.items[k] = self.items[parent];
            self.slot[self.items[k] as usize] = k as u32;
            k = parent;
        }
        self.keys[k] = key;
        self.items[k] = item;
        self.slot[item as usize] = k as u32;
    }

    #[inline]
    fn sift_down(&mut self, mut k: usize) {
        let n = self.keys.len();
        let key = self.keys[k];
        let item = self.items[k];
        loop {
            let left = 2 * k + 1;
            if left >= n {
                break;
            }
            let right = left + 1;
            let child = if right < n && self.keys[right] < self.keys[left] {
                right
            } else {
                left
            };
            if self.keys[child] >= key {
                break;
            }
            self.keys[k] = self.keys[child];
            self.items[k] = self.items[child];
            self.slot[self.items[k] as usize] = k as u32;
            k = child;
        }
        self.keys[k] = key;
        self.items[k] = item;
        self.slot[item as usize] = k as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_key_order_after_moves_both_ways() {
        let mut h = IndexedHeap::new(10);
        for (i, k) in [5.0, 3.0, 8.0, 1.0, 9.0, 7.0].iter().enumerate() {
            h.set(i as u32, *k);
        }
        h.set(2, 0.5); // decrease
        h.set(3, 10.0); // increase
        let order: Vec<u32> = std::iter::from_fn(|| h.pop()).collect();
        assert_eq!(order, vec![2, 1, 0, 5, 4, 3]);
    }
}
