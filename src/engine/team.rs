//! A fixed team of threads for the force passes of one simulation.
//!
//! A step of a few thousand particles takes a few hundred microseconds and
//! has several parallel passes. A general work-stealing pool puts its idle
//! workers to sleep between them, and on the virtual machines this project
//! runs on, waking a sleeping thread costs tens of microseconds: measured on
//! the 4,336-particle compaction packing, two threads of `rayon::scope` per
//! pass were slower than one. The team's workers instead wait for the next
//! pass by spinning, and sleep only after [`IDLE_BEFORE_SLEEP`] without
//! work (between stages, while a study analyses), as OpenMP runtimes do.
//! A wait longer than [`SPIN_BEFORE_YIELD`] offers the core to other
//! threads at every look: on a machine with more busy threads than cores
//! (two runs side by side, a build), the thread being waited for may need
//! the very core the waiter spins on. Spinning alone, two threads of the
//! 4,336-particle packing took 26 s instead of 2.4 s beside a compiler.
//!
//! A pass is `run(|chunk| ...)`: chunk 0 runs on the calling thread, chunk
//! `c` on worker `c`, and `run` returns when all are done. Which chunk runs
//! where is fixed, so a pass whose chunks write disjoint data gives the same
//! result on every run.

use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a worker spins for the next pass before it sleeps.
pub const IDLE_BEFORE_SLEEP: Duration = Duration::from_millis(2);

/// How long a waiting thread spins before it yields its core at each look.
pub const SPIN_BEFORE_YIELD: Duration = Duration::from_micros(50);

/// A waiting thread's pace: spin while the wait is short, then yield.
///
/// Most waits end within a few hundred looks, before the clock is first
/// read: reading it costs more than a short pass on some virtual machines.
struct Patience {
    since: Option<Instant>,
    looks: u32,
    yielding: bool,
}

/// Looks before a wait starts timing itself, and between clock reads.
const LOOKS_PER_CLOCK_READ: u32 = 256;

impl Patience {
    fn new() -> Self {
        Self {
            since: None,
            looks: 0,
            yielding: false,
        }
    }

    /// Waits a little after a look that found nothing.
    #[inline]
    fn snooze(&mut self) {
        if self.yielding {
            std::thread::yield_now();
            return;
        }
        std::hint::spin_loop();
        self.looks = self.looks.wrapping_add(1);
        if self.looks % LOOKS_PER_CLOCK_READ == 0 {
            let since = *self.since.get_or_insert_with(Instant::now);
            self.yielding = since.elapsed() >= SPIN_BEFORE_YIELD;
        }
    }

    /// How long the wait has been timed (it starts timing itself only after
    /// [`LOOKS_PER_CLOCK_READ`] looks).
    fn waited(&self) -> Duration {
        self.since.map_or(Duration::ZERO, |t| t.elapsed())
    }
}

/// The pass being run, as seen by the workers.
type Job = *const (dyn Fn(usize) + Sync);

struct Shared {
    /// Counts passes; a worker starts the pass when it sees it change.
    epoch: AtomicU64,
    /// Workers that have not finished the current pass.
    running: AtomicUsize,
    /// The current pass; written by the caller before `epoch` moves on
    /// and read by workers after they see it move.
    job: UnsafeCell<Option<Job>>,
    /// Per worker: whether it is asleep (or about to be) and needs waking.
    asleep: Vec<AtomicBool>,
    /// A worker's chunk panicked in the current pass.
    panicked: AtomicBool,
    /// The team is being dropped.
    stop: AtomicBool,
}

// SAFETY: `job` is written only by the thread that runs a pass, while no
// worker reads it (every worker has finished the previous pass and waits
// for `epoch` to move), and read by workers only between that move and
// their decrement of `running`, while the caller waits. The job itself is
// `Sync`.
unsafe impl Sync for Shared {}
unsafe impl Send for Shared {}

/// Threads that run the chunks of a pass together; see the module docs.
pub struct Team {
    shared: Arc<Shared>,
    workers: Vec<JoinHandle<()>>,
    /// Set while a pass runs: a second caller (another thread, or a pass
    /// started inside a pass) runs its chunks itself instead of waiting.
    busy: AtomicBool,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("threads", &self.threads())
            .finish()
    }
}

impl Team {
    /// A team of `threads` threads in all (the caller and `threads - 1`
    /// workers); 0 counts as 1.
    pub fn new(threads: usize) -> Self {
        let workers = threads.max(1) - 1;
        let shared = Arc::new(Shared {
            epoch: AtomicU64::new(0),
            running: AtomicUsize::new(0),
            job: UnsafeCell::new(None),
            asleep: (0..workers).map(|_| AtomicBool::new(false)).collect(),
            panicked: AtomicBool::new(false),
            stop: AtomicBool::new(false),
        });
        let workers = (0..workers)
            .map(|w| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("bpm-team-{}", w + 1))
                    .spawn(move || work(&shared, w))
                    .expect("starting a thread of the force team")
            })
            .collect();
        Self {
            shared,
            workers,
            busy: AtomicBool::new(false),
        }
    }

    /// Threads in the team, the caller's included.
    pub fn threads(&self) -> usize {
        self.workers.len() + 1
    }

    /// Runs `job(c)` for every chunk `c` in `0..self.threads()`, chunk 0 on
    /// the calling thread, and returns when all have finished. A panic in
    /// any chunk is raised here once all have finished.
    pub fn run<F: Fn(usize) + Sync>(&self, job: F) {
        let n = self.threads();
        if n == 1 || self.busy.swap(true, Ordering::Acquire) {
            (0..n).for_each(&job);
            return;
        }
        let shared = &*self.shared;
        let erased: &(dyn Fn(usize) + Sync) = &job;
        // SAFETY: no worker reads `job` now (see `Shared`); the pointer is
        // used only until `running` reaches 0 below, while `job` lives.
        unsafe {
            *shared.job.get() =
                Some(std::mem::transmute::<*const (dyn Fn(usize) + Sync + '_), Job>(erased));
        }
        shared.running.store(n - 1, Ordering::Relaxed);
        shared.epoch.fetch_add(1, Ordering::SeqCst);
        #[cfg(test)]
        tests::hold_caller(self);
        self.wake_sleepers();
        let mine = catch_unwind(AssertUnwindSafe(|| job(0)));
        let mut patience = Patience::new();
        while shared.running.load(Ordering::Acquire) != 0 {
            patience.snooze();
        }
        // SAFETY: every worker has finished with the pass.
        unsafe { *shared.job.get() = None };
        let theirs = shared.panicked.swap(false, Ordering::Relaxed);
        self.busy.store(false, Ordering::Release);
        if let Err(payload) = mine {
            resume_unwind(payload);
        }
        assert!(!theirs, "a thread of the force team panicked");
    }

    /// Runs `job(c, &mut items[c])` for every chunk `c`; `items` must have
    /// one entry per thread.
    pub fn run_on<T: Send, F: Fn(usize, &mut T) + Sync>(&self, items: &mut [T], job: F) {
        assert_eq!(items.len(), self.threads(), "one item per thread");
        let items = SharedSlice::new(items);
        // SAFETY: chunk c touches only items[c], and each chunk runs once.
        self.run(|c| job(c, unsafe { items.get(c) }));
    }

    /// Runs `job(c, range, &mut data[range])` for the `c`-th of
    /// `self.threads()` nearly equal contiguous ranges of `data`
    /// ([`chunk_range`]).
    pub fn run_split<T: Send, F: Fn(usize, std::ops::Range<usize>, &mut [T]) + Sync>(
        &self,
        data: &mut [T],
        job: F,
    ) {
        let chunks = self.threads();
        let len = data.len();
        let data = SharedSlice::new(data);
        self.run(|c| {
            let range = chunk_range(len, chunks, c);
            // SAFETY: the chunks' ranges are disjoint.
            let part = unsafe { data.range(range.clone()) };
            job(c, range, part)
        });
    }

    /// Runs `job(c, &mut data[ranges[c]], &mut items[c])` for every chunk
    /// `c`; the ranges must lie in `data` in chunk order without overlap,
    /// and `ranges` and `items` must have one entry per thread.
    pub fn run_parts<T, I, F>(
        &self,
        data: &mut [T],
        ranges: &[std::ops::Range<usize>],
        items: &mut [I],
        job: F,
    ) where
        T: Send,
        I: Send,
        F: Fn(usize, &mut [T], &mut I) + Sync,
    {
        assert_eq!(items.len(), self.threads(), "one item per thread");
        assert_eq!(ranges.len(), self.threads(), "one range per thread");
        let mut end = 0;
        for (c, range) in ranges.iter().enumerate() {
            assert!(
                end <= range.start && range.start <= range.end && range.end <= data.len(),
                "part {c}, {range:?}, overlaps the one before (to {end}) or leaves {} items",
                data.len()
            );
            end = range.end;
        }
        let (data, items) = (SharedSlice::new(data), SharedSlice::new(items));
        self.run(|c| {
            // SAFETY: the ranges are disjoint (checked above, and the
            // slice cannot change meanwhile), and chunk c alone takes
            // items[c].
            let (part, item) = unsafe { (data.range(ranges[c].clone()), items.get(c)) };
            job(c, part, item)
        });
    }

    /// [`Team::run_split`] over two slices of one length at once.
    pub fn run_split2<A, B, F>(&self, a: &mut [A], b: &mut [B], job: F)
    where
        A: Send,
        B: Send,
        F: Fn(std::ops::Range<usize>, &mut [A], &mut [B]) + Sync,
    {
        assert_eq!(a.len(), b.len(), "split of two slices of one length");
        let chunks = self.threads();
        let len = a.len();
        let (a, b) = (SharedSlice::new(a), SharedSlice::new(b));
        self.run(|c| {
            let range = chunk_range(len, chunks, c);
            // SAFETY: the chunks' ranges are disjoint.
            let (pa, pb) = unsafe { (a.range(range.clone()), b.range(range.clone())) };
            job(range, pa, pb)
        });
    }

    /// The results of `job(range)` over the team's [`chunk_range`]s of
    /// `0..len`, in chunk order, folded with `merge` from `init`.
    pub fn map_reduce<R, F, M>(&self, len: usize, init: R, job: F, merge: M) -> R
    where
        R: Send + Copy,
        F: Fn(std::ops::Range<usize>) -> R + Sync,
        M: Fn(R, R) -> R,
    {
        let chunks = self.threads();
        self.reduce_chunks(init, |c| job(chunk_range(len, chunks, c)), merge)
    }

    /// The results of `job(c)` for every chunk `c`, in chunk order, folded
    /// with `merge` from `init`.
    pub fn reduce_chunks<R, F, M>(&self, init: R, job: F, merge: M) -> R
    where
        R: Send + Copy,
        F: Fn(usize) -> R + Sync,
        M: Fn(R, R) -> R,
    {
        let chunks = self.threads();
        if chunks == 1 {
            return merge(init, job(0));
        }
        // On the stack for teams of up to 64, so a step allocates nothing.
        let mut on_stack = [init; 64];
        let mut on_heap = Vec::new();
        let results = if chunks <= on_stack.len() {
            &mut on_stack[..chunks]
        } else {
            on_heap.resize(chunks, init);
            &mut on_heap[..]
        };
        self.run_on(results, |c, r| *r = job(c));
        results.iter().fold(init, |acc, &r| merge(acc, r))
    }

    /// Runs `job(c, [(range, part); 2])` where `data` is two sections,
    /// `0..split` and `split..len`, and chunk `c` gets the `c`-th of the
    /// team's [`chunk_range`]s of each (as ranges of `data` and the parts
    /// themselves); the chunk's result goes to `results[c]`, which must have
    /// one entry per thread.
    pub fn run_sections<T, R, F>(&self, data: &mut [T], split: usize, results: &mut [R], job: F)
    where
        T: Send,
        R: Send,
        F: Fn(usize, [(std::ops::Range<usize>, &mut [T]); 2]) -> R + Sync,
    {
        assert!(
            split <= data.len(),
            "section split {split} beyond {}",
            data.len()
        );
        assert_eq!(results.len(), self.threads(), "one result per thread");
        let chunks = self.threads();
        let len = data.len();
        let data = SharedSlice::new(data);
        let results = SharedSlice::new(results);
        self.run(|c| {
            let first = chunk_range(split, chunks, c);
            let second = chunk_range(len - split, chunks, c);
            let second = split + second.start..split + second.end;
            // SAFETY: the chunks' ranges are disjoint, and chunk c alone
            // writes results[c].
            let parts = unsafe {
                [
                    (first.clone(), data.range(first)),
                    (second.clone(), data.range(second)),
                ]
            };
            let result = job(c, parts);
            unsafe { *results.get(c) = result };
        });
    }

    fn wake_sleepers(&self) {
        for (flag, worker) in self.shared.asleep.iter().zip(&self.workers) {
            if flag.swap(false, Ordering::SeqCst) {
                worker.thread().unpark();
            }
        }
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        self.shared.epoch.fetch_add(1, Ordering::SeqCst);
        for worker in &self.workers {
            worker.thread().unpark();
        }
        for worker in self.workers.drain(..) {
            let _ = worker.join();
        }
    }
}

/// A worker's life: wait for a pass, run its chunk, report, repeat.
fn work(shared: &Shared, w: usize) {
    let mut seen = 0;
    loop {
        seen = wait_for_pass(shared, w, seen);
        if shared.stop.load(Ordering::Acquire) {
            return;
        }
        // SAFETY: the caller wrote the job before moving `epoch`, and keeps
        // it alive until `running` reaches 0.
        let job = unsafe { (*shared.job.get()).expect("a pass is running") };
        let chunk = w + 1;
        if catch_unwind(AssertUnwindSafe(|| unsafe { (*job)(chunk) })).is_err() {
            shared.panicked.store(true, Ordering::Relaxed);
        }
        shared.running.fetch_sub(1, Ordering::Release);
    }
}

/// Waits until `epoch` differs from `seen` (spinning, then yielding, see
/// [`Patience`]), sleeping after [`IDLE_BEFORE_SLEEP`]; returns the new
/// epoch.
fn wait_for_pass(shared: &Shared, w: usize, seen: u64) -> u64 {
    let mut patience = Patience::new();
    loop {
        let epoch = shared.epoch.load(Ordering::Acquire);
        if epoch != seen {
            return epoch;
        }
        if !patience.yielding || patience.waited() < IDLE_BEFORE_SLEEP {
            patience.snooze();
            continue;
        }
        // Announce the sleep, then look once more: the caller moves
        // `epoch` before it reads the flag, so one of the two sees the
        // other (both sequentially consistent). Announce again before
        // every park: the caller of the pass this worker has already run
        // may clear the flag (and unpark) late, after being held up
        // between moving `epoch` and waking; parking again without the
        // flag would let the next pass skip the wake-up and wait forever.
        loop {
            shared.asleep[w].store(true, Ordering::SeqCst);
            if shared.epoch.load(Ordering::SeqCst) != seen {
                break;
            }
            std::thread::park();
        }
        shared.asleep[w].store(false, Ordering::SeqCst);
    }
}

/// Splits `0..len` into `chunks` nearly equal contiguous ranges.
pub fn chunk_range(len: usize, chunks: usize, c: usize) -> std::ops::Range<usize> {
    let start = len * c / chunks;
    let end = len * (c + 1) / chunks;
    start..end
}

/// A mutable slice handed to the chunks of a pass, each taking its own
/// disjoint part.
pub(super) struct SharedSlice<T> {
    ptr: *mut T,
    len: usize,
}

// SAFETY: chunks take disjoint parts (the callers' contract), and `T: Send`.
unsafe impl<T: Send> Sync for SharedSlice<T> {}

impl<T> SharedSlice<T> {
    /// The slice's length.
    pub(super) fn len(&self) -> usize {
        self.len
    }

    pub(super) fn new(slice: &mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
        }
    }

    /// # Safety
    /// No other live reference to element `i`.
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn get(&self, i: usize) -> &mut T {
        assert!(i < self.len);
        &mut *self.ptr.add(i)
    }

    /// # Safety
    /// No other live reference into `range`.
    #[allow(clippy::mut_from_ref)]
    pub(super) unsafe fn range(&self, range: std::ops::Range<usize>) -> &mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// Teams whose caller is held up, once, between moving `epoch` and
    /// waking the sleepers, for the given time: the preemption of a busy
    /// machine, at the one place where it matters.
    static HOLDS: Mutex<Vec<(usize, Duration)>> = Mutex::new(Vec::new());

    pub(super) fn hold_caller(team: &Team) {
        let id = team as *const Team as usize;
        let hold = {
            let mut holds = HOLDS.lock().unwrap();
            let at = holds.iter().position(|&(t, _)| t == id);
            at.map(|k| holds.swap_remove(k).1)
        };
        if let Some(hold) = hold {
            std::thread::sleep(hold);
        }
    }

    /// A worker that ran its chunk and fell asleep before the pass's caller
    /// woke it must still be woken by the next pass. It used to park again
    /// without announcing it (its flag cleared by that late wake-up), and
    /// the next pass then waited for it forever.
    #[test]
    fn a_worker_woken_late_is_woken_by_the_next_pass() {
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let team = Team::new(2);
            let count = AtomicUsize::new(0);
            team.run(|_| {
                count.fetch_add(1, Ordering::Relaxed);
            });
            // The worker is spinning for the next pass: it runs its chunk
            // while the caller is held, then falls asleep.
            HOLDS
                .lock()
                .unwrap()
                .push((&team as *const Team as usize, IDLE_BEFORE_SLEEP * 4));
            for _ in 0..3 {
                team.run(|_| {
                    count.fetch_add(1, Ordering::Relaxed);
                });
                // Time for the worker, woken late, to park again.
                std::thread::sleep(IDLE_BEFORE_SLEEP / 2);
            }
            done.send(count.load(Ordering::Relaxed)).unwrap();
        });
        let count = finished
            .recv_timeout(Duration::from_secs(20))
            .expect("the team hung: a pass waited for a worker that was never woken");
        assert_eq!(count, 8);
    }

    #[test]
    fn every_chunk_runs_once_per_pass_on_its_own_thread() {
        let team = Team::new(3);
        let mut hits = vec![0u32; 3];
        for _ in 0..1000 {
            team.run_on(&mut hits, |_, h| *h += 1);
        }
        assert_eq!(hits, vec![1000; 3]);
        let ids = std::sync::Mutex::new(Vec::new());
        team.run(|c| ids.lock().unwrap().push((c, std::thread::current().id())));
        let mut ids = ids.into_inner().unwrap();
        ids.sort_by_key(|&(c, _)| c);
        assert_eq!(ids[0].1, std::thread::current().id());
        assert!(ids[1].1 != ids[0].1 && ids[2].1 != ids[1].1);
    }

    #[test]
    fn split_covers_the_slice_in_order() {
        let team = Team::new(2);
        let mut data = vec![0usize; 101];
        team.run_split(&mut data, |_, range, part| {
            for (k, d) in range.zip(part.iter_mut()) {
                *d = k;
            }
        });
        assert_eq!(data, (0..101).collect::<Vec<_>>());
    }

    #[test]
    fn workers_wake_after_sleeping() {
        let team = Team::new(2);
        let mut hits = vec![0u32; 2];
        team.run_on(&mut hits, |_, h| *h += 1);
        std::thread::sleep(IDLE_BEFORE_SLEEP * 3);
        team.run_on(&mut hits, |_, h| *h += 1);
        assert_eq!(hits, vec![2, 2]);
    }

    #[test]
    fn a_panic_in_a_worker_reaches_the_caller_and_the_team_goes_on() {
        let team = Team::new(2);
        let caught = catch_unwind(AssertUnwindSafe(|| {
            team.run(|c| assert!(c == 0, "chunk {c} fails on purpose"))
        }));
        assert!(caught.is_err());
        let mut hits = vec![0u32; 2];
        team.run_on(&mut hits, |_, h| *h += 1);
        assert_eq!(hits, vec![1, 1]);
    }

    #[test]
    fn a_pass_inside_a_pass_runs_on_the_caller() {
        let team = Team::new(2);
        let total = AtomicUsize::new(0);
        team.run(|_| {
            team.run(|_| {
                total.fetch_add(1, Ordering::Relaxed);
            })
        });
        assert_eq!(total.load(Ordering::Relaxed), 4);
    }
}
