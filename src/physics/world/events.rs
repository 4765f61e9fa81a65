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
    /// shape asking) against those of the last step.
    pub(super) fn find_contact_events(&mut self) {
        let slop = self.settings.linear_slop;
        let mut now = std::mem::take(&mut self.events.touching_now);
        now.clear();
        for c in self.contacts.awake.iter().chain(&self.contacts.sleeping) {
            let Some((a, b)) = self.pair_of_contact(c) else {
                continue;
            };
            let (sa, sb) = shapes(c, a, b);
            let asked =
                flags_of(a, sa.shape).contact_events || flags_of(b, sb.shape).contact_events;
            if asked && c.live().iter().any(|p| p.separation <= slop) {
                now.push(ContactEvent { a: sa, b: sb });
            }
        }
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

    /// Hits, before the solve: this step's contacts whose shapes ask, with the point that
    /// approaches fastest above the threshold (velocities at the step's start).
    pub(super) fn find_hit_candidates(&mut self) {
        let threshold = self.settings.hit_event_threshold;
        let mut found = std::mem::take(&mut self.events.hit_candidates);
        for (k, c) in self.contacts.awake.iter().enumerate() {
            let Some((a, b)) = self.pair_of_contact(c) else {
                continue;
            };
            let (sa, sb) = shapes(c, a, b);
            if !(flags_of(a, sa.shape).hit_events || flags_of(b, sb.shape).hit_events) {
                continue;
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
            if let Some((i, speed)) = fastest.filter(|f| f.1 > threshold) {
                let event = HitEvent {
                    a: sa,
                    b: sb,
                    point: c.points[i].point,
                    normal: c.normal,
                    approach_speed: speed,
                };
                found.push((k as u32, i as u8, event));
            }
        }
        self.events.hit_candidates = found;
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
    /// sensor at the end of the step, against those of the last step.
    pub(super) fn find_sensor_events(&mut self) {
        if self.queries.synced_at != Some(self.steps) {
            self.sync_queries();
        }
        let mut now = std::mem::take(&mut self.events.overlapping_now);
        now.clear();
        for body in self.bodies() {
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
}
