//! `[[joint]]` and `[[rope]]` tables: joints between the scene's bodies, named by body name,
//! with anchors and axes given in world coordinates as the scene lays the bodies out.

use super::error::body_label;
use super::{Colour, SceneBody, SceneError, MAX_BODIES};
use crate::physics::joint::{
    Distance, JointKind, Limit, Motor, MotorJoint, Prismatic, Revolute, Spring, Weld, Wheel,
};
use crate::physics::ragdoll::{ragdoll, RagdollDef};
use crate::physics::{BodyDef, Real, Rot, Shape, Vec2};
use serde::{Deserialize, Serialize};

/// A joint of a scene: its bodies by index into [`super::Scene::bodies`] (`a` None: the
/// world), its anchors in each body's frame (m from its origin), and its kind.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneJoint {
    /// The name from the file, or `joint INDEX` / `NAME[i]` for a rope's.
    pub name: String,
    /// Body A's index, or None for the world.
    pub a: Option<usize>,
    /// Body B's index.
    pub b: usize,
    /// A's anchor in A's frame (m; world coordinates when A is the world).
    pub anchor_a: Vec2,
    /// B's anchor in B's frame (m).
    pub anchor_b: Vec2,
    /// The kind and its settings (axes in A's frame).
    pub kind: JointKind,
    /// Whether the two bodies collide with each other.
    pub collide_connected: bool,
    /// Break force (N); infinity: never.
    pub break_force: Real,
    /// Break torque (N m); infinity: never.
    pub break_torque: Real,
}

/// A `[[joint]]` table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JointEntry {
    name: Option<String>,
    /// revolute, prismatic, distance, weld, wheel or motor.
    #[serde(rename = "type")]
    kind: String,
    /// Body A's name; omitted: the world.
    a: Option<String>,
    /// Body B's name.
    b: String,
    /// The anchor both bodies share (world point, m); or `anchor_a` and `anchor_b`.
    anchor: Option<[Real; 2]>,
    anchor_a: Option<[Real; 2]>,
    anchor_b: Option<[Real; 2]>,
    /// World direction of travel (prismatic, wheel).
    axis: Option<[Real; 2]>,
    /// [lower, upper] (rad, or m).
    limit: Option<[Real; 2]>,
    motor: Option<Motor>,
    spring: Option<Spring>,
    /// Distance joints: rest length (m; default: the anchors' distance).
    length: Option<Real>,
    /// Weld joints' springs (Hz, 0 rigid) and damping ratios.
    linear_hertz: Option<Real>,
    linear_damping_ratio: Option<Real>,
    angular_hertz: Option<Real>,
    angular_damping_ratio: Option<Real>,
    /// Motor joints.
    max_force: Option<Real>,
    max_torque: Option<Real>,
    angular_offset: Option<Real>,
    correction_factor: Option<Real>,
    #[serde(default)]
    collide_connected: bool,
    break_force: Option<Real>,
    break_torque: Option<Real>,
}

/// A `[[rope]]` table: `links` boxes laid end to end from `from` to `to`, each joined to the
/// next by a hinge at their shared end; the first hangs from `a` (or the world) at `from`,
/// the last from `b` at `to` when `b` is given.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RopeEntry {
    name: Option<String>,
    from: [Real; 2],
    to: [Real; 2],
    links: u32,
    #[serde(default = "default_thickness")]
    thickness: Real,
    #[serde(default = "default_density")]
    density: Real,
    a: Option<String>,
    b: Option<String>,
    colour: Option<String>,
}

fn default_thickness() -> Real {
    0.125
}
/// A rope's density and a ragdoll's scale unless given.
fn default_density() -> Real {
    1.0
}

/// How an error names a joint table.
fn joint_label(name: Option<&str>, k: usize) -> String {
    match name {
        Some(name) => format!("joint {name:?} ([[joint]] #{k})"),
        None => format!("[[joint]] #{k}"),
    }
}

/// The index of the body named `name`, or an error naming the field.
fn find(at: &str, field: &str, name: &str, bodies: &[SceneBody]) -> Result<usize, SceneError> {
    bodies.iter().position(|b| b.name == name).ok_or_else(|| {
        SceneError::invalid(
            at,
            field,
            Some(format!("{name:?}")),
            "names no body of the scene (bodies are named by their `name`)",
        )
    })
}

/// A world point `p` in the frame of body `i` (or the world).
fn local(bodies: &[SceneBody], i: Option<usize>, p: Vec2) -> Vec2 {
    match i {
        Some(i) => {
            let d = &bodies[i].def;
            Rot::from_angle(d.angle).inv_rotate(p - d.position)
        }
        None => p,
    }
}

/// A world direction in the frame of body `i` (or the world).
fn local_axis(bodies: &[SceneBody], i: Option<usize>, v: Vec2) -> Vec2 {
    i.map_or(v, |i| Rot::from_angle(bodies[i].def.angle).inv_rotate(v))
}

impl JointEntry {
    /// The joint, checked against the scene's `bodies`; `k` is its index among the joint
    /// tables.
    pub(super) fn into_joint(
        self,
        k: usize,
        bodies: &[SceneBody],
    ) -> Result<SceneJoint, SceneError> {
        let at = joint_label(self.name.as_deref(), k);
        let a = match &self.a {
            Some(name) => Some(find(&at, "a", name, bodies)?),
            None => None,
        };
        let b = find(&at, "b", &self.b, bodies)?;
        let (pa, pb) = self.anchors(&at, a, b, bodies)?;
        let kind = self.kind(&at, a, bodies, (pa, pb))?;
        let joint = SceneJoint {
            name: self.name.clone().unwrap_or_else(|| format!("joint {k}")),
            a,
            b,
            anchor_a: local(bodies, a, pa),
            anchor_b: local(bodies, Some(b), pb),
            kind,
            collide_connected: self.collide_connected,
            break_force: self.break_force.unwrap_or(Real::INFINITY),
            break_torque: self.break_torque.unwrap_or(Real::INFINITY),
        };
        check_joint(&at, &joint, bodies)?;
        Ok(joint)
    }

    /// The anchors as world points: `anchor` for both, or `anchor_a` and `anchor_b`
    /// (defaulting to the bodies' origins: the world's origin for the world).
    fn anchors(
        &self,
        at: &str,
        a: Option<usize>,
        b: usize,
        bodies: &[SceneBody],
    ) -> Result<(Vec2, Vec2), SceneError> {
        let centre = |i: Option<usize>| i.map_or(Vec2::ZERO, |i| bodies[i].def.position);
        let v = |p: [Real; 2]| Vec2::new(p[0], p[1]);
        match (self.anchor, self.anchor_a, self.anchor_b) {
            (Some(p), None, None) => Ok((v(p), v(p))),
            (None, pa, pb) => Ok((pa.map_or(centre(a), v), pb.map_or(centre(Some(b)), v))),
            _ => Err(SceneError::invalid(
                at,
                "anchor",
                None,
                "give either `anchor` (shared) or `anchor_a` and `anchor_b`, not both",
            )),
        }
    }

    /// The kind from `type` and the fields that go with it; a field another kind uses is
    /// refused by name.
    fn kind(
        &self,
        at: &str,
        a: Option<usize>,
        bodies: &[SceneBody],
        (pa, pb): (Vec2, Vec2),
    ) -> Result<JointKind, SceneError> {
        let limit = self.limit.map(|[lower, upper]| Limit { lower, upper });
        let axis = |at: &str| {
            let [x, y] = self.axis.ok_or_else(|| {
                SceneError::invalid(at, "axis", None, "is required for this joint type")
            })?;
            Ok::<Vec2, SceneError>(local_axis(bodies, a, Vec2::new(x, y)))
        };
        let kind = match self.kind.as_str() {
            "revolute" => JointKind::Revolute(Revolute {
                reference_angle: None,
                limit,
                motor: self.motor,
                spring: self.spring,
            }),
            "prismatic" => JointKind::Prismatic(Prismatic {
                limit,
                motor: self.motor,
                spring: self.spring,
                ..Prismatic::on_axis(axis(at)?)
            }),
            "wheel" => {
                let mut wheel = Wheel::on_axis(axis(at)?);
                wheel.spring = self.spring.or(wheel.spring);
                wheel.limit = limit;
                wheel.motor = self.motor;
                JointKind::Wheel(wheel)
            }
            "distance" => JointKind::Distance(Distance {
                length: Some(self.length.unwrap_or((pb - pa).length())),
                spring: self.spring,
                limit,
            }),
            "weld" => JointKind::Weld(Weld {
                reference_angle: None,
                linear_hertz: self.linear_hertz.unwrap_or(0.0),
                linear_damping_ratio: self.linear_damping_ratio.unwrap_or(1.0),
                angular_hertz: self.angular_hertz.unwrap_or(0.0),
                angular_damping_ratio: self.angular_damping_ratio.unwrap_or(1.0),
            }),
            "motor" => JointKind::Motor(MotorJoint {
                angular_offset: self.angular_offset.unwrap_or(0.0),
                correction_factor: self.correction_factor.unwrap_or(0.3),
                ..MotorJoint::new(
                    self.max_force.unwrap_or(1.0),
                    self.max_torque.unwrap_or(1.0),
                )
            }),
            other => {
                return Err(SceneError::invalid(
                    at,
                    "type",
                    Some(format!("{other:?}")),
                    "must be one of revolute, prismatic, distance, weld, wheel, motor",
                ))
            }
        };
        self.refuse_foreign_fields(at, &kind)?;
        Ok(kind)
    }

    /// Refuse a field the joint's kind does not read, naming it.
    fn refuse_foreign_fields(&self, at: &str, kind: &JointKind) -> Result<(), SceneError> {
        let name = kind.name();
        let uses = |kinds: &[&str]| kinds.contains(&name);
        let fields: [(&str, bool, &[&str]); 11] = [
            ("axis", self.axis.is_some(), &["prismatic", "wheel"]),
            (
                "limit",
                self.limit.is_some(),
                &["revolute", "prismatic", "wheel", "distance"],
            ),
            (
                "motor",
                self.motor.is_some(),
                &["revolute", "prismatic", "wheel"],
            ),
            (
                "spring",
                self.spring.is_some(),
                &["revolute", "prismatic", "wheel", "distance"],
            ),
            ("length", self.length.is_some(), &["distance"]),
            ("linear_hertz", self.linear_hertz.is_some(), &["weld"]),
            ("angular_hertz", self.angular_hertz.is_some(), &["weld"]),
            ("max_force", self.max_force.is_some(), &["motor"]),
            ("max_torque", self.max_torque.is_some(), &["motor"]),
            ("angular_offset", self.angular_offset.is_some(), &["motor"]),
            (
                "correction_factor",
                self.correction_factor.is_some(),
                &["motor"],
            ),
        ];
        for (field, given, kinds) in fields {
            if given && !uses(kinds) {
                return Err(SceneError::invalid(
                    at,
                    field,
                    None,
                    format!("does not apply to a {name} joint"),
                ));
            }
        }
        Ok(())
    }
}

/// Refuse a joint the engine would: the same body twice, no dynamic body, bad numbers.
fn check_joint(at: &str, j: &SceneJoint, bodies: &[SceneBody]) -> Result<(), SceneError> {
    if j.a == Some(j.b) {
        return Err(SceneError::invalid(
            at,
            "b",
            Some(format!("{:?}", bodies[j.b].name)),
            "is also `a`: a joint joins two different bodies",
        ));
    }
    let fixed = |i: usize| {
        !matches!(
            bodies[i].def.mass,
            crate::physics::MassSpec::Density(_) | crate::physics::MassSpec::Mass(_)
        )
    };
    if fixed(j.b) && j.a.map_or(true, fixed) {
        return Err(SceneError::invalid(
            at,
            "b",
            Some(format!("{:?}", bodies[j.b].name)),
            "a joint needs at least one dynamic body (a and b are static or kinematic)",
        ));
    }
    let wrap = |e| SceneError::physics(at, e);
    j.kind.validate().map_err(wrap)?;
    for (field, v) in [("anchor_a", j.anchor_a), ("anchor_b", j.anchor_b)] {
        if !(v.x.is_finite() && v.y.is_finite()) {
            return Err(SceneError::invalid(
                at,
                field,
                Some(format!("{v}")),
                "must be finite",
            ));
        }
    }
    for (field, v) in [
        ("break_force", j.break_force),
        ("break_torque", j.break_torque),
    ] {
        if v.is_nan() || v <= 0.0 {
            let message = "must be > 0 (omit it for a joint that never breaks)";
            return Err(SceneError::invalid(at, field, Some(v.to_string()), message));
        }
    }
    Ok(())
}

impl RopeEntry {
    /// The rope's links (appended to `bodies`, named `NAME[i]`) and joints; `k` is its index
    /// among the rope tables.
    pub(super) fn expand(
        self,
        k: usize,
        bodies: &mut Vec<SceneBody>,
        joints: &mut Vec<SceneJoint>,
    ) -> Result<(), SceneError> {
        let prefix = self.name.clone().unwrap_or_else(|| "rope".to_owned());
        let at = match &self.name {
            Some(name) => format!("rope {name:?} ([[rope]] #{k})"),
            None => format!("[[rope]] #{k}"),
        };
        let (from, to) = (Vec2::from(self.from), Vec2::from(self.to));
        let span = to - from;
        let (count, length) = (self.links as usize, span.length());
        if count == 0 || bodies.len() + count > MAX_BODIES {
            let message = format!("must be 1 or more, and the scene at most {MAX_BODIES} bodies");
            return Err(SceneError::invalid(
                &at,
                "links",
                Some(count.to_string()),
                message,
            ));
        }
        if !(length.is_finite() && length > 0.0) {
            let message = "`from` and `to` must be two different finite points";
            return Err(SceneError::invalid(
                &at,
                "to",
                Some(format!("{to}")),
                message,
            ));
        }
        let a = match &self.a {
            Some(name) => Some(find(&at, "a", name, bodies)?),
            None => None,
        };
        let b = match &self.b {
            Some(name) => Some(find(&at, "b", name, bodies)?),
            None => None,
        };
        let colour = match self.colour.as_deref() {
            None => Colour::GREY,
            Some(s) => s.parse().map_err(|_| {
                SceneError::invalid(&at, "colour", Some(s.to_owned()), "must be \"#rrggbb\"")
            })?,
        };
        let link = length / count as Real;
        let (dir, angle) = (span / length, span.y.atan2(span.x));
        let first = bodies.len();
        for i in 0..count {
            let centre = from + (i as Real + 0.5) * link * dir;
            let def = BodyDef::dynamic(Shape::rect(link, self.thickness), centre)
                .with_angle(angle)
                .with_density(self.density);
            def.validate()
                .map_err(|e| SceneError::physics(body_label(Some(&prefix), first + i), e))?;
            let mut body = SceneBody::new(format!("{prefix}[{i}]"), def);
            body.colour = colour;
            bodies.push(body);
        }
        let hinge = |name: String, a: Option<usize>, b: usize, point: Vec2| SceneJoint {
            name,
            a,
            b,
            anchor_a: local(bodies, a, point),
            anchor_b: local(bodies, Some(b), point),
            kind: JointKind::Revolute(Revolute::free()),
            collide_connected: false,
            break_force: Real::INFINITY,
            break_torque: Real::INFINITY,
        };
        let mut list = vec![hinge(format!("{prefix}.joint[0]"), a, first, from)];
        for i in 1..count {
            let point = from + i as Real * link * dir;
            list.push(hinge(
                format!("{prefix}.joint[{i}]"),
                Some(first + i - 1),
                first + i,
                point,
            ));
        }
        if let Some(b) = b {
            list.push(hinge(
                format!("{prefix}.joint[{count}]"),
                Some(first + count - 1),
                b,
                to,
            ));
        }
        for j in &list {
            check_joint(&at, j, bodies)?;
        }
        joints.extend(list);
        Ok(())
    }
}

/// A `[[ragdoll]]` table: a human as Box2D's `human.c` lays it out ([`crate::physics::ragdoll`])
/// standing at `position`, its bones named `NAME.hip`, `NAME.torso`, ... and its joints after
/// the bones they join.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RagdollEntry {
    name: Option<String>,
    position: [Real; 2],
    #[serde(default = "default_density")]
    scale: Real,
    #[serde(default = "default_friction_torque")]
    friction_torque: Real,
    #[serde(default)]
    hertz: Real,
    #[serde(default = "default_ragdoll_damping")]
    damping_ratio: Real,
    group: Option<i32>,
    colour: Option<String>,
}

fn default_friction_torque() -> Real {
    0.05
}
fn default_ragdoll_damping() -> Real {
    0.5
}

impl RagdollEntry {
    /// The ragdoll's bones (appended to `bodies`) and joints; `k` is its index among the
    /// ragdoll tables (its default group is -(k + 1): its bones never collide with each other).
    pub(super) fn expand(
        self,
        k: usize,
        bodies: &mut Vec<SceneBody>,
        joints: &mut Vec<SceneJoint>,
    ) -> Result<(), SceneError> {
        let prefix = self.name.clone().unwrap_or_else(|| format!("ragdoll {k}"));
        let at = match &self.name {
            Some(name) => format!("ragdoll {name:?} ([[ragdoll]] #{k})"),
            None => format!("[[ragdoll]] #{k}"),
        };
        let checks = [
            (
                "scale",
                self.scale,
                self.scale.is_finite() && (0.01..=100.0).contains(&self.scale),
                "must be within [0.01, 100]",
            ),
            (
                "friction_torque",
                self.friction_torque,
                self.friction_torque.is_finite() && self.friction_torque >= 0.0,
                "must be finite and >= 0 (N m)",
            ),
            (
                "hertz",
                self.hertz,
                self.hertz.is_finite() && self.hertz >= 0.0,
                "must be finite and >= 0 (0: no spring)",
            ),
            (
                "damping_ratio",
                self.damping_ratio,
                self.damping_ratio.is_finite() && self.damping_ratio >= 0.0,
                "must be finite and >= 0",
            ),
            (
                "position",
                self.position[0],
                self.position.iter().all(|v| v.is_finite()),
                "must be finite",
            ),
        ];
        for (field, value, ok, message) in checks {
            if !ok {
                return Err(SceneError::invalid(
                    &at,
                    field,
                    Some(value.to_string()),
                    message,
                ));
            }
        }
        let colour = match self.colour.as_deref() {
            None => Colour::GREY,
            Some(s) => s.parse().map_err(|_| {
                SceneError::invalid(&at, "colour", Some(s.to_owned()), "must be \"#rrggbb\"")
            })?,
        };
        let bones = ragdoll(&RagdollDef {
            position: Vec2::from(self.position),
            scale: self.scale,
            friction_torque: self.friction_torque,
            hertz: self.hertz,
            damping_ratio: self.damping_ratio,
            group: self.group.unwrap_or(-(k as i32) - 1),
        });
        if bodies.len() + bones.len() > MAX_BODIES {
            let message = format!("the scene may have at most {MAX_BODIES} bodies");
            return Err(SceneError::invalid(&at, "position", None, message));
        }
        let first = bodies.len();
        for bone in &bones {
            let mut body = SceneBody::new(format!("{prefix}.{}", bone.name), bone.def.clone());
            body.colour = colour;
            bodies.push(body);
        }
        for (i, bone) in bones.iter().enumerate() {
            if let Some((parent, point, kind)) = &bone.joint {
                let (a, b) = (first + parent, first + i);
                let joint = SceneJoint {
                    name: format!("{prefix}.{}", bone.name),
                    a: Some(a),
                    b,
                    anchor_a: local(bodies, Some(a), *point),
                    anchor_b: local(bodies, Some(b), *point),
                    kind: kind.clone(),
                    collide_connected: false,
                    break_force: Real::INFINITY,
                    break_torque: Real::INFINITY,
                };
                check_joint(&at, &joint, bodies)?;
                joints.push(joint);
            }
        }
        Ok(())
    }
}
