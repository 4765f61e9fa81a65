//! A human ragdoll laid out as Box2D v3's `shared/human.c` lays it out (its samples' ragdoll
//! and the `rain` benchmark's): eleven capsule bones, the lower legs with a foot each (a body of
//! two shapes), joined by revolute joints with Box2D's limits, a motor at rest as joint
//! friction and an optional spring. Sizes scale with `scale` (1: 1.59 m tall).
//!
//! Where tiltbox differs: a capsule lies along a body's x axis, so every bone is turned a
//! quarter turn (the joints' angles count from the pose as laid out, so the limits mean what
//! Box2D's mean); the foot, a polygon rounded by 1.5 cm in Box2D, is that polygon grown by
//! 1.5 cm with sharp corners; Box2D's linear damping on the head and forearms and its sleep
//! threshold of 0.1 m/s are left out (tiltbox has neither).

use super::body::{BodyDef, BodyId};
use super::convex::Polygon;
use super::error::PhysicsError;
use super::filter::Filter;
use super::joint::JointDef;
use super::joint::{JointKind, Limit, Motor, Revolute, Spring};
use super::math::{Real, Vec2, PI};
use super::math::{Rot, Transform};
use super::part::PartDef;
use super::shape::Shape;
use super::world::World;

/// How a ragdoll is made: where, how big, how stiff its joints are, and its group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RagdollDef {
    /// Where its feet stand (m): the bones are laid out upright above it.
    pub position: Vec2,
    /// Size (1: 1.59 m from the soles to the top of the head).
    pub scale: Real,
    /// Joint friction (N m per unit of scale, times each joint's share): a motor held at
    /// rest with this torque. Box2D's samples use 0.05.
    pub friction_torque: Real,
    /// The joints' springs toward the pose as laid out (Hz; 0: none).
    pub hertz: Real,
    /// Their damping ratio.
    pub damping_ratio: Real,
    /// The filter group: bones of one ragdoll never collide with each other when it is
    /// negative (Box2D's rain gives each ragdoll its own).
    pub group: i32,
}

/// One bone: its name, its body, and its joint to its parent (by index into the bones).
#[derive(Clone, Debug, PartialEq)]
pub struct Bone {
    /// e.g. `hip`, `lower_left_leg`.
    pub name: &'static str,
    /// The body (dynamic, density 1).
    pub def: BodyDef,
    /// The parent bone's index, the joint's world point (m) and its kind; None for the hip.
    pub joint: Option<(usize, Vec2, JointKind)>,
}

/// One bone's layout at scale 1, from the feet: centre height, capsule ends (heights), radius,
/// joint height, limits (multiples of pi), share of the joint friction and parent.
struct Layout {
    name: &'static str,
    centre: Real,
    ends: (Real, Real),
    radius: Real,
    joint: Option<(usize, Real, (Real, Real), Real)>,
}

const fn bone(
    name: &'static str,
    centre: Real,
    ends: (Real, Real),
    radius: Real,
    joint: Option<(usize, Real, (Real, Real), Real)>,
) -> Layout {
    Layout {
        name,
        centre,
        ends,
        radius,
        joint,
    }
}

/// Box2D's `human.c`, bone by bone (heights in m at scale 1; limits in multiples of pi).
const BONES: [Layout; 11] = [
    bone("hip", 0.95, (-0.02, 0.02), 0.095, None),
    bone(
        "torso",
        1.2,
        (-0.135, 0.135),
        0.09,
        Some((0, 1.0, (-0.25, 0.0), 0.5)),
    ),
    bone(
        "head",
        1.475,
        (-0.038, 0.039),
        0.075,
        Some((1, 1.4, (-0.3, 0.1), 0.25)),
    ),
    bone(
        "upper_left_leg",
        0.775,
        (-0.125, 0.125),
        0.06,
        Some((0, 0.9, (-0.05, 0.4), 1.0)),
    ),
    bone(
        "lower_left_leg",
        0.475,
        (-0.155, 0.125),
        0.045,
        Some((3, 0.625, (-0.5, -0.02), 0.5)),
    ),
    bone(
        "upper_right_leg",
        0.775,
        (-0.125, 0.125),
        0.06,
        Some((0, 0.9, (-0.05, 0.4), 1.0)),
    ),
    bone(
        "lower_right_leg",
        0.475,
        (-0.155, 0.125),
        0.045,
        Some((5, 0.625, (-0.5, -0.02), 0.5)),
    ),
    bone(
        "upper_left_arm",
        1.225,
        (-0.125, 0.125),
        0.035,
        Some((1, 1.35, (-0.1, 0.8), 0.5)),
    ),
    bone(
        "lower_left_arm",
        0.975,
        (-0.125, 0.125),
        0.03,
        Some((7, 1.1, (-0.2, 0.3), 0.1)),
    ),
    bone(
        "upper_right_arm",
        1.225,
        (-0.125, 0.125),
        0.035,
        Some((1, 1.35, (-0.1, 0.8), 0.5)),
    ),
    bone(
        "lower_right_arm",
        0.975,
        (-0.125, 0.125),
        0.03,
        Some((9, 1.1, (-0.2, 0.3), 0.1)),
    ),
];

/// The foot under a lower leg, in Box2D's leg frame (x forward, y up, from the bone's
/// centre), grown by Box2D's rounding.
const FOOT: [(Real, Real); 4] = [
    (-0.03, -0.185),
    (0.11, -0.185),
    (0.11, -0.16),
    (-0.03, -0.14),
];
const FOOT_ROUNDING: Real = 0.015;

/// The bones of a ragdoll, hip first, each joint after its parent.
pub fn ragdoll(def: &RagdollDef) -> Vec<Bone> {
    let s = def.scale;
    let body_filter = Filter {
        category: 2,
        mask: 1 | 2,
        group: def.group,
    };
    // Feet collide with the ground (category 1), not with ragdolls.
    let foot_filter = Filter {
        category: 2,
        mask: 1,
        group: def.group,
    };
    BONES
        .iter()
        .map(|b| {
            // A capsule along the bone, whose ends need not be symmetric: the body's origin
            // is the capsule's middle, and the bone is turned a quarter turn (x up).
            let middle = 0.5 * (b.ends.0 + b.ends.1);
            let half = 0.5 * (b.ends.1 - b.ends.0);
            let at = def.position + Vec2::new(0.0, s * (b.centre + middle));
            let capsule = Shape::capsule(2.0 * s * (half + b.radius), s * b.radius);
            let mut body = BodyDef::dynamic(capsule, at)
                .with_angle(0.5 * PI)
                .with_friction(0.2)
                .with_filter(body_filter);
            if b.name.starts_with("lower_") && b.name.ends_with("_leg") {
                body.parts.push(foot(s, middle, foot_filter));
            }
            let joint = b.joint.map(|(parent, height, (lower, upper), share)| {
                let point = def.position + Vec2::new(0.0, s * height);
                let kind = JointKind::Revolute(Revolute {
                    reference_angle: None,
                    limit: Some(Limit {
                        lower: lower * PI,
                        upper: upper * PI,
                    }),
                    motor: Some(Motor {
                        speed: 0.0,
                        max: share * def.friction_torque * s,
                    }),
                    spring: (def.hertz > 0.0).then_some(Spring {
                        hertz: def.hertz,
                        damping_ratio: def.damping_ratio,
                    }),
                });
                (parent, point, kind)
            });
            Bone {
                name: b.name,
                def: body,
                joint,
            }
        })
        .collect()
}

/// The foot of a lower leg whose capsule's middle is `middle` (m at scale 1) above the bone's
/// centre, in the leg's frame turned a quarter turn: Box2D's (x, y) is (y, -x) here.
fn foot(s: Real, middle: Real, filter: Filter) -> PartDef {
    let grown: Vec<Vec2> = FOOT
        .iter()
        .map(|&(x, y)| {
            let cx = if x < 0.04 {
                x - FOOT_ROUNDING
            } else {
                x + FOOT_ROUNDING
            };
            let cy = if y < -0.17 {
                y - FOOT_ROUNDING
            } else {
                y + FOOT_ROUNDING
            };
            Vec2::new(s * (cy - middle), -s * cx)
        })
        .collect();
    let (polygon, centroid) = Polygon::new(&grown).expect("the foot is convex");
    PartDef::new(Shape::from(polygon), centroid)
        .with_friction(0.05)
        .with_filter(filter)
}

/// Add a ragdoll to `world`: its bones' ids, hip first (as [`ragdoll`] lists them). All or
/// nothing: on an error (a bone faster than the World allows, say) nothing is added.
pub fn add_ragdoll(world: &mut World, def: &RagdollDef) -> Result<Vec<BodyId>, PhysicsError> {
    let bones = ragdoll(def);
    let mut ids = Vec::with_capacity(bones.len());
    let added = (|| {
        for b in &bones {
            ids.push(world.add_body(&b.def)?);
        }
        for (b, &id) in bones.iter().zip(&ids) {
            if let Some((parent, point, kind)) = &b.joint {
                let frame = |d: &BodyDef| Transform {
                    p: d.position,
                    q: Rot::from_angle(d.angle),
                };
                let anchors = (
                    frame(&bones[*parent].def).apply_inv(*point),
                    frame(&b.def).apply_inv(*point),
                );
                let joint = JointDef::new(kind.clone(), Some(ids[*parent]), id)
                    .with_anchors(anchors.0, anchors.1);
                world.add_joint(&joint)?;
            }
        }
        Ok(())
    })();
    match added {
        Ok(()) => Ok(ids),
        Err(e) => {
            world.remove_bodies(&ids).expect("just added");
            Err(e)
        }
    }
}
