//! Timing for the benchmarks: the CPU clocks Linux keeps in /proc (one reader for the calling
//! thread and the whole process), the median wall and CPU time of repeated runs, and how busy
//! the rest of the machine was meanwhile.

use std::time::Instant;

use amber_stdx::median;
use serde::Serialize;

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

/// CPU seconds used so far by this process's finished children (a peer script, once waited for).
fn children_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // cutime and cstime are fields 16 and 17.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i)?.parse::<f64>().ok();
    Some((ticks(13)? + ticks(14)?) / CLOCK_TICKS_PER_S)
}

/// `/proc/loadavg` as Linux writes it (1, 5 and 15 minute averages, runnable/total tasks, last pid).
pub fn load_average() -> Option<String> {
    std::fs::read_to_string("/proc/loadavg").ok().map(|s| s.trim().to_string())
}

/// Measures how busy the machine was over an interval, besides us: the load average at both
/// ends, and the CPUs the other processes used in between (the machine's busy time from
/// `/proc/stat` minus this process's and its finished children's, such as a peer script).
pub struct LoadMeter {
    load_average_before: Option<String>,
    start: Instant,
    /// The machine's busy and total clock ticks at the start.
    machine: Option<(u64, u64)>,
    /// CPU seconds of this process and its finished children at the start.
    ours: Option<f64>,
}

/// What a [`LoadMeter`] saw: a results file's record of the machine's load around a case.
#[derive(Clone, Debug, Serialize)]
pub struct Load {
    pub load_average_before: Option<String>,
    pub load_average_after: Option<String>,
    /// Mean CPUs used by other processes (0 on a quiet machine; at most the core count).
    pub other_cpus: f64,
    pub wall_seconds: f64,
}

impl LoadMeter {
    pub fn start() -> Self {
        Self {
            load_average_before: load_average(),
            start: Instant::now(),
            machine: Self::machine_ticks(),
            ours: Self::our_cpu_seconds(),
        }
    }

    /// The machine's busy and total clock ticks so far.
    fn machine_ticks() -> Option<(u64, u64)> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let v: Vec<u64> = stat.lines().next()?.split_whitespace().skip(1).filter_map(|x| x.parse().ok()).collect();
        let total: u64 = v.iter().sum();
        Some((total - v.get(3)? - v.get(4)?, total))
    }

    fn our_cpu_seconds() -> Option<f64> {
        Some(cpu_seconds(CpuClock::Process)? + children_cpu_seconds()?)
    }

    /// Mean CPUs used by other processes since [`Self::start`] (NaN without /proc).
    pub fn other_cpus(&self) -> f64 {
        let (Some((busy0, total0)), Some((busy, total)), Some(ours0), Some(ours)) =
            (self.machine, Self::machine_ticks(), self.ours, Self::our_cpu_seconds())
        else {
            return f64::NAN;
        };
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let other = (busy - busy0) as f64 / CLOCK_TICKS_PER_S - (ours - ours0);
        (other / ((total - total0).max(1) as f64 / CLOCK_TICKS_PER_S) * cpus).max(0.0)
    }

    pub fn finish(&self) -> Load {
        Load {
            load_average_before: self.load_average_before.clone(),
            load_average_after: load_average(),
            other_cpus: self.other_cpus(),
            wall_seconds: self.start.elapsed().as_secs_f64(),
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
