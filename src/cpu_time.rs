//! CPU time, as the kernel counts it: the calling thread's clock for the
//! stepper's phase times, the process's for the benches' totals. On a
//! shared machine wall time counts the other jobs too; these do not. On
//! unix they are `clock_gettime`'s `CLOCK_THREAD_CPUTIME_ID` and
//! `CLOCK_PROCESS_CPUTIME_ID`; on Windows the kernel plus user times of
//! `GetThreadTimes` and `GetProcessTimes`.

use std::time::{Duration, Instant};

/// Which CPU clock to read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// CPU time of the calling thread.
    Thread,
    /// CPU time of the whole process (all threads).
    Process,
}

/// The CPU time `clock` has counted so far.
#[cfg(unix)]
#[allow(unsafe_code)] // one libc call with a valid out pointer
pub fn now(clock: Clock) -> Duration {
    let id = match clock {
        Clock::Thread => libc::CLOCK_THREAD_CPUTIME_ID,
        Clock::Process => libc::CLOCK_PROCESS_CPUTIME_ID,
    };
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock ids exist on
    // every Linux (and the BSDs and macOS have both).
    let rc = unsafe { libc::clock_gettime(id, &mut ts) };
    if rc != 0 {
        return Duration::ZERO;
    }
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// The CPU time `clock` has counted so far.
#[cfg(windows)]
#[allow(unsafe_code)] // one Windows API call with valid out pointers
pub fn now(clock: Clock) -> Duration {
    use windows_sys::Win32::Foundation::FILETIME;
    use windows_sys::Win32::System::Threading as t;
    let [mut created, mut exited, mut kernel, mut user] = [FILETIME::default(); 4];
    // SAFETY: the pseudo-handles of the current thread and process are
    // always valid, and the four FILETIMEs are valid, writable locals.
    let ok = unsafe {
        match clock {
            Clock::Thread => t::GetThreadTimes(
                t::GetCurrentThread(),
                &mut created,
                &mut exited,
                &mut kernel,
                &mut user,
            ),
            Clock::Process => t::GetProcessTimes(
                t::GetCurrentProcess(),
                &mut created,
                &mut exited,
                &mut kernel,
                &mut user,
            ),
        }
    };
    if ok == 0 {
        return Duration::ZERO;
    }
    // FILETIME counts 100 ns ticks in two 32-bit halves.
    let ticks = |f: FILETIME| (u64::from(f.dwHighDateTime) << 32) | u64::from(f.dwLowDateTime);
    Duration::from_nanos((ticks(kernel) + ticks(user)).saturating_mul(100))
}

/// CPU time of the whole process so far, s.
pub fn process_seconds() -> f64 {
    now(Clock::Process).as_secs_f64()
}

/// A start point on the calling thread's CPU clock: `Instant` for CPU
/// time. Read [`CpuInstant::elapsed`] on the thread that took it.
#[derive(Clone, Copy, Debug)]
pub struct CpuInstant(Duration);

impl CpuInstant {
    /// The calling thread's CPU time now.
    pub fn now() -> CpuInstant {
        CpuInstant(now(Clock::Thread))
    }

    /// CPU time the thread spent since `self`.
    pub fn elapsed(&self) -> Duration {
        now(Clock::Thread).saturating_sub(self.0)
    }
}

/// A limit on the calling thread's CPU time from now. [`Self::passed`]
/// reads the thread's CPU clock (a system call) only once the wall clock
/// has run past the limit, since a thread's CPU time never runs ahead of
/// the wall clock: checked at every Newton iteration, it costs a monotonic
/// clock read.
#[derive(Clone, Copy, Debug)]
pub struct ThreadDeadline {
    wall: Instant,
    cpu: Duration,
    limit: Duration,
}

impl ThreadDeadline {
    /// `limit` seconds of this thread's CPU from now; `None` where the
    /// limit is too large to count (no limit then).
    pub fn after(limit: f64) -> Option<ThreadDeadline> {
        let limit = Duration::try_from_secs_f64(limit).ok()?;
        Some(ThreadDeadline {
            wall: Instant::now(),
            cpu: now(Clock::Thread),
            limit,
        })
    }

    /// Whether this thread has used more than the limit since the start.
    pub fn passed(&self) -> bool {
        self.wall.elapsed() > self.limit && now(Clock::Thread).saturating_sub(self.cpu) > self.limit
    }
}

/// Process CPU time and wall time from one start: what a bench prints
/// (both, labelled), so that the machine's load shows as their ratio.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch {
    cpu: Duration,
    wall: Instant,
}

impl Stopwatch {
    /// Start both clocks.
    pub fn start() -> Stopwatch {
        Stopwatch {
            cpu: now(Clock::Process),
            wall: Instant::now(),
        }
    }

    /// Process CPU seconds since the start.
    pub fn cpu(&self) -> f64 {
        now(Clock::Process).saturating_sub(self.cpu).as_secs_f64()
    }

    /// Wall-clock seconds since the start.
    pub fn wall(&self) -> f64 {
        self.wall.elapsed().as_secs_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deadline passes after its CPU, not after a sleep.
    #[test]
    fn a_deadline_counts_cpu() {
        let d = ThreadDeadline::after(0.02).unwrap();
        std::thread::sleep(Duration::from_millis(40));
        assert!(!d.passed(), "a sleep passed it");
        let mut x = 0u64;
        while !d.passed() {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        assert!(x > 0);
        assert!(ThreadDeadline::after(1e300).is_none());
    }

    /// A busy loop counts on the thread clock; a sleep does not.
    #[test]
    fn thread_clock_counts_work_not_sleep() {
        let t = CpuInstant::now();
        std::thread::sleep(Duration::from_millis(50));
        let slept = t.elapsed();
        assert!(slept < Duration::from_millis(20), "sleep counted {slept:?}");
        let t = CpuInstant::now();
        let mut x = 0u64;
        while t.elapsed() < Duration::from_millis(20) {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        assert!(x > 0);
    }
}
