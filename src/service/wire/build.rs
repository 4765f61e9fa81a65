//! A `…/build` from the wire to the engine and back: built bodies (one or more shapes each,
//! every shape checked as a spawned one is), joints (every setting through the engine's own
//! checks), and the descriptions of bodies of several shapes and of joints that events and
//! the `…/scene?joints` reply carry.
//!
//! A built body's origin is its first part's centre (a polygon's centroid) and its angle the
//! body's plus that part's: the engine's body frame, in which the first shape sits unturned at
//! the origin. The other parts are placed in that frame.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

use super::spawn::{
    check_angle, check_motion, check_place, check_shape_limits, check_vertices_as_sent,
    checked_name, shape_from_spec,
};
use super::{finite, shape_spec, vec2, vector};
use crate::physics::joint::{
    Distance, JointDef, JointKind, Limit, Motor, MotorJoint, Prismatic, Revolute, Spring, Weld,
    Wheel,
};
use crate::physics::{Body, BodyDef, BodyId, Filter, Joint, PartDef, Real, Rot, ShapeFlags, Vec2};
use crate::protocol::{
    Build, BuildBody, FilterSpec, JointEnd, JointInfo, JointKindSpec, JointRef, JointSpec,
    LimitSpec, Motion, MotorSpec, PartShape, PartSpec, ShapeSpec, SpringSpec, Vector,
};
use crate::service::command::SpawnDef;
use crate::service::config::Limits;

/// Check a build as sent: the counts, every body ([`body_def`]) and every joint's settings
/// and ends as far as they can be known without the World (live bodies are found when it is
/// applied). The refusal names the body or joint by its index.
pub(crate) fn check_build(b: &Build, limits: &Limits) -> Result<(), String> {
    if b.bodies.is_empty() && b.joints.is_empty() {
        return Err("bodies and joints are both empty: nothing to build".into());
    }
    let max = limits.max_bodies_per_spawn as usize;
    for (what, n) in [("bodies", b.bodies.len()), ("joints", b.joints.len())] {
        if n > max {
            return Err(format!(
                "{n} {what} in one build, more than limits.max_bodies_per_spawn = {max}"
            ));
        }
    }
    for (i, body) in b.bodies.iter().enumerate() {
        body_def(body, limits).map_err(|e| format!("bodies[{i}]: {e}"))?;
    }
    for (i, j) in b.joints.iter().enumerate() {
        check_joint(j, &b.bodies).map_err(|e| format!("joints[{i}]: {e}"))?;
    }
    Ok(())
}

/// The engine's definition of a built body, every field checked; the refusal names the field
/// and the value as sent.
pub(crate) fn body_def(b: &BuildBody, limits: &Limits) -> Result<SpawnDef, String> {
    if b.parts.is_empty() {
        return Err("parts is empty: a body needs at least one shape".into());
    }
    check_place(b.position, b.angle, limits)?;
    if b.motion == Motion::Sleeping
        && (b.velocity != Vector::default() || b.angular_velocity != 0.0)
    {
        return Err(format!(
            "motion = Sleeping with velocity = [{}, {}], angular_velocity = {}: a body created \
             asleep must be at rest",
            b.velocity.x, b.velocity.y, b.angular_velocity
        ));
    }
    let mut placed = Vec::with_capacity(b.parts.len());
    for (i, p) in b.parts.iter().enumerate() {
        placed.push(part_def(p, b.motion, limits).map_err(|e| format!("parts[{i}]: {e}"))?);
    }
    let first = placed.remove(0);
    let turn = Rot::from_angle(first.angle);
    let angle = b.angle as Real + first.angle;
    let position = vec2(b.position) + Rot::from_angle(b.angle as Real).rotate(first.offset);
    let max = limits.max_coordinate as Real;
    if position.x.abs() > max || position.y.abs() > max {
        return Err(format!(
            "the first part's centre lands at [{}, {}]: must be within +-{max} \
             (limits.max_coordinate)",
            position.x, position.y
        ));
    }
    let mut def = match b.motion {
        Motion::Dynamic | Motion::Sleeping => BodyDef::dynamic(first.shape, position)
            .with_density(first.density)
            .with_awake(b.motion == Motion::Dynamic),
        Motion::Kinematic => BodyDef::kinematic(first.shape, position, Vec2::ZERO),
        Motion::Static => BodyDef::fixed(first.shape, position),
    }
    .with_angle(angle)
    .with_friction(first.friction)
    .with_restitution(first.restitution)
    .with_filter(first.filter)
    .with_flags(first.flags);
    if b.motion != Motion::Static {
        def = def
            .with_velocity(vec2(b.velocity))
            .with_angular_velocity(b.angular_velocity as Real);
    }
    for mut p in placed {
        p.offset = turn.inv_rotate(p.offset - first.offset);
        p.angle -= first.angle;
        def = def.with_part(p);
    }
    def.validate().map_err(|e| e.to_string())?;
    check_motion(b.velocity, b.angular_velocity, limits)?;
    Ok(SpawnDef {
        def,
        name: checked_name(b.name.clone(), limits)?,
        colour: b.colour,
    })
}

/// One part as the engine places it: its shape centred on its centroid, `offset` where that
/// centroid sits in the frame the sender gave.
fn part_def(p: &PartSpec, motion: Motion, limits: &Limits) -> Result<PartDef, String> {
    let place = &p.place;
    check_vertices_as_sent(&place.shape, limits.max_coordinate)?;
    let (shape, centroid) = shape_from_spec(&place.shape).map_err(|e| e.to_string())?;
    check_shape_limits(&place.shape, &shape, limits)?;
    let max = limits.max_coordinate;
    for (field, v) in [("offset.x", place.offset.x), ("offset.y", place.offset.y)] {
        finite(field, v)?;
        if v.abs() > max {
            return Err(format!(
                "{field} = {v} is out of range: must be within +-{max} (limits.max_coordinate)"
            ));
        }
    }
    check_angle(place.angle)?;
    if p.friction > limits.max_friction {
        return Err(format!(
            "friction = {} is out of range: must be within [0, {}] (limits.max_friction)",
            p.friction, limits.max_friction
        ));
    }
    if motion.is_dynamic() && !(limits.min_density..=limits.max_density).contains(&p.density) {
        return Err(format!(
            "density = {} is out of range: must be within {}..={} (limits.min_density, limits.max_density)",
            p.density, limits.min_density, limits.max_density
        ));
    }
    let angle = place.angle as Real;
    let offset = vec2(place.offset) + Rot::from_angle(angle).rotate(centroid);
    let def = PartDef::new(shape, offset)
        .with_angle(angle)
        .with_density(if motion.is_dynamic() {
            p.density as Real
        } else {
            1.0
        })
        .with_friction(p.friction as Real)
        .with_restitution(p.restitution as Real)
        .with_filter(filter(p.filter))
        .with_flags(ShapeFlags {
            contact_events: p.contact_events,
            hit_events: p.hit_events,
            sensor: p.sensor,
        });
    def.validate().map_err(|e| e.to_string())?;
    Ok(def)
}

/// The engine filter for a wire filter.
fn filter(f: FilterSpec) -> Filter {
    Filter {
        category: f.category,
        mask: f.mask,
        group: f.group,
    }
}

/// A joint's checks that need no World: its ends (a new body's index in range, B not the
/// world, not the same body twice, at least one end that can be dynamic) and its settings.
fn check_joint(j: &JointSpec, bodies: &[BuildBody]) -> Result<(), String> {
    for (field, end) in [("a", j.a), ("b", j.b)] {
        if let JointEnd::New(i) = end {
            if i as usize >= bodies.len() {
                return Err(format!(
                    "{field} = new body {i}: the build has {} bodies",
                    bodies.len()
                ));
            }
        }
    }
    if j.b == JointEnd::World {
        return Err("b = world: body B must be a body (put the world at A)".into());
    }
    if j.a == j.b {
        return Err(format!("a and b are the same body ({:?})", j.b));
    }
    let fixed = |end: JointEnd| match end {
        JointEnd::World => true,
        JointEnd::New(i) => !bodies[i as usize].motion.is_dynamic(),
        JointEnd::Live(_) => false, // the World checks live bodies when the build is applied
    };
    if fixed(j.a) && fixed(j.b) {
        return Err("neither a nor b is a dynamic body: a joint must move something".into());
    }
    for (field, v) in [
        ("anchor_a.x", j.anchor_a.x),
        ("anchor_a.y", j.anchor_a.y),
        ("anchor_b.x", j.anchor_b.x),
        ("anchor_b.y", j.anchor_b.y),
    ] {
        finite(field, v)?;
    }
    for (field, v) in [
        ("break_force", j.break_force),
        ("break_torque", j.break_torque),
    ] {
        // NaN is refused too: it is not greater than 0.
        if let Some(v) = v.filter(|v| v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)) {
            return Err(format!(
                "{field} = {v} is out of range: must be > 0 (or left out: never breaks)"
            ));
        }
    }
    kind(&j.kind).validate().map_err(|e| e.to_string())
}

/// The engine's joint for `j` between `a` (None: the world) and `b`.
pub(crate) fn joint_def(j: &JointSpec, a: Option<BodyId>, b: BodyId) -> JointDef {
    let mut def =
        JointDef::new(kind(&j.kind), a, b).with_anchors(vec2(j.anchor_a), vec2(j.anchor_b));
    def.collide_connected = j.collide_connected;
    def.break_force = j.break_force.map_or(Real::INFINITY, |f| f as Real);
    def.break_torque = j.break_torque.map_or(Real::INFINITY, |t| t as Real);
    def
}

fn limit(l: Option<LimitSpec>) -> Option<Limit> {
    l.map(|l| Limit {
        lower: l.lower as Real,
        upper: l.upper as Real,
    })
}

fn motor(m: Option<MotorSpec>) -> Option<Motor> {
    m.map(|m| Motor {
        speed: m.speed as Real,
        max: m.max as Real,
    })
}

fn spring(s: Option<SpringSpec>) -> Option<Spring> {
    s.map(|s| Spring {
        hertz: s.hertz as Real,
        damping_ratio: s.damping_ratio as Real,
    })
}

fn real(v: Option<f32>) -> Option<Real> {
    v.map(|v| v as Real)
}

/// The engine's joint kind for a wire one.
fn kind(k: &JointKindSpec) -> JointKind {
    match *k {
        JointKindSpec::Revolute {
            reference_angle,
            limit: l,
            motor: m,
            spring: s,
        } => JointKind::Revolute(Revolute {
            reference_angle: real(reference_angle),
            limit: limit(l),
            motor: motor(m),
            spring: spring(s),
        }),
        JointKindSpec::Prismatic {
            axis,
            reference_angle,
            limit: l,
            motor: m,
            spring: s,
        } => JointKind::Prismatic(Prismatic {
            axis: vec2(axis),
            reference_angle: real(reference_angle),
            limit: limit(l),
            motor: motor(m),
            spring: spring(s),
        }),
        JointKindSpec::Distance {
            length,
            spring: s,
            limit: l,
        } => JointKind::Distance(Distance {
            length: real(length),
            spring: spring(s),
            limit: limit(l),
        }),
        JointKindSpec::Weld {
            reference_angle,
            linear_hertz,
            linear_damping_ratio,
            angular_hertz,
            angular_damping_ratio,
        } => JointKind::Weld(Weld {
            reference_angle: real(reference_angle),
            linear_hertz: linear_hertz as Real,
            linear_damping_ratio: linear_damping_ratio as Real,
            angular_hertz: angular_hertz as Real,
            angular_damping_ratio: angular_damping_ratio as Real,
        }),
        JointKindSpec::Wheel {
            axis,
            spring: s,
            limit: l,
            motor: m,
        } => JointKind::Wheel(Wheel {
            axis: vec2(axis),
            spring: spring(s),
            limit: limit(l),
            motor: motor(m),
        }),
        JointKindSpec::Motor {
            angular_offset,
            max_force,
            max_torque,
            correction_factor,
        } => JointKind::Motor(MotorJoint {
            angular_offset: angular_offset as Real,
            max_force: max_force as Real,
            max_torque: max_torque as Real,
            correction_factor: correction_factor as Real,
        }),
    }
}

/// The wire form of a body's shapes: its one shape, or a compound of all of them (its own
/// shape first, at the origin).
pub(crate) fn body_shape_spec(body: &Body) -> ShapeSpec {
    if body.parts().is_empty() {
        return shape_spec(body.shape());
    }
    let own = PartShape {
        shape: shape_spec(body.shape()),
        offset: vector(Vec2::ZERO),
        angle: 0.0,
    };
    let rest = body.parts().iter().map(|p| PartShape {
        shape: shape_spec(&p.shape),
        offset: vector(p.offset),
        angle: p.angle as f32,
    });
    ShapeSpec::Compound {
        parts: std::iter::once(own).chain(rest).collect(),
    }
}

/// A joint's wire id.
pub(crate) fn joint_ref(id: crate::physics::JointId) -> JointRef {
    JointRef {
        index: id.index(),
        generation: id.generation(),
    }
}

/// The description of a joint; None for a target joint (a drag hand's, never listed).
pub(crate) fn joint_info(j: &Joint) -> Option<JointInfo> {
    let d = j.def();
    let end = |id: BodyId| JointEnd::Live(id.into());
    let kind = wire_kind(&d.kind)?;
    let finite_or_none = |v: Real| v.is_finite().then_some(v as f32);
    Some(JointInfo {
        id: joint_ref(j.id()),
        joint: JointSpec {
            a: d.body_a.map_or(JointEnd::World, end),
            b: end(d.body_b),
            anchor_a: vector(d.anchor_a),
            anchor_b: vector(d.anchor_b),
            kind,
            collide_connected: d.collide_connected,
            break_force: finite_or_none(d.break_force),
            break_torque: finite_or_none(d.break_torque),
        },
    })
}

fn wire_limit(l: Option<Limit>) -> Option<LimitSpec> {
    l.map(|l| LimitSpec {
        lower: l.lower as f32,
        upper: l.upper as f32,
    })
}

fn wire_motor(m: Option<Motor>) -> Option<MotorSpec> {
    m.map(|m| MotorSpec {
        speed: m.speed as f32,
        max: m.max as f32,
    })
}

fn wire_spring(s: Option<Spring>) -> Option<SpringSpec> {
    s.map(|s| SpringSpec {
        hertz: s.hertz as f32,
        damping_ratio: s.damping_ratio as f32,
    })
}

fn single(v: Option<Real>) -> Option<f32> {
    v.map(|v| v as f32)
}

/// The wire form of an engine joint kind; None for a target joint.
fn wire_kind(k: &JointKind) -> Option<JointKindSpec> {
    Some(match *k {
        JointKind::Revolute(r) => JointKindSpec::Revolute {
            reference_angle: single(r.reference_angle),
            limit: wire_limit(r.limit),
            motor: wire_motor(r.motor),
            spring: wire_spring(r.spring),
        },
        JointKind::Prismatic(p) => JointKindSpec::Prismatic {
            axis: vector(p.axis),
            reference_angle: single(p.reference_angle),
            limit: wire_limit(p.limit),
            motor: wire_motor(p.motor),
            spring: wire_spring(p.spring),
        },
        JointKind::Distance(d) => JointKindSpec::Distance {
            length: single(d.length),
            spring: wire_spring(d.spring),
            limit: wire_limit(d.limit),
        },
        JointKind::Weld(w) => JointKindSpec::Weld {
            reference_angle: single(w.reference_angle),
            linear_hertz: w.linear_hertz as f32,
            linear_damping_ratio: w.linear_damping_ratio as f32,
            angular_hertz: w.angular_hertz as f32,
            angular_damping_ratio: w.angular_damping_ratio as f32,
        },
        JointKind::Wheel(w) => JointKindSpec::Wheel {
            axis: vector(w.axis),
            spring: wire_spring(w.spring),
            limit: wire_limit(w.limit),
            motor: wire_motor(w.motor),
        },
        JointKind::Motor(m) => JointKindSpec::Motor {
            angular_offset: m.angular_offset as f32,
            max_force: m.max_force as f32,
            max_torque: m.max_torque as f32,
            correction_factor: m.correction_factor as f32,
        },
        JointKind::Target(_) => return None,
    })
}
