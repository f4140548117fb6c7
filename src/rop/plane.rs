//! One per-pixel plane of a frame buffer (colour, depth, winner or normal), in memory that
//! a fresh frame does not fault in page by page.
//!
//! A 1024x1024 frame's planes are 11.5 MB: taken from the allocator they are 2 800 4 KiB
//! pages, each faulted in (and zeroed by the kernel) on its first write, which measured
//! 7.6 ms of a fresh process's frame (median of 9; 2.0 ms with huge pages). So on Linux a
//! plane of 2 MiB or more is mapped on a 2 MiB boundary and advised as a transparent huge
//! page (`madvise(MADV_HUGEPAGE)`), and is faulted in 2 MiB at a time. Where the kernel gives
//! no huge pages (`/sys/kernel/mm/transparent_hugepage/enabled` set to `never`) the mapping
//! is ordinary pages and only slower. Smaller planes, and other systems, use a `Vec`.
//!
//! A mapped plane starts as the kernel's zero pages, so [`Plane::zeroed`] touches nothing:
//! `frame::bands` clears each band's rows on the thread that draws them.

use std::ops::{Deref, DerefMut};

/// What a plane holds: plain values for which all-zero bits are a valid value.
///
/// # Safety
/// All-zero bits must be a valid value of the type.
pub unsafe trait PlaneValue:
    Copy + Default + PartialEq + std::fmt::Debug + Send + Sync
{
}

// SAFETY: all-zero bits are a valid value of each of these.
unsafe impl PlaneValue for [u8; 3] {}
unsafe impl PlaneValue for f32 {}
unsafe impl PlaneValue for u32 {}
unsafe impl PlaneValue for [f32; 3] {}

/// A plane of `len` values.
pub struct Plane<T: PlaneValue> {
    storage: Storage<T>,
}

enum Storage<T> {
    Vec(Vec<T>),
    #[cfg(target_os = "linux")]
    Mapped(mapped::Mapping<T>),
}

impl<T: PlaneValue> Plane<T> {
    /// `len` copies of `value`.
    pub fn filled(len: usize, value: T) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(mut m) = mapped::Mapping::new(len) {
            fill(m.as_mut_slice(), value);
            return Plane {
                storage: Storage::Mapped(m),
            };
        }
        Plane {
            storage: Storage::Vec(vec![value; len]),
        }
    }

    /// `len` zero values; a mapped plane is not touched until it is written.
    pub fn zeroed(len: usize) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(m) = mapped::Mapping::new(len) {
            return Plane {
                storage: Storage::Mapped(m),
            };
        }
        Plane {
            storage: Storage::Vec(vec![T::default(); len]),
        }
    }
}

/// Values [`fill`] writes one by one before it copies them as a block.
const FILL_BLOCK: usize = 1024;

/// `slice.fill(value)`, as fast for a 3-byte colour as for a word: the first
/// `FILL_BLOCK` values are written one by one, and the rest copied from them a block at a
/// time (`fill` stores an `[u8; 3]` three bytes at a time; a copy moves whole vectors).
pub fn fill<T: PlaneValue>(slice: &mut [T], value: T) {
    let (first, rest) = slice.split_at_mut(FILL_BLOCK.min(slice.len()));
    first.fill(value);
    for chunk in rest.chunks_mut(FILL_BLOCK) {
        chunk.copy_from_slice(&first[..chunk.len()]);
    }
}

impl<T: PlaneValue> Deref for Plane<T> {
    type Target = [T];
    #[inline(always)]
    fn deref(&self) -> &[T] {
        match &self.storage {
            Storage::Vec(v) => v,
            #[cfg(target_os = "linux")]
            Storage::Mapped(m) => m.as_slice(),
        }
    }
}

impl<T: PlaneValue> DerefMut for Plane<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        match &mut self.storage {
            Storage::Vec(v) => v,
            #[cfg(target_os = "linux")]
            Storage::Mapped(m) => m.as_mut_slice(),
        }
    }
}

impl<T: PlaneValue> Clone for Plane<T> {
    fn clone(&self) -> Self {
        let mut p = Plane::zeroed(self.len());
        p.copy_from_slice(self);
        p
    }
}

impl<T: PlaneValue> PartialEq for Plane<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T: PlaneValue> std::fmt::Debug for Plane<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        (**self).fmt(f)
    }
}

impl<T: PlaneValue> From<Plane<T>> for Vec<T> {
    fn from(p: Plane<T>) -> Vec<T> {
        match p.storage {
            Storage::Vec(v) => v,
            #[cfg(target_os = "linux")]
            Storage::Mapped(m) => m.as_slice().to_vec(),
        }
    }
}

#[cfg(target_os = "linux")]
mod mapped {
    use super::PlaneValue;
    use std::marker::PhantomData;
    use std::ptr::NonNull;

    /// A transparent huge page's size on x86-64 and arm64 \[bytes\].
    const HUGE: usize = 2 << 20;

    /// `len` values in an anonymous private mapping on a [`HUGE`] boundary, advised as huge
    /// pages. Owns the mapping: one huge page more than the values' whole huge pages, so
    /// that a boundary lies within its first; the slack either side of the values is never
    /// touched, so it takes address space, not memory, and is unmapped with the rest.
    pub struct Mapping<T> {
        ptr: NonNull<T>,
        len: usize,
        /// Where the mapping starts, and its bytes.
        base: NonNull<libc::c_void>,
        span: usize,
        _values: PhantomData<T>,
    }

    // SAFETY: a Mapping owns its memory as a Vec<T> does.
    unsafe impl<T: Send> Send for Mapping<T> {}
    // SAFETY: shared access only reads, as for &[T].
    unsafe impl<T: Sync> Sync for Mapping<T> {}

    impl<T: PlaneValue> Mapping<T> {
        /// A mapping of `len` zero values, or `None` for a plane under one huge page or a
        /// mapping the system refuses (the caller falls back to a `Vec`).
        pub fn new(len: usize) -> Option<Self> {
            let size = len.checked_mul(std::mem::size_of::<T>())?;
            if size < HUGE {
                return None;
            }
            let bytes = size.checked_next_multiple_of(HUGE)?;
            let span = bytes.checked_add(HUGE)?;
            // SAFETY: a fresh anonymous private mapping; no memory is aliased.
            let base = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    span,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                    -1,
                    0,
                )
            };
            if base == libc::MAP_FAILED {
                return None;
            }
            // The values start at the first huge-page boundary in the span: `bytes` fit after
            // it, since the span is a huge page longer.
            let head = (HUGE - base as usize % HUGE) % HUGE;
            // SAFETY: `head < HUGE`, so `base + head` and the `bytes` after it lie inside
            // the mapping made above.
            let start = unsafe { base.cast::<u8>().add(head) };
            // Advice only: without huge pages the mapping is ordinary pages. Miri (`cargo
            // +nightly miri test --lib rop::`) models no such advice.
            #[cfg(not(miri))]
            // SAFETY: the range lies inside the mapping made above; advice changes no value.
            unsafe {
                libc::madvise(start.cast(), bytes, libc::MADV_HUGEPAGE);
            }
            Some(Mapping {
                ptr: NonNull::new(start.cast::<T>())?,
                len,
                base: NonNull::new(base)?,
                span,
                _values: PhantomData,
            })
        }

        #[inline(always)]
        pub fn as_slice(&self) -> &[T] {
            // SAFETY: `len` values inside the mapping, initialised (zero pages are valid
            // values, `PlaneValue`), aligned (huge-page aligned), owned by self.
            unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
        }

        #[inline(always)]
        pub fn as_mut_slice(&mut self) -> &mut [T] {
            // SAFETY: as `as_slice`, borrowed uniquely through &mut self.
            unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
        }
    }

    impl<T> Drop for Mapping<T> {
        fn drop(&mut self) {
            // SAFETY: the whole mapping this value owns, unmapped once.
            unsafe {
                libc::munmap(self.base.as_ptr(), self.span);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn planes_small_and_large_hold_what_was_written() {
        // Under Miri, which checks every access to the mapping against its bounds, the
        // mapped planes are read at their ends and a stride apart rather than whole: a
        // 3 M-value plane read whole takes minutes there.
        let read = |len: usize| -> Vec<usize> {
            match cfg!(miri) {
                true => (0..len)
                    .step_by(4093)
                    .chain(len.saturating_sub(3)..len)
                    .collect(),
                false => (0..len).collect(),
            }
        };
        for len in [0, 1, 1000, (2 << 20) / 4 - 1, (2 << 20) / 4, 3 << 20] {
            let mut p = Plane::filled(len, 7u32);
            assert_eq!(p.len(), len);
            assert!(read(len).into_iter().all(|i| p[i] == 7), "{len}");
            if len > 0 {
                p[len - 1] = 9;
                p[0] = 5;
            }
            let q = p.clone();
            assert!(read(len).into_iter().all(|i| p[i] == q[i]), "{len}");
            let z = Plane::<f32>::zeroed(len);
            assert!(read(len).into_iter().all(|i| z[i] == 0.0), "{len}");
            let v: Vec<u32> = q.into();
            assert_eq!(v.len(), len);
            if len > 1 {
                assert_eq!((v[0], v[1], v[len - 1]), (5, 7, 9));
            }
        }
    }

    #[test]
    fn fill_writes_every_value_of_any_length() {
        for len in [
            0,
            1,
            FILL_BLOCK - 1,
            FILL_BLOCK,
            FILL_BLOCK + 1,
            3 * FILL_BLOCK + 7,
        ] {
            let mut v = vec![[0u8; 3]; len];
            fill(&mut v, [1, 2, 3]);
            assert!(v.iter().all(|&c| c == [1, 2, 3]), "{len}");
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn large_planes_are_mapped_on_huge_page_boundaries() {
        let p = Plane::filled(1 << 20, [1u8, 2, 3]);
        assert!(matches!(p.storage, Storage::Mapped(_)));
        assert_eq!(p.as_ptr() as usize % (2 << 20), 0);
        assert!(matches!(
            Plane::filled(100, 0.5f32).storage,
            Storage::Vec(_)
        ));
    }
}
