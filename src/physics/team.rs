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
//! Blocks are taken from one counter that only grows (a ticket per block, each stage's
//! tickets following the last's), so a worker that comes late to a stage finds nothing left
//! and nothing is reset between stages. A stage ends when all its blocks are done, not when
//! every worker has arrived: a worker held up by the operating system delays only the blocks
//! it has taken. Between stages the workers spin briefly, then yield; between steps they
//! sleep.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// The most workers a World may have (`Settings::workers`).
pub const MAX_WORKERS: u32 = 64;

/// How many times a waiting worker spins before it yields its core.
const SPINS: u32 = 2_000;

/// A stage's work as the workers see it: a block runner with its lifetime erased, and the
/// first ticket of the stage.
#[derive(Clone, Copy)]
struct Task {
    run: *const (dyn Fn(usize) + Sync),
    base: usize,
}

/// What the stepping thread and the workers share.
struct Shared {
    /// Tickets below this are open to take.
    open: AtomicUsize,
    /// The next ticket to take.
    next: AtomicUsize,
    /// Tickets whose block is done.
    done: AtomicUsize,
    /// The current stage: written by the stepping thread only while every ticket handed out
    /// is done, read by a worker only after it has taken one of the stage's tickets.
    task: UnsafeCell<Task>,
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

// SAFETY: `task` is written only while no worker can read it (see `Shared::task`), and the
// runner it points to is `Sync`; everything else is atomic or locked.
unsafe impl Sync for Shared {}
// SAFETY: as above; the raw pointer in `task` is used only under the same rule.
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
        let workers = workers.clamp(2, MAX_WORKERS);
        let noop: &'static (dyn Fn(usize) + Sync) = &|_| {};
        let shared = Arc::new(Shared {
            open: AtomicUsize::new(0),
            next: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            task: UnsafeCell::new(Task { run: noop, base: 0 }),
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
        for i in 1..workers {
            let shared = Arc::clone(&team.shared);
            let thread = std::thread::Builder::new()
                .name(format!("tiltbox-worker-{i}"))
                .spawn(move || worker(&shared))?;
            team.threads.push(thread);
        }
        Ok(team)
    }

    /// How many workers, the stepping thread included.
    pub fn workers(&self) -> u32 {
        self.threads.len() as u32 + 1
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
    pub fn for_blocks(&self, blocks: usize, run: &(dyn Fn(usize) + Sync)) {
        if blocks == 0 {
            return;
        }
        let shared = self.shared;
        let base = shared.open.load(Ordering::Relaxed);
        // SAFETY: every ticket handed out so far is done (the last stage waited for them), so
        // no worker reads `task` until the store to `open` below publishes it. The runner's
        // lifetime is erased: this call does not return until every block has run, after
        // which no worker calls it.
        unsafe {
            let run: *const (dyn Fn(usize) + Sync + '_) = run;
            *shared.task.get() = Task {
                run: std::mem::transmute::<
                    *const (dyn Fn(usize) + Sync + '_),
                    *const (dyn Fn(usize) + Sync + 'static),
                >(run),
                base,
            };
        }
        let end = base + blocks;
        shared.open.store(end, Ordering::Release);
        while take_and_run(shared) {}
        let mut spins = 0;
        while shared.done.load(Ordering::Acquire) < end {
            pause(&mut spins);
        }
        if shared.panicked.swap(false, Ordering::Relaxed) {
            panic!("a worker's block panicked");
        }
    }
}

/// Take one open ticket and run its block; false when none is open.
fn take_and_run(shared: &Shared) -> bool {
    loop {
        let next = shared.next.load(Ordering::Relaxed);
        if next >= shared.open.load(Ordering::Acquire) {
            return false;
        }
        if shared
            .next
            .compare_exchange_weak(next, next + 1, Ordering::Acquire, Ordering::Relaxed)
            .is_ok()
        {
            // SAFETY: the ticket is ours and not done, so the stage it belongs to is the one
            // in `task` (published before `open` passed it) and its runner is alive.
            let task = unsafe { *shared.task.get() };
            let run = unsafe { &*task.run };
            let ran =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(next - task.base)));
            if ran.is_err() {
                shared.panicked.store(true, Ordering::Relaxed);
            }
            shared.done.fetch_add(1, Ordering::Release);
            return true;
        }
    }
}

/// A worker thread: sleep until a region begins, take blocks until it ends, sleep again.
fn worker(shared: &Shared) {
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
        let mut spins = 0;
        loop {
            if take_and_run(shared) {
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
