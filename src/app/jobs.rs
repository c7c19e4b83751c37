//! Background jobs: the UI thread never blocks on a computation.
//!
//! A [`Job`] runs a closure on its own thread and hands back results through a
//! channel (several per job: the field sends each refinement level as it lands).
//! Its [`Progress`] is the one the library functions take, so Cancel reaches the
//! inner loops. A [`Slot`] holds the job computing "the current thing": when the
//! key it was started for (scene revision + parameters) changes, the old job is
//! cancelled and a new one started — the whole scheduling policy of the app.
//!
//! Jobs run in one of two rayon pools ([`Priority`]). With one shared pool a probe
//! waits behind every queued row of the field (rayon workers drain their own
//! queues before taking new work): measured 60 s for a 0.2 s probe. Separate pools
//! with different nice values let the interactive work through at once, while the
//! UI thread (nice 0) stays ahead of both.

use crate::progress::{Cancelled, Progress};
use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Called from worker threads when something new is there to show (the app passes
/// `ctx.request_repaint`; tests pass nothing).
pub type Notify = Arc<dyn Fn() + Send + Sync>;

pub fn no_notify() -> Notify {
    Arc::new(|| {})
}

/// Which pool a job's parallel loops run in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Priority {
    /// What the user is waiting for right now (probe, reference): nice 5.
    Interactive,
    /// Long refinements (field, gradient grid): nice 15.
    Background,
}

impl Priority {
    fn nice(self) -> i32 {
        match self {
            Priority::Interactive => 5,
            Priority::Background => 15,
        }
    }

    /// A pool of one job's own, as many threads as the global pool (`--threads`
    /// sets it). Not shared between jobs: a rayon worker waiting in a join runs
    /// any task it can steal, so in a shared pool a cancelled job could wait for a
    /// long task of the job that replaced it (seconds at full resolution) before
    /// it could stop. None when the threads cannot be made (the job then runs in
    /// the global pool).
    fn pool(self) -> Option<rayon::ThreadPool> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(rayon::current_num_threads())
            .thread_name(move |i| format!("volcache-{self:?}-{i}").to_lowercase())
            .start_handler(move |_| super::lower_priority(self.nice()))
            .build()
            .ok()
    }
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Status {
    Running,
    Finished,
    Cancelled,
    /// The worker panicked (a bug): the message is shown instead of crashing the UI.
    Failed(String),
}

const RUNNING: u8 = 0;
const FINISHED: u8 = 1;
const CANCELLED: u8 = 2;
const FAILED: u8 = 3;

/// What the worker and the UI share.
#[derive(Default)]
struct Shared {
    progress: Progress,
    status: AtomicU8,
    /// What is being computed right now (e.g. "level 2/3: 128×128 @ 16 spp").
    stage: Mutex<String>,
    failure: Mutex<String>,
    /// Ray-casting queries of the finished parts of the work.
    rays: AtomicU64,
    /// Wall time when the job ended.
    took: Mutex<Option<Duration>>,
}

/// The worker's side: progress, stage, cost and results.
pub struct Reporter<T> {
    shared: Arc<Shared>,
    tx: Sender<T>,
    notify: Notify,
}

impl<T> Reporter<T> {
    pub fn progress(&self) -> &Progress {
        &self.shared.progress
    }

    pub fn stage(&self, s: impl Into<String>) {
        *self.shared.stage.lock().unwrap() = s.into();
    }

    pub fn add_rays(&self, n: u64) {
        self.shared.rays.fetch_add(n, Ordering::Relaxed);
    }

    /// Hand a result to the UI (ignored if the job was dropped meanwhile).
    pub fn send(&self, value: T) {
        let _ = self.tx.send(value);
        (self.notify)();
    }
}

/// A computation on a background thread.
pub struct Job<T> {
    shared: Arc<Shared>,
    rx: Receiver<T>,
    started: Instant,
    label: String,
}

impl<T: Send + 'static> Job<T> {
    /// Start `work` on a new thread, its parallel loops in the pool of `priority`.
    /// It returns `Err(Cancelled)` when it stopped early; a panic inside it becomes
    /// [`Status::Failed`].
    pub fn spawn(
        label: impl Into<String>,
        priority: Priority,
        notify: Notify,
        work: impl FnOnce(&Reporter<T>) -> Result<(), Cancelled> + Send + 'static,
    ) -> Self {
        let shared = Arc::new(Shared::default());
        let (tx, rx) = channel();
        let started = Instant::now();
        let reporter = Reporter {
            shared: shared.clone(),
            tx,
            notify,
        };
        std::thread::Builder::new()
            .name("volcache-job".into())
            .spawn(move || {
                super::lower_priority(priority.nice());
                let run = || match priority.pool() {
                    Some(pool) => pool.install(|| work(&reporter)),
                    None => work(&reporter),
                };
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(run));
                let s = &reporter.shared;
                *s.took.lock().unwrap() = Some(started.elapsed());
                let code = match r {
                    Ok(Ok(())) => FINISHED,
                    Ok(Err(Cancelled)) => CANCELLED,
                    Err(panic) => {
                        let msg = panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_else(|| "unknown panic".into());
                        *s.failure.lock().unwrap() = msg;
                        FAILED
                    }
                };
                s.status.store(code, Ordering::Release);
                (reporter.notify)();
            })
            .expect("spawning a worker thread");
        Job {
            shared,
            rx,
            started,
            label: label.into(),
        }
    }
}

impl<T> Job<T> {
    /// Results that arrived since the last call, oldest first.
    pub fn poll(&self) -> Vec<T> {
        self.rx.try_iter().collect()
    }

    pub fn cancel(&self) {
        self.shared.progress.cancel();
    }

    pub fn is_cancel_requested(&self) -> bool {
        self.shared.progress.is_cancelled()
    }

    pub fn status(&self) -> Status {
        match self.shared.status.load(Ordering::Acquire) {
            RUNNING => Status::Running,
            FINISHED => Status::Finished,
            CANCELLED => Status::Cancelled,
            _ => Status::Failed(self.shared.failure.lock().unwrap().clone()),
        }
    }

    pub fn is_running(&self) -> bool {
        self.status() == Status::Running
    }

    pub fn label(&self) -> &str {
        &self.label
    }

    pub fn stage(&self) -> String {
        self.shared.stage.lock().unwrap().clone()
    }

    /// Fraction of the current phase done, in [0, 1].
    pub fn fraction(&self) -> f64 {
        self.shared.progress.fraction()
    }

    pub fn rays(&self) -> u64 {
        self.shared.rays.load(Ordering::Relaxed)
    }

    /// Seconds since the start, frozen when the job ends.
    pub fn seconds(&self) -> f64 {
        self.shared
            .took
            .lock()
            .unwrap()
            .unwrap_or_else(|| self.started.elapsed())
            .as_secs_f64()
    }
}

/// A look at a job that outlives the slot's hold on it (tests check that a
/// replaced job was told to stop).
#[derive(Clone)]
pub struct JobWatch(Arc<Shared>);

impl JobWatch {
    pub fn is_cancel_requested(&self) -> bool {
        self.0.progress.is_cancelled()
    }

    pub fn is_running(&self) -> bool {
        self.0.status.load(Ordering::Acquire) == RUNNING
    }
}

impl<T> Job<T> {
    pub fn watch(&self) -> JobWatch {
        JobWatch(self.shared.clone())
    }
}

impl<T> Drop for Job<T> {
    /// A job nobody holds is nobody's business: stop it.
    fn drop(&mut self) {
        self.cancel();
    }
}

/// The job computing the current value of something, with the key it was started
/// for, and the latest result it delivered (kept while a successor computes, so the
/// screen never goes blank).
pub struct Slot<K, T> {
    key: Option<K>,
    job: Option<Job<T>>,
    latest: Option<T>,
    /// `latest` came from the job of the current key (false from the moment the
    /// key changes until the new job delivers): results of an older scene or
    /// older parameters must not pass for the current ones.
    fresh: bool,
    /// How many jobs were started (tests and the status bar read it).
    pub starts: u64,
}

impl<K, T> Default for Slot<K, T> {
    fn default() -> Self {
        Slot {
            key: None,
            job: None,
            latest: None,
            fresh: false,
            starts: 0,
        }
    }
}

impl<K: PartialEq, T: Send + 'static> Slot<K, T> {
    /// Make sure the job for `key` runs or ran: if the key changed, cancel the old
    /// job and start `spawn()`. Returns whether a job was started.
    pub fn ensure(&mut self, key: K, spawn: impl FnOnce() -> Job<T>) -> bool {
        if self.key.as_ref() == Some(&key) {
            return false;
        }
        if let Some(j) = self.job.take() {
            j.cancel();
        }
        self.job = Some(spawn());
        self.key = Some(key);
        self.fresh = false;
        self.starts += 1;
        true
    }

    /// Cancel the job and forget its key (the next `ensure` starts anew); the
    /// latest result stays unless `clear_result`.
    pub fn reset(&mut self, clear_result: bool) {
        if let Some(j) = self.job.take() {
            j.cancel();
        }
        self.key = None;
        self.fresh = false;
        if clear_result {
            self.latest = None;
        }
    }

    /// Cancel the running job but keep its key: nothing restarts until the key
    /// changes (the Cancel button).
    pub fn cancel(&mut self) {
        if let Some(j) = &self.job {
            j.cancel();
        }
    }

    /// Take in new results; returns true if any arrived.
    pub fn update(&mut self) -> bool {
        let Some(j) = &self.job else { return false };
        let mut any = false;
        for r in j.poll() {
            self.latest = Some(r);
            any = true;
        }
        self.fresh |= any;
        any
    }

    pub fn key(&self) -> Option<&K> {
        self.key.as_ref()
    }

    pub fn job(&self) -> Option<&Job<T>> {
        self.job.as_ref()
    }

    /// The latest result, whichever key it was computed for (the field shows its
    /// last level while the next scene's first level computes).
    pub fn latest(&self) -> Option<&T> {
        self.latest.as_ref()
    }

    /// The latest result if it belongs to the current key, else None.
    pub fn current(&self) -> Option<&T> {
        self.latest.as_ref().filter(|_| self.fresh)
    }

    /// The running job, if any.
    pub fn running(&self) -> Option<&Job<T>> {
        self.job.as_ref().filter(|j| j.is_running())
    }

    /// True when the job for the current key delivered everything.
    pub fn is_done(&self) -> bool {
        self.job.as_ref().is_some_and(|j| j.status() == Status::Finished)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait<T>(j: &Job<T>) {
        let t = Instant::now();
        while j.is_running() {
            assert!(t.elapsed() < Duration::from_secs(10), "job did not end");
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    #[test]
    fn results_arrive_in_order_and_the_job_finishes() {
        let j = Job::spawn("count", Priority::Background, no_notify(), |r: &Reporter<u32>| {
            r.progress().start(3);
            for i in 0..3 {
                r.add_rays(10);
                r.progress().advance(1);
                r.send(i);
            }
            Ok(())
        });
        wait(&j);
        assert_eq!(j.poll(), vec![0, 1, 2]);
        assert_eq!(j.status(), Status::Finished);
        assert_eq!((j.rays(), j.fraction()), (30, 1.0));
        let s = j.seconds();
        std::thread::sleep(Duration::from_millis(5));
        assert_eq!(j.seconds(), s, "time freezes at the end");
    }

    /// A job that runs until cancelled.
    fn endless(notify: Notify) -> Job<u32> {
        Job::spawn("endless", Priority::Background, notify, |r: &Reporter<u32>| {
            loop {
                r.progress().check()?;
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    }

    #[test]
    fn cancel_stops_the_worker_and_panics_are_contained() {
        let j = endless(no_notify());
        j.cancel();
        wait(&j);
        assert_eq!(j.status(), Status::Cancelled);
        let bad = Job::spawn("bad", Priority::Interactive, no_notify(), |_: &Reporter<()>| {
            panic!("boom")
        });
        wait(&bad);
        assert_eq!(bad.status(), Status::Failed("boom".into()));
    }

    #[test]
    fn slot_restarts_only_when_the_key_changes() {
        let mut slot: Slot<(u64, u32), u32> = Slot::default();
        assert!(slot.ensure((1, 7), || endless(no_notify())));
        assert!(!slot.ensure((1, 7), || unreachable!("same key: no restart")));
        let first = slot.job().unwrap().shared.clone();
        assert!(slot.ensure((2, 7), || endless(no_notify())));
        assert!(first.progress.is_cancelled(), "the old job was cancelled");
        assert!(!slot.job().unwrap().is_cancel_requested());
        assert_eq!(slot.starts, 2);
        // Cancel keeps the key: no restart for it, but one for a new key.
        slot.cancel();
        assert!(!slot.ensure((2, 7), || unreachable!()));
        assert!(slot.ensure((2, 8), || {
            Job::spawn("one", Priority::Interactive, no_notify(), |r| {
                r.send(5);
                Ok(())
            })
        }));
        wait(slot.job().unwrap());
        assert!(slot.update());
        assert_eq!((slot.latest(), slot.is_done()), (Some(&5), true));
        assert_eq!(slot.current(), Some(&5));
        slot.reset(false);
        assert_eq!((slot.key(), slot.latest()), (None, Some(&5)));
        assert_eq!(slot.current(), None, "no key: nothing is current");
    }

    #[test]
    fn a_result_of_an_older_key_is_not_current() {
        let one = |v: u32| {
            move || {
                Job::spawn("one", Priority::Interactive, no_notify(), move |r| {
                    r.send(v);
                    Ok(())
                })
            }
        };
        let mut slot: Slot<u32, u32> = Slot::default();
        slot.ensure(1, one(10));
        wait(slot.job().unwrap());
        slot.update();
        assert_eq!(slot.current(), Some(&10));
        slot.ensure(2, || endless(no_notify()));
        slot.update();
        assert_eq!((slot.latest(), slot.current()), (Some(&10), None));
        slot.ensure(3, one(30));
        wait(slot.job().unwrap());
        slot.update();
        assert_eq!(slot.current(), Some(&30));
    }

    #[test]
    fn notify_is_called_for_results_and_the_end() {
        let n = Arc::new(AtomicU64::new(0));
        let c = n.clone();
        let j = Job::spawn(
            "n",
            Priority::Interactive,
            Arc::new(move || {
                c.fetch_add(1, Ordering::Relaxed);
            }),
            |r: &Reporter<u8>| {
                r.send(1);
                Ok(())
            },
        );
        wait(&j);
        assert_eq!(n.load(Ordering::Relaxed), 2);
    }
}
