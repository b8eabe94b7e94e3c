//! Process-wide allocator setting for long runs.
//!
//! glibc's malloc serves large blocks with their own `mmap` at first, but
//! after the first such block is freed it raises that threshold to the
//! block's size (up to 32 MiB), so later particle-sized buffers (a few MiB
//! at 10^5-10^6 particles) come from its heap instead. The temporaries
//! freed there each step (packed migration and halo messages, received
//! buffers) are kept by the process rather than returned to the OS.
//! Measured (Sedov 80^3, 2 ranks x 1 thread, `/usr/bin/time -v`): 152 MB
//! per rank with the adaptive threshold, 134 MB with it fixed at 128 KiB;
//! one rank is unchanged, and the time per step is within noise.

/// Allocations of at least this many bytes get their own mapping, so
/// freeing them returns the memory to the OS at once.
pub const MMAP_THRESHOLD: usize = 128 * 1024;

/// Fixes glibc's mmap threshold at [`MMAP_THRESHOLD`] (which also stops it
/// from adapting). Call it once, at the start of `main`, before any thread
/// exists. Does nothing on other C libraries, and leaves the setting alone
/// when the user chose one with `MALLOC_MMAP_THRESHOLD_`.
pub fn return_large_buffers_to_os() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_some() {
            return;
        }
        use std::ffi::c_int;
        // glibc's <malloc.h>: M_MMAP_THRESHOLD.
        const M_MMAP_THRESHOLD: c_int = -3;
        #[allow(unsafe_code)]
        {
            extern "C" {
                fn mallopt(param: c_int, value: c_int) -> c_int;
            }
            // SAFETY: `mallopt` only changes a tuning parameter of the C
            // allocator; it takes plain integers and is called before any
            // other thread is started. Measured gain in the module docs.
            unsafe {
                mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD as c_int);
            }
        }
    }
}
