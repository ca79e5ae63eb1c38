//! How much freed memory the C heap keeps for the next allocation instead of giving it back to
//! the OS.
//!
//! The window's renderer under software rendering (Mesa llvmpipe) allocates about 4.6 MB of
//! scene memory a frame, in pieces under 128 KiB, and frees it when the frame is shown; glibc
//! then gives the top of the heap back to the OS (its trim threshold is 128 KiB), so the next
//! frame takes the same memory again, page fault by page fault, each page cleared by the kernel
//! (seen as 250 `brk` calls a second and `clear_page_erms` in a profile of the telemetry view at
//! 10 frames a second). Keeping up to [`WINDOW_KEPT_BYTES`] of it cut the window's CPU by about
//! a fifth (`.ci/window_cpu.sh` telemetry-50hz, release build, four runs each: median 22.4 %
//! of a core before, 17.6 % after).

/// The freed memory a window process keeps (and the size under which its allocations come from
/// the heap rather than fresh mappings): 32 MiB.
pub const WINDOW_KEPT_BYTES: usize = 32 << 20;

/// Keeps up to `bytes` of freed heap memory in the process rather than returning it to the OS
/// at each free, and serves allocations smaller than `bytes` from the heap (glibc's
/// `M_TRIM_THRESHOLD` and `M_MMAP_THRESHOLD`; setting them also stops glibc adjusting them on
/// its own). Returns whether the allocator took both settings: `false` with another C library
/// or OS (nothing changed there), or for a size glibc refuses (one past an `int`, or past its
/// largest mmap threshold: 32 MiB on a 64-bit system or more, by version).
#[allow(unsafe_code)]
pub fn keep_freed_memory(bytes: usize) -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let Ok(bytes) = libc::c_int::try_from(bytes) else {
            return false;
        };
        // SAFETY: mallopt only sets the allocator's parameters; it takes any value and says
        // whether it accepted it.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, bytes) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, bytes) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        let _ = bytes;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn glibc_takes_the_windows_setting_and_refuses_a_size_past_an_int() {
        assert!(keep_freed_memory(WINDOW_KEPT_BYTES));
        assert!(!keep_freed_memory(usize::MAX), "past an int");
    }
}
