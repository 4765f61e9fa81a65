//! The World's contact, hit and sensor events as `…/events` messages: one event per kind a
//! step with any, stamped with that step's frame, each list cut at
//! [`MAX_PHYSICS_EVENTS`] entries (the rest counted in `dropped`) so that a scene where every
//! shape asks cannot flood a subscriber or hold back the tick.

use super::Simulation;
use crate::physics::{ContactEvent, HitEvent, SensorEvent, ShapeRef, StepEvents};
use crate::protocol::{BodyRef, BrokenJoint, Event, EventKind, HitInfo, ShapeHit, ShapePair};
use crate::service::wire::build::joint_ref;
use crate::service::wire::vector;

/// The most entries of one kind (begins and ends together) an event carries.
pub const MAX_PHYSICS_EVENTS: usize = 256;

fn hit(s: ShapeRef) -> ShapeHit {
    ShapeHit {
        id: BodyRef::from(s.body),
        shape: s.shape,
    }
}

/// The first of `begin` and then `end` within the cap, and how many did not fit.
fn capped<T, U>(begin: &[T], end: &[T], f: impl Fn(&T) -> U) -> (Vec<U>, Vec<U>, u32) {
    let b = begin.len().min(MAX_PHYSICS_EVENTS);
    let e = end.len().min(MAX_PHYSICS_EVENTS - b);
    let dropped = (begin.len() - b + end.len() - e) as u32;
    (
        begin[..b].iter().map(&f).collect(),
        end[..e].iter().map(&f).collect(),
        dropped,
    )
}

fn contact(c: &ContactEvent) -> ShapePair {
    ShapePair {
        a: hit(c.a),
        b: hit(c.b),
    }
}

fn sensor(s: &SensorEvent) -> ShapePair {
    ShapePair {
        a: hit(s.sensor),
        b: hit(s.visitor),
    }
}

fn hit_info(h: &HitEvent) -> HitInfo {
    HitInfo {
        pair: ShapePair {
            a: hit(h.a),
            b: hit(h.b),
        },
        point: vector(h.point),
        normal: vector(h.normal),
        approach_speed: h.approach_speed as f32,
    }
}

/// The events to publish for one step's `events`, at `frame`.
pub(super) fn physics_events(events: &StepEvents, frame: u64) -> Vec<Event> {
    let mut out = Vec::new();
    let mut push = |kind| out.push(Event { frame, kind });
    if !events.contact_begin.is_empty() || !events.contact_end.is_empty() {
        let (begin, end, dropped) = capped(&events.contact_begin, &events.contact_end, contact);
        push(EventKind::Contacts {
            begin,
            end,
            dropped,
        });
    }
    if !events.hits.is_empty() {
        let (hits, _, dropped) = capped(&events.hits, &[], hit_info);
        push(EventKind::Hits { hits, dropped });
    }
    if !events.sensor_begin.is_empty() || !events.sensor_end.is_empty() {
        let (begin, end, dropped) = capped(&events.sensor_begin, &events.sensor_end, sensor);
        push(EventKind::Sensors {
            begin,
            end,
            dropped,
        });
    }
    out
}

impl Simulation {
    /// The events of the step just taken: the joints of a scene a reset loaded just before
    /// it (`Built`, after the `Reset`), the joints that broke, and the contact, hit and sensor
    /// events (none unless a shape asked).
    pub fn physics_events(&mut self) -> Vec<Event> {
        let events = self.world.events();
        let mut out = if events.is_empty() {
            Vec::new()
        } else {
            physics_events(events, self.frame)
        };
        let frame = self.frame;
        if std::mem::take(&mut self.announce_joints) {
            let kind = EventKind::Built {
                bodies: Vec::new(),
                joints: self.joint_infos(),
            };
            out.insert(0, Event { frame, kind });
        }
        let broken = self.world.broken_joints();
        if !broken.is_empty() {
            let loads = self.world.broken_joint_loads();
            let joints = broken
                .iter()
                .zip(loads)
                .map(|(&id, &(force, torque))| BrokenJoint {
                    id: joint_ref(id),
                    force: force.length() as f32,
                    torque: torque as f32,
                })
                .collect();
            out.push(Event {
                frame,
                kind: EventKind::JointsBroken { joints },
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_list_longer_than_the_cap_is_cut_begins_first_and_counted() {
        let begin: Vec<u32> = (0..200).collect();
        let end: Vec<u32> = (0..100).collect();
        let (b, e, dropped) = capped(&begin, &end, |x| *x);
        assert_eq!((b.len(), e.len(), dropped), (200, 56, 44));
        let (b, e, dropped) = capped(&begin[..3], &end[..2], |x| *x);
        assert_eq!((b, e, dropped), (vec![0, 1, 2], vec![0, 1], 0));
        let many: Vec<u32> = (0..300).collect();
        let (b, e, dropped) = capped(&many, &end, |x| *x);
        assert_eq!((b.len(), e.len(), dropped), (MAX_PHYSICS_EVENTS, 0, 144));
    }
}
