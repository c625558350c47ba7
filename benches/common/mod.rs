//! Helpers the benches share (kept out of the library, which has no
//! unsafe code outside its FMI layer).

/// CPU time of this process so far, s (the benches compare CPU, not wall,
/// time on the shared machine).
pub fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid out pointer for clock_gettime.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
