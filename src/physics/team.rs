//! Workers for the parallel step: a team of threads that share a stage's blocks of work.
//!
//! A World with `Settings::workers` above one keeps a [`Team`] of that many workers: the
//! thread that steps the World and `workers - 1` threads of its own. The stepping thread runs
//! the step as it always does; where a stage's work splits into independent blocks (the
//! bundles of one colour, runs of bodies) it hands them out through [`Region::for_blocks`],
//! and every worker takes blocks until none is left. Which worker takes which block changes
//! from run to run; what a block computes does not, and no number is summed across blocks, so
//! the World's results are the same to the bit for any number of workers.
//!
//! Each worker starts a stage at its own share of the blocks and takes from the others' ends
//! only once its own are gone, so that a worker meets, stage after stage, much the same
//! bodies. A stage ends when all its blocks are done, not when every worker has arrived: a
//! worker held up by the operating system delays only the blocks it has taken. Between stages
//! the workers spin briefly, then yield; between steps they sleep.
//!
//! Several Worlds (a daemon's) can share one team through a [`WorkerPool`]: a step takes the
//! team if no other World's step holds it, and otherwise runs on its own thread alone. The
//! results are the same either way, so no step ever waits for another World's.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

pub use crate::physics::settings::MAX_WORKERS;

/// How many times a waiting worker spins before it yields its core.
const SPINS: u32 = 2_000;

/// The most blocks one range holds (its counters are 16 bits); a stage of more runs several
/// blocks for each.
const MAX_BLOCKS: usize = u16::MAX as usize;

/// What the stepping thread and the workers share.
struct Shared {
    /// Workers, the stepping thread included.
    workers: usize,
    /// The current stage's number, published once its ranges are set.
    stage: AtomicU32,
    /// Each worker's range of the current stage's blocks, packed as stage number (32 bits),
    /// next block (16) and end (16): its owner takes blocks from the front, the others, once
    /// their own are gone, from the back. A range of an older stage gives nothing. (A cache
    /// line each: an owner's takes do not contend with the others'.)
    ranges: Box<[Line<AtomicU64>]>,
    /// Blocks done, over all stages (each worker adds its count once per stage).
    done: Line<AtomicUsize>,
    /// The current stage's block runner, its lifetime erased: written by the stepping thread
    /// while no block is taken, read by a worker only once it holds one of the stage's blocks
    /// (the stage cannot end, nor the runner change, before that block is done).
    run: UnsafeCell<*const (dyn Fn(usize) + Sync)>,
    /// Regions begun; a sleeping worker wakes for the next.
    regions: Mutex<u64>,
    wake: Condvar,
    /// Set when the current region's last stage is done: its workers leave.
    finished: AtomicBool,
    /// Workers that have left the current region.
    left: AtomicUsize,
    /// Set when a block panicked (the stepping thread panics in turn).
    panicked: AtomicBool,
    /// Set when the team is dropped.
    quit: AtomicBool,
}

// SAFETY: `run` is written only while no worker can read it (see `Shared::run`), and the
// runner it points to is `Sync`; everything else is atomic or locked.
unsafe impl Sync for Shared {}
// SAFETY: as above.
unsafe impl Send for Shared {}

/// The workers of one World.
pub struct Team {
    shared: Arc<Shared>,
    threads: Vec<JoinHandle<()>>,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("workers", &self.workers())
            .finish()
    }
}

impl Team {
    /// A team of `workers` (the calling thread and `workers - 1` new threads), clamped to
    /// 2..=[`MAX_WORKERS`]; the error is the system's, when it cannot start a thread.
    pub fn new(workers: u32) -> std::io::Result<Team> {
        let workers = workers.clamp(2, MAX_WORKERS) as usize;
        let noop: &'static (dyn Fn(usize) + Sync) = &|_| {};
        let shared = Arc::new(Shared {
            workers,
            stage: AtomicU32::new(0),
            ranges: (0..workers).map(|_| Line(AtomicU64::new(0))).collect(),
            done: Line(AtomicUsize::new(0)),
            run: UnsafeCell::new(noop),
            regions: Mutex::new(0),
            wake: Condvar::new(),
            finished: AtomicBool::new(false),
            left: AtomicUsize::new(0),
            panicked: AtomicBool::new(false),
            quit: AtomicBool::new(false),
        });
        let mut team = Team {
            shared,
            threads: Vec::new(),
        };
        for me in 1..workers {
            let shared = Arc::clone(&team.shared);
            let thread = std::thread::Builder::new()
                .name(format!("tiltbox-worker-{me}"))
                .spawn(move || worker(&shared, me))?;
            team.threads.push(thread);
        }
        Ok(team)
    }

    /// How many workers, the stepping thread included.
    pub fn workers(&self) -> u32 {
        self.shared.workers as u32
    }

    /// Regions run so far.
    #[cfg(test)]
    pub fn regions(&self) -> u64 {
        *self
            .shared
            .regions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
    }

    /// Run `body` on this thread with the workers awake to take the blocks it hands out;
    /// returns when they have all left.
    pub fn region<R>(&mut self, body: impl FnOnce(&Region) -> R) -> R {
        let shared = &*self.shared;
        shared.finished.store(false, Ordering::Relaxed);
        shared.left.store(0, Ordering::Relaxed);
        {
            let mut regions = shared.regions.lock().unwrap_or_else(|e| e.into_inner());
            *regions += 1;
        }
        shared.wake.notify_all();
        // The workers leave when the body returns, or unwinds.
        let _leave = Leave {
            shared,
            workers: self.threads.len(),
        };
        body(&Region {
            shared,
            _not_send: PhantomData,
        })
    }
}

/// One [`Team`] that several Worlds share (`World::share_workers`): each step takes it if it is
/// free and otherwise steps alone on its own thread, never waiting for another World's step.
/// Cloning shares the same team.
#[derive(Clone, Debug)]
pub struct WorkerPool {
    team: Arc<Mutex<Team>>,
    workers: u32,
    /// Steps that took the team.
    taken: Arc<AtomicU64>,
}

impl WorkerPool {
    /// A pool of `workers` (the stepping thread and `workers - 1` threads), clamped to
    /// 2..=[`MAX_WORKERS`]; the error is the system's, when it cannot start a thread.
    pub fn new(workers: u32) -> std::io::Result<WorkerPool> {
        let team = Team::new(workers)?;
        Ok(WorkerPool {
            workers: team.workers(),
            team: Arc::new(Mutex::new(team)),
            taken: Arc::new(AtomicU64::new(0)),
        })
    }

    /// How many workers, the stepping thread included.
    pub fn workers(&self) -> u32 {
        self.workers
    }

    /// Steps (of any World sharing the pool) that have taken its workers so far.
    pub fn steps_shared(&self) -> u64 {
        self.taken.load(Ordering::Relaxed)
    }

    /// The team for a step, if no other step holds it (counted in
    /// [`WorkerPool::steps_shared`]).
    pub(crate) fn take(&self) -> Option<std::sync::MutexGuard<'_, Team>> {
        let team = self.lock()?;
        self.taken.fetch_add(1, Ordering::Relaxed);
        Some(team)
    }

    /// The team, if no other step holds it. A step that panicked left it whole (its region
    /// waited for the workers to leave), so a poisoned lock is taken as it is.
    pub(crate) fn lock(&self) -> Option<std::sync::MutexGuard<'_, Team>> {
        match self.team.try_lock() {
            Ok(team) => Some(team),
            Err(std::sync::TryLockError::Poisoned(e)) => Some(e.into_inner()),
            Err(std::sync::TryLockError::WouldBlock) => None,
        }
    }

    /// Whether `self` and `other` are the same pool.
    pub fn same(&self, other: &WorkerPool) -> bool {
        Arc::ptr_eq(&self.team, &other.team)
    }
}

/// Ends a region when dropped: tells its workers to leave and waits until they have.
struct Leave<'t> {
    shared: &'t Shared,
    workers: usize,
}

impl Drop for Leave<'_> {
    fn drop(&mut self) {
        self.shared.finished.store(true, Ordering::Release);
        let mut spins = 0;
        while self.shared.left.load(Ordering::Acquire) < self.workers {
            pause(&mut spins);
        }
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.quit.store(true, Ordering::Release);
        {
            let mut regions = self
                .shared
                .regions
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            *regions += 1;
        }
        self.shared.wake.notify_all();
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
    }
}

/// A region of the step in which the workers are awake: the stepping thread's handle for
/// handing out blocks.
pub struct Region<'t> {
    shared: &'t Shared,
    /// Only the stepping thread hands out work.
    _not_send: PhantomData<*const ()>,
}

impl Region<'_> {
    /// Run `run(k)` for every block k in `0..blocks`, spread over the workers (this thread
    /// among them); returns when all are done. Blocks must be independent of one another.
    /// Worker w starts at the w-th of as many equal runs of the blocks, so that a worker
    /// meets, stage after stage, much the same bodies (the colours' bundles lie in key
    /// order, which follows the bodies' order), as Box2D's solver does.
    pub fn for_blocks(&self, blocks: usize, run: &(dyn Fn(usize) + Sync)) {
        if blocks > MAX_BLOCKS {
            let per = blocks.div_ceil(MAX_BLOCKS);
            let grouped = |k: usize| (k * per..((k + 1) * per).min(blocks)).for_each(run);
            return self.for_blocks(blocks.div_ceil(per), &grouped);
        }
        if blocks <= 1 {
            // One block: run here, without waking the others for it (they wait meanwhile,
            // as they would for a stage).
            if blocks == 1 {
                run(0);
            }
            return;
        }
        let shared = self.shared;
        let target = shared.done.0.load(Ordering::Acquire) + blocks;
        // SAFETY: every block of every earlier stage is done, so no worker holds one and none
        // reads `run` until a range below publishes this stage. The lifetime is erased: this
        // call returns only once every block has run, after which no worker calls it.
        unsafe {
            let run: *const (dyn Fn(usize) + Sync + '_) = run;
            *shared.run.get() = std::mem::transmute::<
                *const (dyn Fn(usize) + Sync + '_),
                *const (dyn Fn(usize) + Sync + 'static),
            >(run);
        }
        let stage = shared.stage.load(Ordering::Relaxed).wrapping_add(1);
        let workers = shared.workers;
        for (w, range) in shared.ranges.iter().enumerate() {
            let (start, end) = (w * blocks / workers, (w + 1) * blocks / workers);
            range.0.store(pack(stage, start, end), Ordering::Release);
        }
        shared.stage.store(stage, Ordering::Release);
        run_stage(shared, 0, stage);
        let mut spins = 0;
        while shared.done.0.load(Ordering::Acquire) < target {
            pause(&mut spins);
        }
        if shared.panicked.swap(false, Ordering::Relaxed) {
            panic!("a worker's block panicked");
        }
    }
}

/// A range: stage number, next block, end.
fn pack(stage: u32, next: usize, end: usize) -> u64 {
    u64::from(stage) << 32 | (next as u64) << 16 | end as u64
}

/// Take a block of `range` in `stage`, from the front or the back; None when it has none.
fn take(range: &AtomicU64, stage: u32, front: bool) -> Option<usize> {
    let mut v = range.load(Ordering::Acquire);
    loop {
        let (next, end) = ((v >> 16 & 0xFFFF) as usize, (v & 0xFFFF) as usize);
        if (v >> 32) as u32 != stage || next >= end {
            return None;
        }
        let (taken, new) = if front {
            (next, v + (1 << 16))
        } else {
            (end - 1, v - 1)
        };
        match range.compare_exchange_weak(v, new, Ordering::AcqRel, Ordering::Acquire) {
            Ok(_) => return Some(taken),
            Err(now) => v = now,
        }
    }
}

/// Worker `me`'s part in `stage`: its own range from the front, then the others' from the
/// back.
fn run_stage(shared: &Shared, me: usize, stage: u32) {
    let workers = shared.workers;
    let ranges = &shared.ranges;
    let order = (0..workers).map(|d| ((me + d) % workers, d == 0));
    let mut done = 0;
    for (w, own) in order {
        while let Some(k) = take(&ranges[w].0, stage, own) {
            // SAFETY: we hold block k of `stage` (and count it done only below), so the stage
            // cannot end and its runner (published before the range) stays.
            let run = unsafe { &**shared.run.get() };
            let ran = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(k)));
            if ran.is_err() {
                shared.panicked.store(true, Ordering::Relaxed);
            }
            done += 1;
        }
    }
    if done > 0 {
        shared.done.0.fetch_add(done, Ordering::Release);
    }
}

/// A value alone on its cache line (two lines: processors fetch lines in pairs).
#[repr(align(128))]
struct Line<T>(T);

/// Worker `me` (1 or more): sleep until a region begins, take part in each stage until it
/// ends, sleep again.
fn worker(shared: &Shared, me: usize) {
    let mut seen = 0u64;
    loop {
        {
            let mut regions = shared.regions.lock().unwrap_or_else(|e| e.into_inner());
            while *regions == seen {
                regions = shared.wake.wait(regions).unwrap_or_else(|e| e.into_inner());
            }
            seen = *regions;
        }
        if shared.quit.load(Ordering::Acquire) {
            return;
        }
        let (mut last, mut spins) = (shared.stage.load(Ordering::Acquire), 0);
        run_stage(shared, me, last);
        loop {
            let stage = shared.stage.load(Ordering::Acquire);
            if stage != last {
                last = stage;
                run_stage(shared, me, stage);
                spins = 0;
            } else if shared.finished.load(Ordering::Acquire) {
                break;
            } else {
                pause(&mut spins);
            }
        }
        shared.left.fetch_add(1, Ordering::Release);
    }
}

/// Wait a little: spin at first, then give the core away.
#[inline]
fn pause(spins: &mut u32) {
    if *spins < SPINS {
        *spins += 1;
        std::hint::spin_loop();
    } else {
        std::thread::yield_now();
    }
}

/// A slice that several workers write at once, each through parts no other touches.
pub(crate) struct SharedSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _items: PhantomData<&'a mut [T]>,
}

impl<T> Clone for SharedSlice<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for SharedSlice<'_, T> {}

// SAFETY: made only by the unsafe `SharedSlice::new`, whose caller promises disjoint use.
unsafe impl<T: Send> Send for SharedSlice<'_, T> {}
unsafe impl<T: Send> Sync for SharedSlice<'_, T> {}

impl<'a, T> SharedSlice<'a, T> {
    /// `items`, for several workers.
    ///
    /// # Safety
    /// While any copy is in use, no item may be reached through two workers at once, and
    /// nothing else may use `items`.
    pub unsafe fn new(items: &'a mut [T]) -> SharedSlice<'a, T> {
        SharedSlice {
            ptr: items.as_mut_ptr(),
            len: items.len(),
            _items: PhantomData,
        }
    }

    /// How many items.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Where item `i` is, to read or write one field of it. Panics past the end.
    ///
    /// # Safety
    /// What is read through it must not be written by another worker meanwhile.
    pub unsafe fn item(&self, i: usize) -> *const T {
        assert!(i < self.len);
        self.ptr.add(i)
    }

    /// Items `range`, to write. Panics past the end.
    ///
    /// # Safety
    /// No other worker may reach these items while the slice lives.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn range(&self, range: std::ops::Range<usize>) -> &'a mut [T] {
        assert!(range.start <= range.end && range.end <= self.len);
        std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.end - range.start)
    }

    /// Item `i`, to write; None past the end.
    ///
    /// # Safety
    /// As [`SharedSlice::range`].
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn get(&self, i: usize) -> Option<&'a mut T> {
        (i < self.len).then(|| &mut *self.ptr.add(i))
    }
}

/// Block `k` of `len` items cut into blocks of `size`.
#[inline]
pub(crate) fn block(k: usize, size: usize, len: usize) -> std::ops::Range<usize> {
    (k * size).min(len)..((k + 1) * size).min(len)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every block of every stage runs exactly once, whatever the number of workers, and a
    /// stage's writes are all seen by the next stage.
    #[test]
    fn every_block_runs_once_and_stages_follow_each_other() {
        for workers in [2, 3, 4] {
            let mut team = Team::new(workers).expect("threads start");
            let mut cells = vec![0u64; 1000];
            for round in 0..50u64 {
                team.region(|r| {
                    for stage in 0..5u64 {
                        // SAFETY: each block writes its own run of cells.
                        let items = unsafe { SharedSlice::new(&mut cells) };
                        let size = 7;
                        r.for_blocks(1000usize.div_ceil(size), &|k| {
                            for c in unsafe { items.range(block(k, size, 1000)) } {
                                // Each stage reads what the last stage wrote.
                                assert_eq!(*c, round * 5 + stage);
                                *c += 1;
                            }
                        });
                    }
                });
            }
            assert!(cells.iter().all(|&c| c == 250), "{workers} workers");
        }
    }

    /// A block that panics on a worker makes the stepping thread panic, and the team goes on.
    #[test]
    fn a_panicking_block_is_reported() {
        let mut team = Team::new(2).expect("threads start");
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            team.region(|r| r.for_blocks(64, &|k| assert!(k != 40, "block 40")))
        }));
        assert!(caught.is_err());
        let count = AtomicUsize::new(0);
        team.region(|r| {
            r.for_blocks(10, &|_| {
                count.fetch_add(1, Ordering::Relaxed);
            })
        });
        assert_eq!(count.load(Ordering::Relaxed), 10);
    }
}
