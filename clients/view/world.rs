//! The viewer's copy of one world, rebuilt the way `docs/protocol.md` tells a late joiner to:
//! subscribe to `…/poses` and `…/events`, query `…/scene` (frame F), drop what is at or before
//! F, then apply later snapshots (a pose replaces the body's pose; a keyframe also says which
//! dynamic bodies exist) and events (added, removed, reset). A pose that arrives before the
//! `Added` event of its body is kept until the event comes.

use crate::protocol::{
    BodyInfo, BodyRef, Event, EventKind, JointEnd, JointInfo, JointRef, JointSpec, Pose,
    SceneState, SceneWithJoints, ShapeSpec, Snapshot, Vector,
};
use std::collections::{BTreeMap, VecDeque};

/// Poses of bodies not known yet are kept this many frames for their `Added` event.
const PENDING_FRAMES: u64 = 120;
/// A snapshot this many frames older than the newest one means the daemon restarted.
const RESTART_FRAMES: u64 = 120;
/// Messages kept while waiting for the `…/scene` reply.
const EARLY_CAPACITY: usize = 1024;

/// One body as the viewer knows it.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewBody {
    /// What the daemon said about it (shape, colour, name, static or not).
    pub info: BodyInfo,
    /// Current centre of mass x (m).
    pub x: f32,
    /// Current centre of mass y (m).
    pub y: f32,
    /// Current angle (rad).
    pub angle: f32,
    /// Frame from which the body exists.
    since: u64,
}

impl ViewBody {
    /// For tests: a body as the scene reply gives it.
    #[cfg(test)]
    pub(crate) fn from_info(info: BodyInfo) -> ViewBody {
        ViewBody::new(info, 0)
    }

    fn new(info: BodyInfo, since: u64) -> ViewBody {
        ViewBody {
            x: info.position.x,
            y: info.position.y,
            angle: info.angle,
            info,
            since,
        }
    }

    /// The body's axis-aligned bounding box in world coordinates at its current pose,
    /// `(min_x, min_y, max_x, max_y)` in metres: exact for every shape (a rotated rectangle's
    /// corners, a disc, a capsule's two end discs, a polygon's vertices). `None` when there is
    /// nothing to bound (a polygon without vertices) or a number is not finite.
    pub fn aabb(&self) -> Option<(f32, f32, f32, f32)> {
        shape_aabb(&self.info.shape, self.x, self.y, self.angle)
    }
}

/// The bounding box of `shape` placed at `(x, y)` turned by `angle` (m, rad): see
/// [`ViewBody::aabb`]; a compound's is the union of its parts'.
fn shape_aabb(shape: &ShapeSpec, x: f32, y: f32, angle: f32) -> Option<(f32, f32, f32, f32)> {
    {
        let (s, c) = angle.sin_cos();
        let (hx, hy) = match shape {
            ShapeSpec::Rect { width, height } => {
                let (hw, hh) = (width * 0.5, height * 0.5);
                (hw * c.abs() + hh * s.abs(), hw * s.abs() + hh * c.abs())
            }
            ShapeSpec::Circle { radius } => (*radius, *radius),
            ShapeSpec::Capsule { length, radius } => {
                let half = capsule_half_core(*length, *radius);
                (half * c.abs() + radius, half * s.abs() + radius)
            }
            ShapeSpec::Polygon { vertices } => {
                let mut it = vertices
                    .iter()
                    .map(|v| (x + c * v.x - s * v.y, y + s * v.x + c * v.y));
                let (x0, y0) = it.next()?;
                let b = it.fold((x0, y0, x0, y0), |(a, b, c, d), (x, y)| {
                    (a.min(x), b.min(y), c.max(x), d.max(y))
                });
                return finite(b);
            }
            ShapeSpec::Segment { a, b, radius, .. } => {
                let at =
                    |v: &crate::protocol::Vector| (x + c * v.x - s * v.y, y + s * v.x + c * v.y);
                let ((ax, ay), (bx, by)) = (at(a), at(b));
                return finite((
                    ax.min(bx) - radius,
                    ay.min(by) - radius,
                    ax.max(bx) + radius,
                    ay.max(by) + radius,
                ));
            }
            ShapeSpec::Compound { parts } => {
                let mut boxes = parts.iter().map(|p| {
                    let (px, py) = (p.offset.x, p.offset.y);
                    let at = (x + c * px - s * py, y + s * px + c * py);
                    shape_aabb(&p.shape, at.0, at.1, angle + p.angle)
                });
                let first = boxes.next()??;
                return boxes.try_fold(first, |(a, b, c, d), next| {
                    let (e, f, g, h) = next?;
                    Some((a.min(e), b.min(f), c.max(g), d.max(h)))
                });
            }
        };
        finite((x - hx, y - hy, x + hx, y + hy))
    }
}

/// Half the length of a capsule's core segment (between the centres of its end discs): the
/// capsule is `length` end to end with ends of `radius`. Never negative.
pub fn capsule_half_core(length: f32, radius: f32) -> f32 {
    (length * 0.5 - radius).max(0.0)
}

/// A short description of a shape with its sizes (m), for body listings and logs:
/// `rect 1x0.5`, `circle r=0.5`, `capsule l=2 r=0.25`, `polygon 5 vertices`.
pub fn describe_shape(shape: &ShapeSpec) -> String {
    match shape {
        ShapeSpec::Rect { width, height } => format!("rect {width}x{height}"),
        ShapeSpec::Circle { radius } => format!("circle r={radius}"),
        ShapeSpec::Capsule { length, radius } => format!("capsule l={length} r={radius}"),
        ShapeSpec::Polygon { vertices } => format!("polygon {} vertices", vertices.len()),
        ShapeSpec::Segment { a, b, radius, .. } => {
            let length = (b.x - a.x).hypot(b.y - a.y);
            format!("segment l={length} r={radius}")
        }
        ShapeSpec::Compound { parts } => format!("compound of {} shapes", parts.len()),
    }
}

fn finite(b: (f32, f32, f32, f32)) -> Option<(f32, f32, f32, f32)> {
    let (a, b2, c, d) = b;
    (a.is_finite() && b2.is_finite() && c.is_finite() && d.is_finite()).then_some(b)
}

/// What became of a snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applied {
    /// It moved the view forward.
    Applied,
    /// It was at or before the view's frame (already included, or out of order).
    Stale,
    /// Its frame is far behind the view's: the daemon restarted, query `…/scene` again.
    Restarted,
}

/// The state of one world: the `…/scene` reply brought forward by snapshots and events.
#[derive(Clone, Debug)]
pub struct WorldView {
    /// World name.
    pub world: String,
    /// Scene name.
    pub scene: String,
    /// Frame of the newest snapshot applied (or of the scene reply).
    pub frame: u64,
    /// Simulated time of that frame (s).
    pub time: f64,
    /// Gravity in force (m/s^2).
    pub gravity: Vector,
    /// Every body, static ones included.
    pub bodies: BTreeMap<BodyRef, ViewBody>,
    /// Every joint (from a `…/scene?joints` reply and the events after it).
    pub joints: BTreeMap<JointRef, JointSpec>,
    /// The reason of the latest `Rejected` event, if any.
    pub last_rejected: Option<String>,
    /// Events at or before this frame are already included.
    base: u64,
    /// Snapshots before this frame describe bodies from before a reset: ignored.
    min_frame: u64,
    /// Poses of bodies whose `Added` event has not arrived yet, with their frame.
    pending: BTreeMap<BodyRef, (u64, Pose)>,
}

impl WorldView {
    /// The view as a `…/scene` reply describes it.
    pub fn from_scene(state: SceneState) -> WorldView {
        let bodies = state
            .bodies
            .into_iter()
            .map(|b| (b.id, ViewBody::new(b, 0)))
            .collect();
        WorldView {
            world: state.world,
            scene: state.scene,
            frame: state.frame,
            time: state.time,
            gravity: state.gravity,
            bodies,
            joints: BTreeMap::new(),
            last_rejected: None,
            base: state.frame,
            min_frame: 0,
            pending: BTreeMap::new(),
        }
    }

    /// Apply a snapshot received after the scene reply.
    pub fn apply_snapshot(&mut self, s: &Snapshot) -> Applied {
        if s.frame + RESTART_FRAMES < self.frame {
            return Applied::Restarted;
        }
        if s.frame <= self.frame || s.frame < self.min_frame {
            return Applied::Stale;
        }
        self.frame = s.frame;
        self.time = s.time;
        self.gravity = s.gravity;
        for p in &s.poses {
            match self.bodies.get_mut(&p.id) {
                Some(b) => (b.x, b.y, b.angle) = (p.x, p.y, p.angle),
                None => {
                    self.pending.insert(p.id, (s.frame, *p));
                }
            }
        }
        if s.keyframe {
            let frame = s.frame;
            let mut present: Vec<BodyRef> = s.poses.iter().map(|p| p.id).collect();
            present.sort_unstable();
            self.bodies.retain(|id, b| {
                b.info.is_static || b.since > frame || present.binary_search(id).is_ok()
            });
        }
        let now = self.frame;
        self.pending.retain(|_, (f, _)| *f + PENDING_FRAMES >= now);
        Applied::Applied
    }

    /// Apply an event received after the scene reply.
    pub fn apply_event(&mut self, e: &Event) {
        if e.frame <= self.base {
            return;
        }
        match &e.kind {
            EventKind::Added { bodies } => {
                for info in bodies {
                    self.insert(info.clone(), e.frame);
                }
            }
            EventKind::Removed { ids } => {
                for id in ids {
                    self.bodies.remove(id);
                    self.pending.remove(id);
                }
                // A body's joints go with it.
                let gone = |e: &JointEnd| matches!(e, JointEnd::Live(id) if ids.contains(id));
                self.joints.retain(|_, j| !gone(&j.a) && !gone(&j.b));
            }
            EventKind::Built { bodies, joints } => {
                for info in bodies {
                    self.insert(info.clone(), e.frame);
                }
                self.add_joints(joints);
            }
            EventKind::JointsRemoved { ids } => {
                for id in ids {
                    self.joints.remove(id);
                }
            }
            EventKind::JointsBroken { joints } => {
                for j in joints {
                    self.joints.remove(&j.id);
                }
            }
            EventKind::Reset {
                scene,
                gravity,
                bodies,
            } => {
                self.scene = scene.clone();
                self.gravity = *gravity;
                self.bodies.clear();
                self.joints.clear();
                self.min_frame = e.frame;
                self.pending.retain(|_, (f, _)| *f >= e.frame);
                for info in bodies {
                    self.insert(info.clone(), e.frame);
                }
            }
            EventKind::Rejected { key, reason } => {
                self.last_rejected = Some(format!("{key}: {reason}"));
            }
            // What touched or entered what changes nothing the viewer draws.
            EventKind::Contacts { .. } | EventKind::Hits { .. } | EventKind::Sensors { .. } => {}
        }
    }

    /// Add joints as a `…/scene?joints` reply or a `Built` event lists them.
    pub fn add_joints(&mut self, joints: &[JointInfo]) {
        for j in joints {
            self.joints.insert(j.id, j.joint.clone());
        }
    }

    /// A joint's two anchors in world coordinates (m) at the bodies' current poses; None when
    /// a body it names is not known.
    pub fn joint_anchors(&self, j: &JointSpec) -> Option<((f32, f32), (f32, f32))> {
        let at = |end: &JointEnd, local: Vector| match end {
            JointEnd::World => Some((local.x, local.y)),
            JointEnd::Live(id) => self.bodies.get(id).map(|b| {
                let (s, c) = b.angle.sin_cos();
                (
                    b.x + c * local.x - s * local.y,
                    b.y + s * local.x + c * local.y,
                )
            }),
            JointEnd::New(_) => None,
        };
        Some((at(&j.a, j.anchor_a)?, at(&j.b, j.anchor_b)?))
    }

    fn insert(&mut self, info: BodyInfo, since: u64) {
        let id = info.id;
        let mut body = ViewBody::new(info, since);
        if let Some((f, p)) = self.pending.remove(&id) {
            if f >= since {
                (body.x, body.y, body.angle) = (p.x, p.y, p.angle);
            }
        }
        self.bodies.insert(id, body);
    }

    /// The area to show, `(min_x, min_y, max_x, max_y)` in metres: the static bodies (the
    /// walls) when there are any, else every body. `None` for an empty world.
    pub fn bounds(&self) -> Option<(f32, f32, f32, f32)> {
        let any_static = self.bodies.values().any(|b| b.info.is_static);
        self.bodies
            .values()
            .filter(|b| !any_static || b.info.is_static)
            .filter_map(ViewBody::aabb)
            .reduce(|(a, b, c, d), (x0, y0, x1, y1)| (a.min(x0), b.min(y0), c.max(x1), d.max(y1)))
    }

    /// Dynamic bodies.
    pub fn dynamic_count(&self) -> usize {
        self.bodies.values().filter(|b| !b.info.is_static).count()
    }
}

/// Something received on the world's keys.
#[derive(Clone, Debug)]
pub enum Received {
    /// A `…/poses` snapshot.
    Snapshot(Snapshot),
    /// An `…/events` event.
    Event(Event),
}

/// A late join in progress or done: messages received before the scene reply are kept, and
/// replayed on it.
#[derive(Debug, Default)]
pub struct Join {
    view: Option<WorldView>,
    early: VecDeque<Received>,
}

impl Join {
    /// A join that waits for its scene reply.
    pub fn new() -> Join {
        Join::default()
    }

    /// The view, once the scene reply came.
    pub fn view(&self) -> Option<&WorldView> {
        self.view.as_ref()
    }

    /// Forget everything (the daemon went away or restarted): wait for a new scene reply.
    pub fn restart(&mut self) {
        self.view = None;
        self.early.clear();
    }

    /// The scene reply: start from it and replay what came before it.
    pub fn scene(&mut self, state: SceneState) {
        self.scene_with_joints(SceneWithJoints {
            scene: state,
            joints: Vec::new(),
        });
    }

    /// The `…/scene?joints` reply: as [`Join::scene`], with the joints.
    pub fn scene_with_joints(&mut self, state: SceneWithJoints) {
        let mut view = WorldView::from_scene(state.scene);
        view.add_joints(&state.joints);
        for r in self.early.drain(..) {
            match r {
                Received::Snapshot(s) => {
                    view.apply_snapshot(&s);
                }
                Received::Event(e) => view.apply_event(&e),
            }
        }
        self.view = Some(view);
    }

    /// A message from the daemon. Returns [`Applied::Restarted`] when the view should be
    /// queried again.
    pub fn receive(&mut self, r: Received) -> Applied {
        match &mut self.view {
            None => {
                if self.early.len() == EARLY_CAPACITY {
                    self.early.pop_front();
                }
                self.early.push_back(r);
                Applied::Stale
            }
            Some(view) => match r {
                Received::Snapshot(s) => view.apply_snapshot(&s),
                Received::Event(e) => {
                    view.apply_event(&e);
                    Applied::Applied
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::Colour;

    fn info(index: u32, is_static: bool, x: f32) -> BodyInfo {
        BodyInfo {
            id: BodyRef {
                index,
                generation: 0,
            },
            name: String::new(),
            shape: ShapeSpec::Rect {
                width: 1.0,
                height: 1.0,
            },
            is_static,
            colour: Colour::default(),
            position: Vector::new(x, 0.0),
            angle: 0.0,
            velocity: Vector::default(),
            angular_velocity: 0.0,
            mass: 1.0,
            friction: 0.5,
            restitution: 0.0,
        }
    }

    fn pose(index: u32, x: f32) -> Pose {
        Pose {
            id: BodyRef {
                index,
                generation: 0,
            },
            x,
            y: 1.0,
            angle: 0.0,
        }
    }

    fn snap(frame: u64, keyframe: bool, poses: Vec<Pose>) -> Received {
        Received::Snapshot(Snapshot {
            frame,
            time: frame as f64 / 60.0,
            gravity: Vector::new(0.0, -9.81),
            keyframe,
            poses,
        })
    }

    fn state(frame: u64) -> SceneState {
        SceneState {
            world: "w".into(),
            scene: "s".into(),
            frame,
            time: 0.0,
            gravity: Vector::new(0.0, -9.81),
            bodies: vec![info(0, true, 0.0), info(1, false, 1.0), info(2, false, 2.0)],
        }
    }

    #[test]
    fn a_late_join_drops_what_the_scene_has_and_keeps_early_poses_for_added_bodies() {
        let mut j = Join::new();
        // before the scene reply: one snapshot already in it, one after it
        j.receive(snap(10, false, vec![pose(1, 9.0)]));
        j.receive(snap(11, false, vec![pose(1, 1.5)]));
        j.scene(state(10));
        let v = j.view().unwrap();
        assert_eq!(v.frame, 11);
        assert_eq!(v.bodies[&pose(1, 0.0).id].x, 1.5);
        // a spawned body's pose comes before its Added event
        j.receive(snap(12, false, vec![pose(3, 7.0)]));
        assert_eq!(j.view().unwrap().bodies.len(), 3);
        j.receive(Received::Event(Event {
            frame: 12,
            kind: EventKind::Added {
                bodies: vec![info(3, false, 5.0)],
            },
        }));
        assert_eq!(j.view().unwrap().bodies[&pose(3, 0.0).id].x, 7.0);
        // a keyframe without body 2: it is gone; the static body stays
        j.receive(snap(13, true, vec![pose(1, 1.5), pose(3, 7.0)]));
        let v = j.view().unwrap();
        assert_eq!(v.bodies.len(), 3);
        assert!(!v.bodies.contains_key(&pose(2, 0.0).id));
        // stale and restarted
        assert_eq!(j.receive(snap(13, false, vec![])), Applied::Stale);
        assert_eq!(j.receive(snap(1, true, vec![])), Applied::Stale);
        let mut far = Join::new();
        far.scene(state(1000));
        assert_eq!(far.receive(snap(2, true, vec![])), Applied::Restarted);
    }

    #[test]
    fn a_reset_replaces_everything_and_older_snapshots_are_ignored() {
        let mut j = Join::new();
        j.scene(state(10));
        j.receive(Received::Event(Event {
            frame: 20,
            kind: EventKind::Reset {
                scene: "again".into(),
                gravity: Vector::new(0.0, -1.0),
                bodies: vec![info(0, false, -3.0)],
            },
        }));
        // a snapshot from before the reset, arriving late: its ids are the old world's
        j.receive(snap(15, false, vec![pose(0, 99.0)]));
        let v = j.view().unwrap();
        assert_eq!(v.scene, "again");
        assert_eq!(v.bodies.len(), 1);
        assert_eq!(v.bodies[&pose(0, 0.0).id].x, -3.0);
        j.receive(snap(20, true, vec![pose(0, -2.5)]));
        assert_eq!(j.view().unwrap().bodies[&pose(0, 0.0).id].x, -2.5);
        assert_eq!(j.view().unwrap().bounds().unwrap(), (-3.0, 0.5, -2.0, 1.5));
    }

    fn shaped(shape: ShapeSpec, x: f32, y: f32, angle: f32) -> ViewBody {
        let mut b = ViewBody::new(info(0, false, 0.0), 0);
        b.info.shape = shape;
        (b.x, b.y, b.angle) = (x, y, angle);
        b
    }

    fn close(a: Option<(f32, f32, f32, f32)>, e: (f32, f32, f32, f32)) -> bool {
        let a = a.unwrap();
        [a.0 - e.0, a.1 - e.1, a.2 - e.2, a.3 - e.3]
            .iter()
            .all(|d| d.abs() < 1e-5)
    }

    #[test]
    fn bounding_boxes_follow_each_shape_and_its_angle() {
        use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
        let rect = ShapeSpec::Rect {
            width: 2.0,
            height: 1.0,
        };
        let a = shaped(rect.clone(), 1.0, 2.0, 0.0).aabb();
        assert!(close(a, (0.0, 1.5, 2.0, 2.5)), "{a:?}");
        let a = shaped(rect, 1.0, 2.0, FRAC_PI_2).aabb();
        assert!(close(a, (0.5, 1.0, 1.5, 3.0)), "{a:?}");
        // a disc's box does not turn with it
        let a = shaped(ShapeSpec::Circle { radius: 0.5 }, 1.0, 2.0, 0.7).aabb();
        assert!(close(a, (0.5, 1.5, 1.5, 2.5)), "{a:?}");
        let capsule = ShapeSpec::Capsule {
            length: 4.0,
            radius: 0.5,
        };
        let a = shaped(capsule.clone(), 0.0, 0.0, 0.0).aabb();
        assert!(close(a, (-2.0, -0.5, 2.0, 0.5)), "{a:?}");
        // at 45 degrees: the end discs' centres at +-1.5/sqrt 2, plus the radius
        let h = 1.5 * FRAC_PI_4.cos() + 0.5;
        let a = shaped(capsule, 0.0, 0.0, FRAC_PI_4).aabb();
        assert!(close(a, (-h, -h, h, h)), "{a:?}");
        let triangle = ShapeSpec::Polygon {
            vertices: vec![
                Vector::new(-1.0, -1.0),
                Vector::new(2.0, -1.0),
                Vector::new(-1.0, 2.0),
            ],
        };
        let a = shaped(triangle.clone(), 10.0, 0.0, 0.0).aabb();
        assert!(close(a, (9.0, -1.0, 12.0, 2.0)), "{a:?}");
        let a = shaped(triangle, 10.0, 0.0, std::f32::consts::PI).aabb();
        assert!(close(a, (8.0, -2.0, 11.0, 1.0)), "{a:?}");
        let empty = ShapeSpec::Polygon { vertices: vec![] };
        assert_eq!(shaped(empty, 0.0, 0.0, 0.0).aabb(), None);
        let nan = ShapeSpec::Circle { radius: f32::NAN };
        assert_eq!(shaped(nan, 0.0, 0.0, 0.0).aabb(), None);
    }

    #[test]
    fn shapes_are_described_with_their_sizes() {
        let d = |s| describe_shape(&s);
        assert_eq!(
            d(ShapeSpec::Rect {
                width: 1.0,
                height: 0.5
            }),
            "rect 1x0.5"
        );
        assert_eq!(d(ShapeSpec::Circle { radius: 0.5 }), "circle r=0.5");
        assert_eq!(
            d(ShapeSpec::Capsule {
                length: 2.0,
                radius: 0.25
            }),
            "capsule l=2 r=0.25"
        );
        let vertices = vec![Vector::new(0.0, 0.0); 5];
        assert_eq!(d(ShapeSpec::Polygon { vertices }), "polygon 5 vertices");
    }
}
