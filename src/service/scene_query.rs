//! Late joiners' `…/scene` queries. The queryable's task asks ([`SceneQueries::ask`]); the
//! tick thread, between ticks, builds the full state once for everyone waiting
//! ([`SceneQueries::answer`]) and never otherwise: the World is never shared or locked, and
//! a tick with nobody asking costs one atomic load.

use crate::protocol::SceneWithJoints;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::oneshot;

/// The queries waiting for the next state.
#[derive(Default)]
pub(crate) struct SceneQueries {
    /// Set by [`SceneQueries::ask`], cleared by [`SceneQueries::answer`].
    asked: AtomicBool,
    waiting: Mutex<Vec<oneshot::Sender<Arc<SceneWithJoints>>>>,
}

impl SceneQueries {
    /// Wait for the state after the last step. The receiver fails if the tick loop stops first.
    pub(crate) fn ask(&self) -> oneshot::Receiver<Arc<SceneWithJoints>> {
        let (tx, rx) = oneshot::channel();
        self.waiting
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(tx);
        self.asked.store(true, Ordering::Release);
        rx
    }

    /// On the tick thread: if anyone asked, `build` the state once and hand it to them all.
    pub(crate) fn answer(&self, build: impl FnOnce() -> SceneWithJoints) {
        if !self.asked.swap(false, Ordering::Acquire) {
            return;
        }
        let waiting = std::mem::take(&mut *self.waiting.lock().unwrap_or_else(|e| e.into_inner()));
        if waiting.is_empty() {
            return;
        }
        let state = Arc::new(build());
        for tx in waiting {
            let _ = tx.send(state.clone()); // a query that gave up is not an error
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{SceneState, Vector};

    /// An empty world at `frame`.
    fn state(frame: u64) -> SceneWithJoints {
        let (world, scene) = (String::from("w"), String::from("s"));
        let time = frame as f64 / 60.0;
        let (gravity, bodies) = (Vector::new(0.0, -9.81), Vec::new());
        let scene = SceneState {
            frame,
            time,
            world,
            scene,
            gravity,
            bodies,
        };
        SceneWithJoints {
            scene,
            joints: Vec::new(),
        }
    }

    #[test]
    fn the_state_is_built_only_when_asked_and_once_for_all_who_wait() {
        let q = SceneQueries::default();
        let mut built = 0;
        q.answer(|| {
            built += 1;
            state(1)
        });
        assert_eq!(built, 0, "nobody asked");
        let (a, b) = (q.ask(), q.ask());
        q.answer(|| {
            built += 1;
            state(2)
        });
        assert_eq!(built, 1);
        assert_eq!(a.blocking_recv().unwrap().scene.frame, 2);
        assert_eq!(b.blocking_recv().unwrap().scene.frame, 2);
        q.answer(|| {
            built += 1;
            state(3)
        });
        assert_eq!(built, 1, "answered queries are not answered again");
        let c = q.ask();
        drop(q);
        assert!(c.blocking_recv().is_err(), "a stopped loop fails the query");
    }
}
