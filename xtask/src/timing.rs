//! Timing for the benchmarks: the CPU clocks Linux keeps in /proc (one reader for the calling
//! thread and the whole process), and the median wall and CPU time of repeated runs.

use std::time::Instant;

use amber_stdx::median;

/// Clock ticks per second of `/proc/stat` and `/proc/self/stat` (`USER_HZ`, 100 on Linux).
pub const CLOCK_TICKS_PER_S: f64 = 100.0;

/// Whose CPU time [`cpu_seconds`] reads.
#[derive(Clone, Copy, Debug)]
pub enum CpuClock {
    /// The calling thread, for work that runs on it alone (the mesh generators).
    Thread,
    /// The whole process (all threads), for work that runs on rayon's threads.
    Process,
}

/// CPU seconds (user + system) used so far by the calling thread, from the scheduler's
/// statistics (`/proc/thread-self/schedstat`, nanoseconds), or by the whole process
/// (`/proc/self/stat`, clock ticks of 10 ms); `None` without Linux's /proc.
pub fn cpu_seconds(clock: CpuClock) -> Option<f64> {
    match clock {
        CpuClock::Thread => {
            let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
            Some(stat.split_whitespace().next()?.parse::<f64>().ok()? * 1e-9)
        }
        CpuClock::Process => {
            let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
            // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
            let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
            let ticks = |i: usize| fields.get(i)?.parse::<f64>().ok();
            Some((ticks(11)? + ticks(12)?) / CLOCK_TICKS_PER_S)
        }
    }
}

/// A started CPU clock.
pub struct CpuTimer {
    clock: CpuClock,
    start: Option<f64>,
}

impl CpuTimer {
    pub fn start(clock: CpuClock) -> Self {
        Self { clock, start: cpu_seconds(clock) }
    }

    /// CPU seconds since [`Self::start`] (NaN without /proc).
    pub fn seconds(&self) -> f64 {
        self.start.zip(cpu_seconds(self.clock)).map_or(f64::NAN, |(start, now)| now - start)
    }
}

/// Runs `make` `repeats` times (at least once); returns its last result and the median wall
/// and CPU seconds of one run on `clock`.
pub fn median_time<T, E: Into<anyhow::Error>>(
    repeats: usize,
    clock: CpuClock,
    mut make: impl FnMut() -> Result<T, E>,
) -> anyhow::Result<(T, f64, f64)> {
    let (mut wall, mut cpu, mut last) = (Vec::new(), Vec::new(), None);
    for _ in 0..repeats.max(1) {
        let (start, timer) = (Instant::now(), CpuTimer::start(clock));
        last = Some(make().map_err(Into::into)?);
        wall.push(start.elapsed().as_secs_f64());
        cpu.push(timer.seconds());
    }
    Ok((last.expect("at least one repetition"), median(&wall), median(&cpu)))
}
