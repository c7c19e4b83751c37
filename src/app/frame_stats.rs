//! Frame-time measurement: with `VOLCACHE_FRAME_TIME=1` the app repaints
//! continuously and prints, every two seconds, the frame interval (egui's
//! `unstable_dt`: UI build + tessellation + painting + buffer swap), the time
//! spent building the UI, and the UI thread's CPU time per frame (what the frame
//! costs when the machine is not shared), split by whether a computation ran.

use std::time::{Duration, Instant};

#[derive(Debug)]
pub struct FrameStats {
    enabled: bool,
    window: Instant,
    /// (frame interval s, UI build s, computing?, UI thread CPU s)
    frames: Vec<(f64, f64, bool, f64)>,
    last_cpu: f64,
}

/// CPU time of the calling thread, seconds.
fn thread_cpu_seconds() -> f64 {
    #[cfg(target_os = "linux")]
    {
        let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: clock_gettime writes into the timespec we own.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) } == 0 {
            return t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9;
        }
    }
    0.0
}

impl FrameStats {
    pub fn from_env() -> Self {
        FrameStats {
            enabled: std::env::var_os("VOLCACHE_FRAME_TIME").is_some_and(|v| v != "0"),
            window: Instant::now(),
            frames: Vec::new(),
            last_cpu: thread_cpu_seconds(),
        }
    }

    /// Record a frame; returns true when the app should repaint continuously.
    pub fn record(&mut self, dt: f32, build: Duration, busy: bool) -> bool {
        if !self.enabled {
            return false;
        }
        let cpu = thread_cpu_seconds();
        self.frames
            .push((dt as f64, build.as_secs_f64(), busy, cpu - self.last_cpu));
        self.last_cpu = cpu;
        if self.window.elapsed() >= Duration::from_secs(2) {
            for (busy, what) in [(true, "computing"), (false, "idle")] {
                if let Some(line) = summary(&self.frames, busy) {
                    eprintln!("frame time ({what}): {line}");
                }
            }
            self.frames.clear();
            self.window = Instant::now();
        }
        true
    }
}

/// "mean … ms, p95 … ms, max … ms over N frames; UI build mean … ms, UI thread CPU
/// mean … ms".
pub fn summary(frames: &[(f64, f64, bool, f64)], busy: bool) -> Option<String> {
    let mut dts: Vec<f64> = frames.iter().filter(|f| f.2 == busy).map(|f| f.0 * 1e3).collect();
    if dts.is_empty() {
        return None;
    }
    let mean_of = |g: fn(&(f64, f64, bool, f64)) -> f64| {
        frames.iter().filter(|f| f.2 == busy).map(g).sum::<f64>() * 1e3 / dts.len() as f64
    };
    let (build, cpu) = (mean_of(|f| f.1), mean_of(|f| f.3));
    let mean = dts.iter().sum::<f64>() / dts.len() as f64;
    dts.sort_by(f64::total_cmp);
    let p95 = dts[((dts.len() - 1) as f64 * 0.95).round() as usize];
    Some(format!(
        "mean {mean:.1} ms, p95 {p95:.1} ms, max {:.1} ms over {} frames; UI build mean {build:.2} ms, \
         UI thread CPU mean {cpu:.1} ms",
        dts[dts.len() - 1],
        dts.len()
    ))
}

#[cfg(test)]
mod tests {
    #[test]
    fn summary_splits_busy_and_idle() {
        let f = [
            (0.010, 0.001, true, 0.004),
            (0.030, 0.003, true, 0.006),
            (0.5, 0.0, false, 0.0),
        ];
        let s = super::summary(&f, true).unwrap();
        let want =
            "mean 20.0 ms, p95 30.0 ms, max 30.0 ms over 2 frames; UI build mean 2.00 ms, UI thread CPU mean 5.0 ms";
        assert_eq!(s, want);
        assert!(super::summary(&[], true).is_none());
    }
}
