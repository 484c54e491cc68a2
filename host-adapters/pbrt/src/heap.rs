//! The program's allocator policy (glibc's `malloc`): its thresholds fixed before any thread starts, and what a
//! scene's build frees given back before the render takes its own.
//!
//! glibc slides its thresholds by default: once a block above 128 KiB it mapped on its own is freed, blocks up to
//! that size come from the arenas and up to twice it stay there when freed. After a build whose transients reach
//! megabytes, each render worker's arena so keeps memory it no longer uses under the render's peak
//! (docs/results/log.md, "Memory: glibc's thresholds held").

/// Holds glibc's mapping threshold at its documented default (128 KiB), which turns its sliding off: a large
/// block freed goes back to the system at once. Called by the command line first; a host embedding this library
/// keeps its own policy.
#[allow(unsafe_code)]
pub fn hold_thresholds() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` only sets the allocator's parameters, under its own lock; the value is in range.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

/// Gives the memory a build freed back to the system. glibc's allocator keeps what a program frees for its next
/// requests — the build's transients in each worker's arena, below the blocks that stay — so without this the
/// render's film and tiles would come on top of them (docs/results/log.md, "Memory: the film's twins apart, the
/// light's copy in bricks").
#[allow(unsafe_code)]
pub fn give_back_freed() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: glibc's `malloc_trim` takes the allocator's own lock and only returns free pages; 0 keeps no pad.
    unsafe {
        libc::malloc_trim(0);
    }
}
