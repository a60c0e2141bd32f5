//! Per-vertex arrays on transparent huge pages.
//!
//! The engine's sweeps and groupings visit vertices in value order, which
//! on a smooth field is scattered across the volume: nearly every access
//! to a per-vertex array lands on another 4 KiB page, so beside the cache
//! miss the processor walks the page table (a TLB holds a few thousand
//! pages: a few MiB, against 64 MiB for one word per vertex of a 256³
//! volume). On 2 MiB pages the same arrays need a few dozen TLB entries,
//! and filling them takes one page fault per 2 MiB instead of 512.
//!
//! Linux gives huge pages to anonymous memory asked for with
//! `madvise(MADV_HUGEPAGE)` when transparent huge pages are enabled
//! ("always" or "madvise", the common default); elsewhere, or when the
//! kernel has none to give, the hint is ignored and the array is an
//! ordinary one. Nothing here changes what an array holds.

use rayon::prelude::*;

/// Arrays smaller than this stay on ordinary pages.
const HUGE: usize = 4 << 20;

/// An array of `n` copies of `value`, on huge pages when it is large,
/// filled on every core (so the pages are first touched in parallel).
pub fn filled<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    filled_within(n, n, value)
}

/// [`filled`] in an allocation of `capacity` (at least `n`).
pub(crate) fn filled_within<T: Copy + Send + Sync>(n: usize, capacity: usize, value: T) -> Vec<T> {
    filled_on(n, capacity, value, true)
}

/// An array of `n` copies of `value` on ordinary pages, filled on every
/// core: for an array read in sequence, where huge pages save no TLB
/// misses, while faulting one in can cost more than its 512 small pages
/// (a virtual machine whose host takes free memory back in huge-page
/// blocks: measured 10 us per 4 KiB then, against 2).
pub fn touched<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    filled_on(n, n, value, false)
}

fn filled_on<T: Copy + Send + Sync>(n: usize, capacity: usize, value: T, huge: bool) -> Vec<T> {
    let mut v: Vec<T> = Vec::with_capacity(capacity.max(n));
    if huge {
        advise(v.as_ptr() as *const u8, v.capacity() * size_of::<T>());
    }
    v.spare_capacity_mut()[..n]
        .par_chunks_mut(1 << 16)
        .for_each(|c| c.iter_mut().for_each(|x| _ = x.write(value)));
    // SAFETY: the first n elements were all written just above.
    unsafe { v.set_len(n) };
    v
}

/// `spare` made `n` copies of `value`, in its own allocation when that
/// is large enough (a recycled array: no fresh page to fault in and zero,
/// which on a large mesh costs as much as making it), else [`filled`].
pub fn refilled<T: Copy + Send + Sync>(spare: Vec<T>, n: usize, value: T) -> Vec<T> {
    let recycled = spare.capacity() >= n;
    let mut v = reused(spare, n, value);
    if recycled {
        v.par_chunks_mut(1 << 16).for_each(|c| c.fill(value));
    }
    v
}

/// An array of `n` elements for a caller that overwrites every one of
/// them: `spare` itself when its allocation is large enough (what it held
/// is left there, and only growth is filled with `value`), else [`filled`]
/// in an allocation with [`room`] to grow (a mesh's arrays, which a drag
/// recycles for its next, slightly larger, steps; the room is never
/// touched, so it costs address space, not memory).
/// A recycled array costs neither fresh pages nor a fill.
pub fn reused<T: Copy + Send + Sync>(mut spare: Vec<T>, n: usize, value: T) -> Vec<T> {
    if spare.capacity() < n {
        let capacity = room(n);
        drop(spare);
        return filled_within(n, capacity, value);
    }
    spare.truncate(n);
    spare.resize(n, value);
    spare
}

/// A copy of `from`, in `spare`'s allocation when that is large enough,
/// else on huge pages when it is large; copied on every core.
pub fn copied<T: Copy + Send + Sync>(mut spare: Vec<T>, from: &[T]) -> Vec<T> {
    let n = from.len();
    if spare.capacity() < n {
        spare = Vec::with_capacity(headroom(spare.capacity(), n));
        advise(
            spare.as_ptr() as *const u8,
            spare.capacity() * size_of::<T>(),
        );
    }
    spare.truncate(n);
    let old = spare.len();
    spare
        .par_chunks_mut(1 << 16)
        .zip(from[..old].par_chunks(1 << 16))
        .for_each(|(out, c)| out.copy_from_slice(c));
    let tail = &from[old..];
    spare.spare_capacity_mut()[..tail.len()]
        .par_chunks_mut(1 << 16)
        .zip(tail.par_chunks(1 << 16))
        .for_each(|(out, c)| {
            for (o, &x) in out.iter_mut().zip(c) {
                o.write(x);
            }
        });
    // SAFETY: the elements from `old` to `n` were all written just above.
    unsafe { spare.set_len(n) };
    spare
}

/// The capacity for `n` elements in place of a recycled array of
/// `recycled` that is too small: a quarter more than asked, so that the
/// slightly larger arrays of the next steps (a dragged contour grows a
/// little with each) fit in it instead of each step faulting in and
/// zeroing fresh pages; exactly `n` when nothing was recycled.
pub fn headroom(recycled: usize, n: usize) -> usize {
    if recycled > 0 { room(n) } else { n }
}

/// Room for `n` elements and a quarter more (see [`headroom`]).
pub fn room(n: usize) -> usize {
    n.saturating_add(n / 4)
}

/// An array to recycle: room for `n` elements and a quarter more, every
/// page already touched ([`filled`] to its whole length, so that
/// [`reused`] writes nothing into it before its caller does).
pub fn spare<T: Copy + Send + Sync + Default>(n: usize) -> Vec<T> {
    filled(room(n), T::default())
}

/// An array written from several threads at once, each slot by one of
/// them: the scatter of a counting sort or a grouping, whose prefix sums
/// give every thread its own slots.
pub struct DisjointSlots<'a, T> {
    start: *mut T,
    len: usize,
    _array: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: writes go to slots no other thread writes (`write`'s contract),
// and the array is borrowed mutably for the lifetime.
unsafe impl<T: Send> Sync for DisjointSlots<'_, T> {}

impl<'a, T> DisjointSlots<'a, T> {
    /// The slots of `array`, borrowed until the writes are done.
    pub fn new(array: &'a mut [T]) -> Self {
        Self {
            start: array.as_mut_ptr(),
            len: array.len(),
            _array: std::marker::PhantomData,
        }
    }

    /// Writes `value` to slot `i` (checked against the length).
    ///
    /// # Safety
    /// No other thread reads or writes slot `i` while the slots are shared.
    #[inline(always)]
    pub unsafe fn write(&self, i: usize, value: T) {
        assert!(i < self.len, "slot {i} of {}", self.len);
        // SAFETY: in bounds (just checked); the caller guarantees no other
        // thread touches this slot.
        unsafe { self.start.add(i).write(value) };
    }

    /// Reads slot `i` (checked against the length).
    ///
    /// # Safety
    /// No other thread writes slot `i` while the slots are shared.
    #[inline(always)]
    pub unsafe fn read(&self, i: usize) -> T
    where
        T: Copy,
    {
        assert!(i < self.len, "slot {i} of {}", self.len);
        // SAFETY: in bounds (just checked); the caller guarantees no other
        // thread writes this slot.
        unsafe { self.start.add(i).read() }
    }

    /// A hint that slot `i` will be read soon (nothing if out of range).
    #[inline(always)]
    pub fn prefetch(&self, i: usize) {
        #[cfg(target_arch = "x86_64")]
        if i < self.len {
            // SAFETY: a prefetch never faults; the address is in the array.
            unsafe {
                std::arch::x86_64::_mm_prefetch(
                    self.start.add(i) as *const i8,
                    std::arch::x86_64::_MM_HINT_T0,
                )
            };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = i;
    }

    /// The slots `range` (checked against the length), to write at once.
    ///
    /// # Safety
    /// No other thread reads or writes these slots while the slice lives.
    #[inline]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn slice(&self, range: std::ops::Range<usize>) -> &mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "slots {range:?} of {}",
            self.len
        );
        // SAFETY: in bounds (just checked); the caller guarantees no other
        // thread touches these slots meanwhile.
        unsafe { std::slice::from_raw_parts_mut(self.start.add(range.start), range.len()) }
    }
}

/// Returns large freed arrays to the system at once: glibc's
/// `M_MMAP_THRESHOLD` fixed at 1 MiB. By default it grows with every large
/// block freed, up to 32 MiB, after which arrays of up to 32 MiB (the
/// candidates' tables of a scan) are carved from the heap and stay
/// resident once freed: 2-3 bytes per vertex of the engine's measured
/// peak on colin27_ch2 and engine were such garbage. The program calls
/// this once at start; nothing else changes.
pub fn return_freed_arrays() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets an allocator parameter; called before any
    // thread is started.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
    }
}

/// Returns to the system the free pages inside the allocator's heaps,
/// every thread's arena: arrays below [`return_freed_arrays`]'s 1 MiB
/// are carved from them and stay resident once freed. The blocks' glue
/// frees many (each block's node tables, the cut-crossing edges): 4 bytes
/// per vertex still held by the finished tree on tooth in 8 blocks.
pub fn trim_freed() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only hands free pages back; no live block moves.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Gives the pages of `v`'s spare capacity (beyond its length) back to
/// the system, keeping the capacity: growing into it later needs no new
/// allocation and no copy (the pages come back, zeroed, when written).
/// A `shrink_to_fit` followed by growth may copy the whole array.
pub fn release_spare<T>(v: &mut Vec<T>) {
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let start = v.as_ptr() as usize + v.len() * size_of::<T>();
        let end = v.as_ptr() as usize + v.capacity() * size_of::<T>();
        let (first, end) = (start.next_multiple_of(PAGE), end / PAGE * PAGE);
        if end > first {
            // SAFETY: the pages lie inside the vector's allocation, beyond
            // its length: nothing initialised lives there, and the kernel
            // maps them back, zeroed, when they are touched again.
            unsafe {
                libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_DONTNEED);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v;
}

/// Asks for huge pages for the `len` bytes at `start` (allocated, not yet
/// touched). Only whole 4 KiB pages inside the range are advised; a hint
/// the kernel refuses is ignored.
fn advise(start: *const u8, len: usize) {
    #[cfg(target_os = "linux")]
    if len >= HUGE {
        const PAGE: usize = 4096;
        let first = (start as usize).next_multiple_of(PAGE);
        let end = (start as usize + len) / PAGE * PAGE;
        if end > first {
            // SAFETY: madvise only changes how the kernel backs these
            // pages, which lie inside the caller's allocation; it never
            // changes their contents.
            unsafe {
                libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, len, HUGE);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filled_arrays_hold_their_value_small_and_large() {
        for n in [0, 1, 1000, (HUGE / 4) + 12_345] {
            for v in [filled(n, 7u32), touched(n, 7u32)] {
                assert_eq!(v.len(), n);
                assert!(v.iter().all(|&x| x == 7));
            }
        }
        let v = filled(HUGE, u64::MAX);
        assert!(v.iter().all(|&x| x == u64::MAX));
    }

    /// Recycled arrays, shorter, longer or as long as asked for, come back
    /// holding exactly what was asked for, in the old allocation when it
    /// fits; a spare holds a quarter more, touched.
    #[test]
    fn recycled_arrays_hold_what_was_asked_for() {
        let big = (HUGE / 4) + 12_345;
        let from: Vec<u32> = (0..big as u32)
            .map(|i| i.wrapping_mul(2_654_435_761))
            .collect();
        for spare_len in [0, 1, 1000, big / 2, big, big + 70_000] {
            for n in [0, 1, 999, 70_000, big] {
                let spare: Vec<u32> = vec![9; spare_len];
                let fits = spare.capacity() >= n;
                let at = spare.as_ptr();
                let v = refilled(spare, n, 7u32);
                assert_eq!(v.len(), n);
                assert!(v.iter().all(|&x| x == 7));
                if fits && spare_len > 0 {
                    assert_eq!(v.as_ptr(), at, "the old allocation");
                }
                let spare: Vec<u32> = vec![9; spare_len];
                let at = spare.as_ptr();
                let c = copied(spare, &from[..n]);
                assert_eq!(c, &from[..n]);
                if fits && spare_len > 0 {
                    assert_eq!(c.as_ptr(), at, "the old allocation");
                }
                // A recycled array too small, or none, is replaced by one
                // with room for the next, slightly larger, steps.
                let spare: Vec<u32> = vec![9; spare_len];
                let r = reused(spare, n, 7u32);
                assert_eq!(r.len(), n);
                let room = if fits { n } else { n + n / 4 };
                assert!(r.capacity() >= room, "{} for {n}", r.capacity());
                let grown = r.len() + r.len() / 5;
                if !fits {
                    let at = r.as_ptr();
                    let again = reused(r, grown, 7u32);
                    assert_eq!(again.as_ptr(), at, "a fifth more fits");
                }
            }
        }
        let s: Vec<u32> = spare(big);
        assert_eq!(s.len(), big + big / 4);
        assert!(s.iter().all(|&x| x == 0));
        let at = s.as_ptr();
        let r = reused(s, big + big / 5, 7u32);
        assert_eq!(r.as_ptr(), at, "the spare fits");
    }
}
