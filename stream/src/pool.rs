//! Where pages go in the pool: a best-fit allocator over the pool's bytes.
//!
//! Pages differ in size (a group's children: a few hundred bytes to tens of KiB), so
//! fixed slots would waste most of a pool sized for the largest. Best fit with free
//! ranges merged on release keeps the holes few; when no hole fits, the streamer evicts
//! and asks again.

use std::collections::{BTreeMap, BTreeSet};

/// Offsets and sizes are multiples of this many bytes: uploads need 4, and coarser
/// granules keep holes too small for any page from accumulating.
pub const ALIGNMENT: u64 = 256;

/// A range of the pool given to one page.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Allocation {
    /// First byte, a multiple of [`ALIGNMENT`].
    pub offset: u64,
    /// Bytes reserved: the page's size rounded up to [`ALIGNMENT`].
    pub bytes: u64,
}

/// The pool's free ranges.
#[derive(Debug, Clone)]
pub struct PoolAllocator {
    capacity: u64,
    used: u64,
    /// Free ranges by offset: offset → bytes.
    by_offset: BTreeMap<u64, u64>,
    /// The same ranges by (bytes, offset), for best fit.
    by_size: BTreeSet<(u64, u64)>,
}

impl PoolAllocator {
    /// A pool of `capacity` bytes (rounded down to [`ALIGNMENT`]), all free.
    pub fn new(capacity: u64) -> Self {
        let capacity = capacity / ALIGNMENT * ALIGNMENT;
        let mut pool = Self {
            capacity,
            used: 0,
            by_offset: BTreeMap::new(),
            by_size: BTreeSet::new(),
        };
        if capacity > 0 {
            pool.insert_free(0, capacity);
        }
        pool
    }

    /// Bytes of the pool.
    pub fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Bytes given out.
    pub fn used(&self) -> u64 {
        self.used
    }

    /// The largest free range: the largest page that fits without evicting.
    pub fn largest_free(&self) -> u64 {
        self.by_size.last().map_or(0, |&(bytes, _)| bytes)
    }

    /// `bytes` rounded up to [`ALIGNMENT`] (what an allocation of them reserves).
    pub fn reserved(bytes: u64) -> u64 {
        bytes.max(1).div_ceil(ALIGNMENT) * ALIGNMENT
    }

    /// Reserves room for `bytes` in the smallest free range that holds them, or `None`
    /// when no range does.
    pub fn allocate(&mut self, bytes: u64) -> Option<Allocation> {
        let bytes = Self::reserved(bytes);
        let &(size, offset) = self.by_size.range((bytes, 0)..).next()?;
        self.remove_free(offset, size);
        if size > bytes {
            self.insert_free(offset + bytes, size - bytes);
        }
        self.used += bytes;
        Some(Allocation { offset, bytes })
    }

    /// Gives `allocation` back, merged with the free ranges beside it.
    pub fn release(&mut self, allocation: Allocation) {
        let Allocation {
            mut offset,
            mut bytes,
        } = allocation;
        debug_assert!(offset + bytes <= self.capacity);
        self.used -= bytes;
        if let Some((&before, &size)) = self.by_offset.range(..offset).next_back()
            && before + size == offset
        {
            self.remove_free(before, size);
            offset = before;
            bytes += size;
        }
        if let Some(&size) = self.by_offset.get(&(offset + bytes)) {
            self.remove_free(offset + bytes, size);
            bytes += size;
        }
        self.insert_free(offset, bytes);
    }

    fn insert_free(&mut self, offset: u64, bytes: u64) {
        self.by_offset.insert(offset, bytes);
        self.by_size.insert((bytes, offset));
    }

    fn remove_free(&mut self, offset: u64, bytes: u64) {
        self.by_offset.remove(&offset);
        self.by_size.remove(&(bytes, offset));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn best_fit_takes_the_smallest_hole_and_release_merges_neighbours() {
        let mut pool = PoolAllocator::new(10 * ALIGNMENT + 7);
        assert_eq!(pool.capacity(), 10 * ALIGNMENT);
        let a = pool.allocate(ALIGNMENT).unwrap();
        let b = pool.allocate(3 * ALIGNMENT).unwrap();
        let c = pool.allocate(1).unwrap();
        assert_eq!(c.bytes, ALIGNMENT);
        let _d = pool.allocate(2 * ALIGNMENT).unwrap();
        assert_eq!(pool.used(), 7 * ALIGNMENT);
        pool.release(a);
        pool.release(c);
        // Holes of 1 (at 0), 1 (at 4) and 3 (at the end): a 1-granule page takes the
        // first of the smallest.
        assert_eq!(pool.allocate(ALIGNMENT).unwrap().offset, 0);
        assert!(pool.allocate(4 * ALIGNMENT).is_none());
        pool.release(b);
        // b (1..4) merged with the hole at 4: one range of 4.
        assert_eq!(pool.largest_free(), 4 * ALIGNMENT);
        assert_eq!(pool.allocate(4 * ALIGNMENT).unwrap().offset, ALIGNMENT);
    }

    proptest! {
        /// Allocations never overlap nor leave the pool, the used bytes add up, and
        /// releasing everything gives back one range of the whole pool.
        #[test]
        fn allocations_never_overlap(ops in prop::collection::vec((0u64..5000, any::<bool>()), 1..300)) {
            let mut pool = PoolAllocator::new(64 * ALIGNMENT);
            let mut live: Vec<Allocation> = Vec::new();
            for (bytes, release) in ops {
                if release && !live.is_empty() {
                    let a = live.swap_remove(bytes as usize % live.len());
                    pool.release(a);
                } else if let Some(a) = pool.allocate(bytes) {
                    prop_assert!(a.offset % ALIGNMENT == 0 && a.bytes >= bytes);
                    prop_assert!(a.offset + a.bytes <= pool.capacity());
                    for b in &live {
                        prop_assert!(a.offset + a.bytes <= b.offset || b.offset + b.bytes <= a.offset);
                    }
                    live.push(a);
                } else {
                    prop_assert!(pool.largest_free() < PoolAllocator::reserved(bytes));
                }
                prop_assert_eq!(pool.used(), live.iter().map(|a| a.bytes).sum::<u64>());
            }
            for a in live.drain(..) {
                pool.release(a);
            }
            prop_assert_eq!(pool.largest_free(), pool.capacity());
        }
    }
}
