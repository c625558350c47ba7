//! The stepper's phase times (assembly, factorizations, solves) on the
//! thread's CPU clock, read only where asked: the thread clock has no vDSO,
//! so each reading is a system call, and with a dozen readings per Newton
//! iteration a small sheet stepped at 1 kHz spent a sixth of its CPU on
//! them. Off by default; a bench or the CLI's closing report turns it on.

use crate::cpu_time::CpuInstant;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

static ON: AtomicBool = AtomicBool::new(false);

/// Turn the phase times of every model in the process on or off
/// ([`crate::model::StepReport`]'s `assembly_time`, `factor_time` and
/// `solve_time` stay zero while off).
pub fn set_phase_timing(on: bool) {
    ON.store(on, Ordering::Relaxed);
}

/// Whether phase times are read.
pub fn phase_timing() -> bool {
    ON.load(Ordering::Relaxed)
}

/// A start point on the thread's CPU clock, or nothing while phase timing
/// is off.
#[derive(Clone, Copy, Debug)]
pub struct PhaseTimer(Option<CpuInstant>);

impl PhaseTimer {
    /// Start timing a phase.
    pub fn start() -> PhaseTimer {
        PhaseTimer(phase_timing().then(CpuInstant::now))
    }

    /// CPU time since the start (zero while phase timing is off).
    pub fn elapsed(&self) -> Duration {
        self.0.map_or(Duration::ZERO, |t| t.elapsed())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Off, nothing is read; on, a busy loop counts.
    #[test]
    fn times_only_when_on() {
        set_phase_timing(false);
        let t = PhaseTimer::start();
        assert!(t.0.is_none());
        assert_eq!(t.elapsed(), Duration::ZERO);
        set_phase_timing(true);
        let t = PhaseTimer::start();
        let mut x = 0u64;
        while t.elapsed() < Duration::from_millis(5) {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        assert!(x > 0);
        set_phase_timing(false);
    }
}
