//! Transparent huge pages for the pyramid's buffers.
//!
//! The doubled first octave of a 2000 x 2500 map is 20 Mpx a layer, and a detector's first call writes
//! hundreds of megabytes for the first time: with 4 KiB pages the page faults cost as much as the blurs
//! (measured: SIFT on two such maps 0.8-0.9 s with small pages, 0.4-0.5 s with huge ones). Linux gives a
//! region huge pages on its first write when asked with `madvise(MADV_HUGEPAGE)` (the usual
//! `transparent_hugepage=madvise` setting); elsewhere, or when the kernel says no, nothing changes.

/// Asks for huge pages under the spare capacity of `buf` (before it is first written).
pub fn advise<T>(buf: &Vec<T>) {
    let bytes = buf.capacity() * std::mem::size_of::<T>();
    advise_range(buf.as_ptr().cast(), bytes);
}

/// Huge-page size on x86_64 and aarch64 Linux with 4 KiB base pages.
const HUGE: usize = 2 << 20;

#[cfg(target_os = "linux")]
fn advise_range(ptr: *const u8, bytes: usize) {
    let (lo, hi) = ((ptr as usize).next_multiple_of(HUGE), (ptr as usize).saturating_add(bytes) / HUGE * HUGE);
    if hi > lo {
        // SAFETY: madvise with MADV_HUGEPAGE changes how the kernel backs pages of this allocation (whole huge
        // pages inside it), never their contents or who may access them; an error (THP off, old kernel) is
        // harmless and ignored.
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_range(_ptr: *const u8, _bytes: usize) {}

#[cfg(test)]
mod tests {
    #[test]
    fn advising_any_buffer_is_harmless() {
        for n in [0usize, 1, 1000, 3 << 20] {
            let mut v: Vec<f32> = Vec::with_capacity(n);
            super::advise(&v);
            v.resize(n, 1.5);
            assert!(v.iter().all(|&x| x == 1.5));
        }
    }
}
