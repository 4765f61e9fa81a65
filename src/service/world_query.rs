//! `…/query`: world queries from clients (rays, points, boxes), answered by the tick thread
//! between ticks from the World as it is then: the World is never shared or locked. The
//! queryable's task decodes and checks each request and hands it over ([`WorldQueries::ask`]);
//! the tick thread answers every one waiting at its next boundary ([`WorldQueries::answer`]).
//! At most [`MAX_PENDING`] wait at once (more are refused as busy), a ray's hits are capped at
//! [`MAX_HITS`], and a tick with nobody asking costs one atomic load.

use crate::protocol::{QueryAnswer, WorldQuery};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use tokio::sync::oneshot;

/// The most queries waiting for the tick thread at once.
pub const MAX_PENDING: usize = 64;
/// The most hits a `RayAll` answers.
pub const MAX_HITS: u32 = 64;

type Waiting = Vec<(WorldQuery, oneshot::Sender<QueryAnswer>)>;

/// The queries waiting for the next tick boundary.
#[derive(Default)]
pub(crate) struct WorldQueries {
    asked: AtomicBool,
    waiting: Mutex<Waiting>,
}

impl WorldQueries {
    /// Queue `q` for the tick thread; its answer comes on the receiver (which fails if the
    /// tick loop stops first). Refused when [`MAX_PENDING`] wait already.
    pub(crate) fn ask(&self, q: WorldQuery) -> Result<oneshot::Receiver<QueryAnswer>, String> {
        let (tx, rx) = oneshot::channel();
        let mut waiting = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
        if waiting.len() >= MAX_PENDING {
            return Err(format!(
                "busy: {MAX_PENDING} queries are waiting for the next tick (at most {MAX_PENDING})"
            ));
        }
        waiting.push((q, tx));
        self.asked.store(true, Ordering::Release);
        Ok(rx)
    }

    /// On the tick thread: answer every query waiting with `answer`, in arrival order.
    pub(crate) fn answer(&self, mut answer: impl FnMut(&WorldQuery) -> QueryAnswer) {
        if !self.asked.swap(false, Ordering::Acquire) {
            return;
        }
        let waiting = std::mem::take(&mut *self.waiting.lock().unwrap_or_else(|e| e.into_inner()));
        for (q, tx) in waiting {
            let _ = tx.send(answer(&q)); // a query that gave up is not an error
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{QueryFilterSpec, Vector};

    #[test]
    fn queries_are_answered_once_in_order_and_a_full_queue_refuses() {
        let q = WorldQueries::default();
        let point = |x| WorldQuery::Point {
            point: Vector::new(x, 0.0),
            filter: QueryFilterSpec::default(),
        };
        let frame_of = |w: &WorldQuery| match w {
            WorldQuery::Point { point, .. } => point.x as u64,
            _ => 0,
        };
        let answer = |w: &WorldQuery| QueryAnswer::Shapes {
            frame: frame_of(w),
            shapes: Vec::new(),
        };
        q.answer(|_| unreachable!("nobody asked"));
        let receivers: Vec<_> = (0..MAX_PENDING)
            .map(|i| q.ask(point(i as f32)).unwrap())
            .collect();
        assert!(q.ask(point(0.0)).unwrap_err().contains("busy"));
        q.answer(answer);
        for (i, rx) in receivers.into_iter().enumerate() {
            let got = rx.blocking_recv().unwrap();
            assert_eq!(
                got,
                QueryAnswer::Shapes {
                    frame: i as u64,
                    shapes: Vec::new()
                }
            );
        }
        q.answer(|_| unreachable!("answered queries are not answered again"));
    }
}
