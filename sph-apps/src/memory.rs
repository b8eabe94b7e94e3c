//! Process-wide allocator settings for long runs.
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

/// Hands the free pages inside glibc's heaps back to the OS
/// (`malloc_trim(0)`); the `sphexa` binary has the simulation loop call
/// it after every step ([`Simulation::set_after_step`](crate::Simulation::set_after_step)).
///
/// Small allocations (below [`MMAP_THRESHOLD`]) come from the heap, and
/// the step's short-lived ones, freed between longer-lived ones, leave
/// holes that later requests do not fill: the heap grows step after step
/// while the bytes in use stay flat. Measured (Sedov 40^3, 1 rank x 2
/// threads, main arena by `mallinfo2`): 1.5 MiB in use throughout, free
/// holes 0.8 MiB after step 1 and 15 MiB after step 275; peak RSS by
/// `/usr/bin/time -v` 30.5 MiB after 50 steps and 41.4 MiB after 300
/// without the trim, 27.9 and 30.2 MiB with it (wall time within noise,
/// 21.5 s against 21.8 s for 300 steps). Does nothing on other C
/// libraries.
pub fn return_free_heap_to_os() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        #[allow(unsafe_code)]
        {
            extern "C" {
                fn malloc_trim(pad: usize) -> std::ffi::c_int;
            }
            // SAFETY: `malloc_trim` takes a plain integer and only releases
            // free pages of the C allocator's own heaps (madvise), which no
            // live allocation occupies; glibc locks each arena while it
            // walks it, so other threads may allocate meanwhile. Measured
            // gain in the doc comment above.
            unsafe {
                malloc_trim(0);
            }
        }
    }
}
