//! Large read-mostly tables that rays touch at random — the BVH's nodes and the triangle cache —
//! in memory the kernel may back with 2 MiB transparent huge pages. A ray through a big scene
//! visits a dozen nodes and a few triangles scattered over tens of megabytes; with 4 KiB pages
//! nearly every one of those reads also misses the TLB, and a page walk costs as much as the
//! cache miss itself. On Linux a table of at least [`HUGE`] bytes is placed in an anonymous
//! mapping aligned to 2 MiB and advised `MADV_HUGEPAGE` (the kernel's default mode,
//! `madvise`, grants huge pages only to memory so advised); elsewhere, for smaller tables, or
//! when the mapping fails, it is an ordinary vector. The contents are the same either way.

use bytemuck::Pod;
use std::fmt;
use std::ops::{Deref, DerefMut};

/// The size of a transparent huge page on x86-64 and aarch64 Linux, and the least table size
/// placed in its own mapping.
pub const HUGE: usize = 2 << 20;

/// A fixed-length table of plain-old-data values.
pub struct PageVec<T: Pod> {
    store: Store<T>,
}

enum Store<T> {
    Heap(Vec<T>),
    #[cfg_attr(not(target_os = "linux"), allow(dead_code))]
    Mapped {
        map: memmap2::MmapMut,
        offset: usize,
        len: usize,
    },
}

impl<T: Pod> PageVec<T> {
    /// A copy of `values`.
    pub fn from_slice(values: &[T]) -> Self {
        let mut v = Self::zeroed(values.len());
        v.copy_from_slice(values);
        v
    }

    /// `len` zeroed values.
    pub fn zeroed(len: usize) -> Self {
        let bytes = len.saturating_mul(size_of::<T>());
        if bytes >= HUGE
            && let Some(store) = Self::mapped(len, bytes)
        {
            return Self { store };
        }
        Self { store: Store::Heap(vec![T::zeroed(); len]) }
    }

    #[cfg(target_os = "linux")]
    fn mapped(len: usize, bytes: usize) -> Option<Store<T>> {
        let map = memmap2::MmapMut::map_anon(bytes.checked_add(HUGE)?).ok()?;
        let offset = (HUGE - map.as_ptr() as usize % HUGE) % HUGE;
        // Advice the kernel cannot follow (no transparent huge pages) leaves ordinary pages.
        let _ = map.advise_range(memmap2::Advice::HugePage, offset, bytes);
        Some(Store::Mapped { map, offset, len })
    }

    #[cfg(not(target_os = "linux"))]
    fn mapped(_len: usize, _bytes: usize) -> Option<Store<T>> {
        None
    }

    /// Whether the table is in a mapping of its own (advised for huge pages).
    pub fn is_mapped(&self) -> bool {
        matches!(self.store, Store::Mapped { .. })
    }
}

impl<T: Pod> Deref for PageVec<T> {
    type Target = [T];
    #[inline(always)]
    fn deref(&self) -> &[T] {
        match &self.store {
            Store::Heap(v) => v,
            Store::Mapped { map, offset, len } => bytemuck::cast_slice(&map[*offset..*offset + *len * size_of::<T>()]),
        }
    }
}

impl<T: Pod> DerefMut for PageVec<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.store {
            Store::Heap(v) => v,
            Store::Mapped { map, offset, len } => {
                bytemuck::cast_slice_mut(&mut map[*offset..*offset + *len * size_of::<T>()])
            }
        }
    }
}

impl<T: Pod> Default for PageVec<T> {
    fn default() -> Self {
        Self { store: Store::Heap(Vec::new()) }
    }
}

impl<T: Pod> Clone for PageVec<T> {
    fn clone(&self) -> Self {
        Self::from_slice(self)
    }
}

impl<T: Pod> From<Vec<T>> for PageVec<T> {
    /// Moves a vector's values into a table (a copy only when the table gets a mapping).
    fn from(values: Vec<T>) -> Self {
        if values.len().saturating_mul(size_of::<T>()) >= HUGE {
            Self::from_slice(&values)
        } else {
            Self { store: Store::Heap(values) }
        }
    }
}

impl<T: Pod + fmt::Debug> fmt::Debug for PageVec<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PageVec").field("len", &self.len()).field("mapped", &self.is_mapped()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small tables stay on the heap; large ones get a mapping (on Linux) aligned to 2 MiB;
    /// both keep their values through construction, writes and clones.
    #[test]
    fn tables_keep_their_values_in_either_store() {
        for len in [0usize, 1, 1000, HUGE / 4 + 3] {
            let mut v = PageVec::zeroed(len);
            for (i, x) in v.iter_mut().enumerate() {
                *x = [i as u32, !(i as u32)];
            }
            assert_eq!(v.len(), len);
            assert_eq!(v.is_mapped(), cfg!(target_os = "linux") && len * 8 >= HUGE);
            if v.is_mapped() {
                assert_eq!(v.as_ptr() as usize % HUGE, 0);
            }
            assert!(v.iter().enumerate().all(|(i, x)| *x == [i as u32, !(i as u32)]));
            let mut c = v.clone();
            assert_eq!(&c[..], &v[..]);
            if len > 0 {
                c[len - 1] = [7, 7];
                assert_eq!(c[len - 1], [7, 7]);
                assert_ne!(v[len - 1], [7, 7]);
            }
            let from: PageVec<[u32; 2]> = v.to_vec().into();
            assert_eq!(&from[..], &v[..]);
            assert_eq!(from.is_mapped(), v.is_mapped());
        }
    }
}
