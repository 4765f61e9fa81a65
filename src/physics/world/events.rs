//! Finding the step's events (`physics::events`): which pairs began or stopped touching, which
//! hit, and what entered or left a sensor. Each stage runs only while some body has a shape
//! that asked (`Bodies::flagged`), or while one reported last step needs its end reported.

use super::World;
use crate::physics::body::Body;
use crate::physics::contact::Contact;
use crate::physics::events::{
    changes, ContactEvent, HitEvent, SensorEvent, ShapeFlags, StepEvents,
};
use crate::physics::id::ShapeRef;
use crate::physics::math::{cross_sv, Real};
use crate::physics::query::{every_shape, overlaps_body, rounded};
use crate::physics::team::{block, Region, SharedSlice};

/// How many contacts a worker looks at for events at a time...
const MARKS_PER_BLOCK: usize = 512;
/// ...and the fewest awake contacts for which the workers look at them.
const SHARED_EVENTS_FROM: usize = 1024;
/// How many sensing bodies a worker looks at at a time (each a query of the tree)...
const SENSING_PER_BLOCK: usize = 8;
/// ...and the fewest for which the workers look at them.
const SHARED_SENSORS_FROM: usize = 32;

/// The flags of `body`'s shape `i`.
fn flags_of(body: &Body, i: u32) -> ShapeFlags {
    body.compound()
        .map_or_else(|| body.flags(), |p| p.all[i as usize].flags)
}

/// The contact's two shapes.
fn shapes(c: &Contact, a: &Body, b: &Body) -> (ShapeRef, ShapeRef) {
    (
        ShapeRef {
            body: a.id,
            shape: c.shapes >> 16,
        },
        ShapeRef {
            body: b.id,
            shape: c.shapes & 0xffff,
        },
    )
}

impl World {
    /// The last step's events.
    pub fn events(&self) -> &StepEvents {
        &self.events.step
    }

    fn pair_of_contact(&self, c: &Contact) -> Option<(&Body, &Body)> {
        Some((self.body_in_slot(c.a)?, self.body_in_slot(c.b)?))
    }

    /// Contact begin and end: the pairs touching now (a point within the linear slop, either
    /// shape asking) against those of the last step. The awake contacts are looked at by
    /// `region`'s workers if given (see [`World::mark_awake`]).
    pub(super) fn find_contact_events(&mut self, region: Option<&Region>) {
        let mut now = std::mem::take(&mut self.events.touching_now);
        now.clear();
        match region.filter(|_| self.contacts.awake.len() >= self.shared_events_from()) {
            Some(region) => {
                let mut marks = std::mem::take(&mut self.events.marks);
                self.mark_awake(region, &mut marks, &|c| {
                    u8::from(self.touching(c).is_some())
                });
                let marked = self.contacts.awake.iter().zip(&marks).filter(|m| *m.1 != 0);
                now.extend(marked.filter_map(|(c, _)| self.touching(c)));
                self.events.marks = marks;
            }
            None => now.extend(self.contacts.awake.iter().filter_map(|c| self.touching(c))),
        }
        now.extend(
            self.contacts
                .sleeping
                .iter()
                .filter_map(|c| self.touching(c)),
        );
        now.sort_unstable();
        let step = &mut self.events.step;
        changes(
            &self.events.touching,
            &now,
            &mut step.contact_begin,
            &mut step.contact_end,
        );
        self.events.touching_now = std::mem::replace(&mut self.events.touching, now);
    }

    /// The pair of contact `c` if it touches (a point within the linear slop) and either
    /// shape asks for contact events.
    fn touching(&self, c: &Contact) -> Option<ContactEvent> {
        let (a, b) = self.pair_of_contact(c)?;
        let (sa, sb) = shapes(c, a, b);
        let asked = flags_of(a, sa.shape).contact_events || flags_of(b, sb.shape).contact_events;
        let slop = self.settings.linear_slop;
        (asked && c.live().iter().any(|p| p.separation <= slop))
            .then_some(ContactEvent { a: sa, b: sb })
    }

    /// Hits, before the solve: this step's contacts whose shapes ask, with the point that
    /// approaches fastest above the threshold (velocities at the step's start). The contacts
    /// are looked at by `region`'s workers if given (see [`World::mark_awake`]).
    pub(super) fn find_hit_candidates(&mut self, region: Option<&Region>) {
        let mut found = std::mem::take(&mut self.events.hit_candidates);
        let mut marks = std::mem::take(&mut self.events.marks);
        let shared = region.filter(|_| self.contacts.awake.len() >= self.shared_events_from());
        if let Some(region) = shared {
            let is_hit = |c: &Contact| u8::from(self.hit_candidate(c).is_some());
            self.mark_awake(region, &mut marks, &is_hit);
        }
        let candidate = |(k, c): (usize, &Contact)| {
            self.hit_candidate(c).map(|(i, event)| (k as u32, i, event))
        };
        let contacts = self.contacts.awake.iter().enumerate();
        match shared {
            Some(_) => found.extend(
                contacts
                    .zip(&marks)
                    .filter(|m| *m.1 != 0)
                    .filter_map(|(kc, _)| candidate(kc)),
            ),
            None => found.extend(contacts.filter_map(candidate)),
        }
        self.events.marks = marks;
        self.events.hit_candidates = found;
    }

    /// Contact `c`'s point that approaches fastest, above the hit threshold, and its event, if
    /// either shape asks for hit events.
    fn hit_candidate(&self, c: &Contact) -> Option<(u8, HitEvent)> {
        let (a, b) = self.pair_of_contact(c)?;
        let (sa, sb) = shapes(c, a, b);
        if !(flags_of(a, sa.shape).hit_events || flags_of(b, sb.shape).hit_events) {
            return None;
        }
        let approach = |i: usize| {
            let p = &c.points[i];
            let va = a.linear_velocity + cross_sv(a.angular_velocity, p.anchor_a);
            let vb = b.linear_velocity + cross_sv(b.angular_velocity, p.anchor_b);
            -(vb - va).dot(c.normal)
        };
        let fastest = (0..c.count as usize).map(|i| (i, approach(i))).fold(
            None,
            |m: Option<(usize, Real)>, x| match m {
                Some(y) if y.1 >= x.1 => Some(y),
                _ => Some(x),
            },
        );
        let (i, speed) = fastest.filter(|f| f.1 > self.settings.hit_event_threshold)?;
        let event = HitEvent {
            a: sa,
            b: sb,
            point: c.points[i].point,
            normal: c.normal,
            approach_speed: speed,
        };
        Some((i as u8, event))
    }

    /// The fewest awake contacts for which the workers look at them for events.
    fn shared_events_from(&self) -> usize {
        // (Tests that lower the solve's threshold lower this one with it.)
        self.solver.bundles.shared_from(SHARED_EVENTS_FROM)
    }

    /// `mark(c)` for every awake contact, by index, spread over `region`'s workers: what a
    /// stage then collects in contact order on this thread, taking again only the marked
    /// contacts' events, so that the events are the same, in the same order, for any number
    /// of workers.
    fn mark_awake(
        &self,
        region: &Region,
        marks: &mut Vec<u8>,
        mark: &(dyn Fn(&Contact) -> u8 + Sync),
    ) {
        let contacts = &self.contacts.awake;
        let n = contacts.len();
        marks.clear();
        marks.resize(n, 0);
        // SAFETY: each block writes its own run of the marks.
        let out = unsafe { SharedSlice::new(marks) };
        region.for_blocks(n.div_ceil(MARKS_PER_BLOCK), &|k| {
            let run = block(k, MARKS_PER_BLOCK, n);
            // SAFETY: as above.
            let out = unsafe { out.range(run.clone()) };
            for (m, c) in out.iter_mut().zip(&contacts[run]) {
                *m = mark(c);
            }
        });
    }

    /// Hits, after the solve: the candidates whose point pushed (a speculative point that
    /// never closed is no hit).
    pub(super) fn confirm_hits(&mut self) {
        let contacts = &self.contacts.awake;
        let pushed = |&&(k, i, _): &&(u32, u8, HitEvent)| {
            contacts[k as usize].points[i as usize].total_normal_impulse > 0.0
        };
        let hits = self
            .events
            .hit_candidates
            .iter()
            .filter(pushed)
            .map(|h| h.2);
        self.events.step.hits.extend(hits);
    }

    /// Sensor begin and end: every shape (not a sensor, its filter allowing) overlapping each
    /// sensor at the end of the step, against those of the last step. The sensing bodies are
    /// looked at by `region`'s workers if given, each block of them into its own list; the
    /// lists are then joined and sorted, so the events are the same for any number of workers.
    pub(super) fn find_sensor_events(&mut self, region: Option<&Region>) {
        if self.queries.synced_at != Some(self.steps) {
            self.sync_queries();
        }
        let mut now = std::mem::take(&mut self.events.overlapping_now);
        now.clear();
        let mut sensing = std::mem::take(&mut self.events.sensing);
        sensing.clear();
        let senses = |b: &&Body| every_shape(b).any(|s| s.4.sensor);
        sensing.extend(self.bodies().filter(senses).map(|b| b.id.index));
        match region.filter(|_| sensing.len() >= self.shared_sensors_from()) {
            Some(region) => {
                let mut lists = std::mem::take(&mut self.events.sensed);
                self.sense_shared(region, &sensing, &mut lists);
                lists.iter().for_each(|l| now.extend_from_slice(l));
                self.events.sensed = lists;
            }
            None => {
                for &slot in &sensing {
                    self.sensed_by(slot, &mut now);
                }
            }
        }
        self.events.sensing = sensing;
        now.sort_unstable();
        let step = &mut self.events.step;
        changes(
            &self.events.overlapping,
            &now,
            &mut step.sensor_begin,
            &mut step.sensor_end,
        );
        self.events.overlapping_now = std::mem::replace(&mut self.events.overlapping, now);
    }

    /// What each sensor of the body in `slot` overlaps, onto `now`.
    fn sensed_by(&self, slot: u32, now: &mut Vec<SensorEvent>) {
        let Some(body) = self.body_in_slot(slot) else {
            return;
        };
        for (i, shape, xf, filter, _) in every_shape(body).filter(|s| s.4.sensor) {
            let sensor = ShapeRef {
                body: body.id,
                shape: i,
            };
            let probe = rounded(shape, xf);
            self.query_tree().query(&shape.aabb(xf), |slot| {
                let Some(other) = self.body_in_slot(slot).filter(|o| o.id != body.id) else {
                    return true;
                };
                let sees = |f: &_| filter.should_collide(f);
                now.extend(overlaps_body(other, &probe, sees).map(|shape| SensorEvent {
                    sensor,
                    visitor: ShapeRef {
                        body: other.id,
                        shape,
                    },
                }));
                true
            });
        }
    }

    /// [`World::sensed_by`] for the bodies in `sensing`, in blocks spread over `region`'s
    /// workers, block `k`'s into `lists[k]` (`lists` keeps exactly one list per block).
    fn sense_shared(&self, region: &Region, sensing: &[u32], lists: &mut Vec<Vec<SensorEvent>>) {
        let n = sensing.len();
        let blocks = n.div_ceil(SENSING_PER_BLOCK);
        lists.truncate(blocks);
        lists.resize_with(blocks, Vec::new);
        // SAFETY: each block writes its own list.
        let out = unsafe { SharedSlice::new(lists) };
        region.for_blocks(blocks, &|k| {
            // SAFETY: as above.
            let list = unsafe { out.get(k) }.expect("a list per block");
            list.clear();
            for &slot in &sensing[block(k, SENSING_PER_BLOCK, n)] {
                self.sensed_by(slot, list);
            }
        });
    }

    /// The fewest sensing bodies for which the workers look at them.
    pub(super) fn shared_sensors_from(&self) -> usize {
        // (Tests that lower the solve's threshold lower this one with it.)
        self.solver.bundles.shared_from(SHARED_SENSORS_FROM)
    }
}
