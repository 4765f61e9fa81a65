//! Events: what a step reports about the shapes that asked (Box2D v3's contact, hit and sensor
//! events). Every report is opt-in per shape ([`ShapeFlags`]); a World where no shape asks
//! pays nothing for them.
//!
//! - **Contact begin / end**: a pair of shapes starts or stops touching (a point of theirs
//!   within `Settings::linear_slop` of the other's surface at the step's start), for contacts
//!   where either shape asked. A sleeping pair stays touching; a removed body's contacts end.
//! - **Hit**: a touching pair whose points approached faster than
//!   `Settings::hit_event_threshold` at the step's start and pushed (a speculative point that
//!   never closed is no hit), reported every step it happens, with the fastest point.
//! - **Sensor begin / end**: a sensor shape takes no part in contacts; it reports the shapes
//!   (not sensors) that start or stop overlapping it, asleep or not, at the end of the step.

use super::id::ShapeRef;
use super::math::{Real, Vec2};
use serde::{Deserialize, Serialize};

/// What a shape reports, and whether it is a sensor. All off by default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default)]
pub struct ShapeFlags {
    /// Report when this shape starts and stops touching another.
    pub contact_events: bool,
    /// Report this shape's hits (see the module doc).
    pub hit_events: bool,
    /// A sensor: it touches nothing and nothing touches it; it reports what overlaps it.
    pub sensor: bool,
}

impl ShapeFlags {
    /// No reports, not a sensor.
    pub const NONE: ShapeFlags = ShapeFlags {
        contact_events: false,
        hit_events: false,
        sensor: false,
    };

    /// Whether any flag is set.
    #[inline]
    pub fn any(&self) -> bool {
        *self != ShapeFlags::NONE
    }
}

/// Two shapes that started or stopped touching (A's body has the lower slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ContactEvent {
    /// Shape A.
    pub a: ShapeRef,
    /// Shape B.
    pub b: ShapeRef,
}

/// Two shapes that met faster than the hit threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitEvent {
    /// Shape A (its body has the lower slot).
    pub a: ShapeRef,
    /// Shape B.
    pub b: ShapeRef,
    /// The point that approached fastest (m, world, at the step's start).
    pub point: Vec2,
    /// The contact normal, from A to B.
    pub normal: Vec2,
    /// How fast that point approached (m/s, > 0).
    pub approach_speed: Real,
}

/// A shape that started or stopped overlapping a sensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SensorEvent {
    /// The sensor shape.
    pub sensor: ShapeRef,
    /// The shape overlapping it.
    pub visitor: ShapeRef,
}

/// The events of the last step, each list in a fixed order (by shapes).
#[derive(Clone, Debug, Default)]
pub struct StepEvents {
    /// Pairs that started touching.
    pub contact_begin: Vec<ContactEvent>,
    /// Pairs that stopped touching (or whose body was removed).
    pub contact_end: Vec<ContactEvent>,
    /// Hits.
    pub hits: Vec<HitEvent>,
    /// Shapes that started overlapping a sensor.
    pub sensor_begin: Vec<SensorEvent>,
    /// Shapes that stopped overlapping a sensor (or whose body was removed).
    pub sensor_end: Vec<SensorEvent>,
}

impl StepEvents {
    /// Whether the step reported nothing.
    pub fn is_empty(&self) -> bool {
        self.contact_begin.is_empty()
            && self.contact_end.is_empty()
            && self.hits.is_empty()
            && self.sensor_begin.is_empty()
            && self.sensor_end.is_empty()
    }

    fn clear(&mut self) {
        self.contact_begin.clear();
        self.contact_end.clear();
        self.hits.clear();
        self.sensor_begin.clear();
        self.sensor_end.clear();
    }
}

/// What the World keeps for events from step to step.
#[derive(Clone, Debug, Default)]
pub(crate) struct EventState {
    /// The last step's events.
    pub step: StepEvents,
    /// The pairs touching at the last step, sorted.
    pub touching: Vec<ContactEvent>,
    /// The shapes overlapping each sensor at the last step, sorted.
    pub overlapping: Vec<SensorEvent>,
    /// This step's lists while they are found (swapped with the last step's, so a steady step
    /// allocates nothing).
    pub touching_now: Vec<ContactEvent>,
    pub overlapping_now: Vec<SensorEvent>,
    /// Hits found before the solve: the contact's index among the awake ones, its point's,
    /// and the event if that point then pushes.
    pub hit_candidates: Vec<(u32, u8, HitEvent)>,
    /// On workers: a mark per awake contact for the event stage that looks at them.
    pub marks: Vec<u8>,
    /// The slots of the bodies with a sensor, this step.
    pub sensing: Vec<u32>,
    /// On workers: what each block of sensing bodies found.
    pub sensed: Vec<Vec<SensorEvent>>,
}

impl EventState {
    /// Start a step's reports.
    pub fn begin_step(&mut self) {
        self.step.clear();
        self.hit_candidates.clear();
    }
}

/// What is in `now` and not in `before` (both sorted), and what is in `before` and not `now`.
pub(crate) fn changes<T: Ord + Copy>(
    before: &[T],
    now: &[T],
    began: &mut Vec<T>,
    ended: &mut Vec<T>,
) {
    let (mut i, mut j) = (0, 0);
    while i < before.len() || j < now.len() {
        match (before.get(i), now.get(j)) {
            (Some(x), Some(y)) if x == y => (i, j) = (i + 1, j + 1),
            (Some(x), Some(y)) if x < y => {
                ended.push(*x);
                i += 1;
            }
            (Some(x), None) => {
                ended.push(*x);
                i += 1;
            }
            (_, Some(y)) => {
                began.push(*y);
                j += 1;
            }
            (None, None) => break,
        }
    }
}
