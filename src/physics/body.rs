//! Rigid bodies: their definition (what a caller asks for) and their state (what the World keeps).

use super::builder::builder_setters;
use super::error::{check_material, finite, finite_vec, positive, PhysicsError};
use super::events::ShapeFlags;
use super::filter::Filter;
use super::math::{is_finite_vec, Real, Rot, Transform, Vec2};
use super::part::{mass_data, placed, Part, PartDef, Parts, MAX_SHAPES};
use super::shape::Shape;
use serde::{Deserialize, Serialize};

pub use super::id::BodyId;

/// How a body's mass is given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassSpec {
    /// Immovable: infinite mass and inertia (walls, ground).
    Static,
    /// Mass = density (kg/m^2) x shape area.
    Density(Real),
    /// Total mass in kilograms.
    Mass(Real),
    /// Moved by the velocity it is given, not by forces or contacts: infinite mass and
    /// inertia like a static body, but it moves, pushes dynamic bodies, carries them by
    /// friction and is never pushed back (platforms, paddles, elevators).
    /// Set its velocity with [`super::World::set_velocity`].
    Kinematic,
}

/// Everything needed to create a body. Validated by [`BodyDef::validate`] before it reaches a World.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BodyDef {
    /// Collision shape, centred on the body's origin.
    pub shape: Shape,
    /// The body's origin in world coordinates, metres: its centre of mass unless it has
    /// `parts`.
    pub position: Vec2,
    /// Orientation in radians, counter-clockwise.
    pub angle: Real,
    /// Linear velocity, m/s.
    pub linear_velocity: Vec2,
    /// Angular velocity, rad/s, counter-clockwise.
    pub angular_velocity: Real,
    /// Mass, density, or static.
    pub mass: MassSpec,
    /// Coulomb friction coefficient, >= 0 (mixed per pair by `Settings::friction_mixing`).
    pub friction: Real,
    /// Coefficient of restitution in [0, 1] (mixed per pair as sqrt(eA eB)).
    pub restitution: Real,
    /// Which other bodies it collides with (default: all).
    #[serde(default)]
    pub filter: Filter,
    /// Further shapes, placed from the origin in the body's frame, each with its own material
    /// (none by default). Mass, centre of mass and inertia come from all the shapes: with
    /// [`MassSpec::Density`] each part has its own density; with [`MassSpec::Mass`] the total
    /// is shared in proportion to area x density, the body's own shape at density 1.
    #[serde(default)]
    pub parts: Vec<PartDef>,
    /// What its own shape reports, and whether it is a sensor (default: nothing, not a
    /// sensor; each part has its own).
    #[serde(default)]
    pub flags: ShapeFlags,
    /// False to create a dynamic body asleep (Box2D's `isAwake = false`): it costs nothing
    /// until a moving body reaches it, a joint is made to it, or it is pushed, and then it
    /// wakes. Bodies created asleep that touch sleep as one island, as if they had come to rest
    /// together, and wake together. It must be at rest. Default true.
    #[serde(default = "starts_awake")]
    pub awake: bool,
}

/// [`Body::sleep_time`] of a body created asleep and not woken since: it sleeps with the
/// bodies created asleep that it touches (see `World::settle_created_asleep`).
pub(crate) const CREATED_ASLEEP: Real = -1.0;

/// A body starts awake unless its definition says otherwise.
fn starts_awake() -> bool {
    true
}

impl BodyDef {
    /// A dynamic body of density 1 kg/m^2 at rest at `position`, friction 0.6, restitution 0.
    pub fn dynamic(shape: Shape, position: Vec2) -> BodyDef {
        BodyDef {
            shape,
            position,
            angle: 0.0,
            linear_velocity: Vec2::ZERO,
            angular_velocity: 0.0,
            mass: MassSpec::Density(1.0),
            friction: 0.6,
            restitution: 0.0,
            filter: Filter::DEFAULT,
            parts: Vec::new(),
            flags: ShapeFlags::NONE,
            awake: true,
        }
    }

    /// A dynamic body (as [`BodyDef::dynamic`]) of a shape drawn around `origin` (m) in the
    /// body's frame and turned by `angle` (rad), whose centre of mass lies `offset` (m, body
    /// frame) from that origin: a polygon's centroid as [`super::Polygon::new`] returns it, zero
    /// for a shape centred on its origin. The body's position, its centre of mass, is
    /// `origin + R(angle) offset`: how scene files and spawns place polygons given around a
    /// position. Refuses a non-finite `origin` or `angle`, naming `position.x`, `position.y`
    /// or `angle`.
    pub fn placed(
        shape: Shape,
        offset: Vec2,
        origin: Vec2,
        angle: Real,
    ) -> Result<BodyDef, PhysicsError> {
        finite_vec(["position.x", "position.y"], origin)?;
        finite("angle", angle)?;
        let position = origin + Rot::from_angle(angle).rotate(offset);
        Ok(BodyDef::dynamic(shape, position).with_angle(angle))
    }

    /// A kinematic body at `position` moving at `velocity` (m/s), friction 0.6, restitution 0.
    pub fn kinematic(shape: Shape, position: Vec2, velocity: Vec2) -> BodyDef {
        BodyDef {
            mass: MassSpec::Kinematic,
            linear_velocity: velocity,
            ..BodyDef::dynamic(shape, position)
        }
    }

    /// A static (immovable) body at `position`, friction 0.6, restitution 0.
    pub fn fixed(shape: Shape, position: Vec2) -> BodyDef {
        BodyDef {
            mass: MassSpec::Static,
            ..BodyDef::dynamic(shape, position)
        }
    }

    builder_setters! {
        /// Set the orientation (radians).
        with_angle(angle: Real) => angle = angle;
        /// Set the linear velocity (m/s).
        with_velocity(v: Vec2) => linear_velocity = v;
        /// Set the angular velocity (rad/s).
        with_angular_velocity(w: Real) => angular_velocity = w;
        /// Set the density (kg/m^2).
        with_density(density: Real) => mass = MassSpec::Density(density);
        /// Set the total mass (kg).
        with_mass(mass: Real) => mass = MassSpec::Mass(mass);
        /// Set the friction coefficient.
        with_friction(friction: Real) => friction = friction;
        /// Set the coefficient of restitution.
        with_restitution(restitution: Real) => restitution = restitution;
        /// Set the collision filter.
        with_filter(filter: Filter) => filter = filter;
        /// Set what its own shape reports and whether it is a sensor.
        with_flags(flags: ShapeFlags) => flags = flags;
        /// Create it awake (the default) or asleep (see [`BodyDef::awake`]).
        with_awake(awake: bool) => awake = awake;
    }

    /// Add a further shape (see [`BodyDef::parts`]).
    pub fn with_part(mut self, part: PartDef) -> Self {
        self.parts.push(part);
        self
    }

    /// A chain as static bodies, one segment each (friction 0.6, restitution 0; change them
    /// on the definitions). See [`super::segment::chain`] for the points and the refusals.
    pub fn chain(
        points: &[Vec2],
        closed: bool,
        one_sided: bool,
    ) -> Result<Vec<BodyDef>, PhysicsError> {
        Ok(super::segment::chain(points, closed, one_sided)?
            .into_iter()
            .map(|(mid, s)| BodyDef::fixed(Shape::Segment(Box::new(s)), mid))
            .collect())
    }

    /// Refuse anything the engine cannot simulate, naming the field and the value.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        self.shape.validate()?;
        finite_vec(["position.x", "position.y"], self.position)?;
        finite("angle", self.angle)?;
        finite_vec(["velocity.x", "velocity.y"], self.linear_velocity)?;
        finite("angular_velocity", self.angular_velocity)?;
        self.validate_parts()?;
        let moves = matches!(self.mass, MassSpec::Density(_) | MassSpec::Mass(_));
        if !self.awake {
            self.validate_asleep(moves)?;
        }
        let shapes = std::iter::once(&self.shape).chain(self.parts.iter().map(|p| &p.shape));
        if moves && shapes.clone().any(|s| matches!(s, Shape::Segment(_))) {
            return Err(PhysicsError::InvalidShape {
                field: "mass".into(),
                reason: "must be static or kinematic for a segment (segments and chains are \
                         terrain, platforms and paddles; a thick moving rod is a capsule)"
                    .into(),
            });
        }
        if let Some((field, m, i)) = match self.mass {
            MassSpec::Static | MassSpec::Kinematic => None,
            MassSpec::Density(d) => {
                positive("density", d)?;
                let data = mass_data(placed(&self.shape, d, &self.parts), None);
                Some(("mass (density x area)", data.mass, data.inertia))
            }
            MassSpec::Mass(m) => {
                positive("mass", m)?;
                let data = mass_data(placed(&self.shape, 1.0, &self.parts), Some(m));
                Some(("mass", m, data.inertia))
            }
        } {
            // Mass and inertia must stay usable: finite, with finite inverses.
            usable(field, m)?;
            usable("inertia (from mass and shape)", i)?;
        }
        check_material(self.friction, self.restitution)
    }

    /// A body created asleep is dynamic (static and kinematic bodies never sleep) and at rest
    /// (a sleeping body has no velocity).
    fn validate_asleep(&self, dynamic: bool) -> Result<(), PhysicsError> {
        let v = self.linear_velocity;
        let reason = if !dynamic {
            "only a dynamic body sleeps (a static or kinematic one is never asleep)".to_owned()
        } else if v != Vec2::ZERO || self.angular_velocity != 0.0 {
            format!(
                "a body created asleep must be at rest, and this one moves: velocity ({}, {}) \
                 m/s, angular_velocity {} rad/s",
                v.x, v.y, self.angular_velocity
            )
        } else {
            return Ok(());
        };
        Err(PhysicsError::CannotStartAsleep { reason })
    }

    /// Each part valid, its errors named `parts[i].field`, and not too many.
    fn validate_parts(&self) -> Result<(), PhysicsError> {
        if self.parts.len() >= MAX_SHAPES {
            return Err(PhysicsError::InvalidShape {
                field: "parts".into(),
                reason: format!(
                    "has {} shapes: a body may have at most {} besides its own",
                    self.parts.len(),
                    MAX_SHAPES - 1
                ),
            });
        }
        for (index, part) in self.parts.iter().enumerate() {
            part.validate().map_err(|e| PhysicsError::InPart {
                index,
                source: Box::new(e),
            })?;
        }
        Ok(())
    }
}

pub use super::error::MAX_FRICTION;

/// A mass or moment of inertia the solver can divide by: finite, positive, finite inverse.
fn usable(field: &'static str, value: Real) -> Result<Real, PhysicsError> {
    if value.is_finite() && value > 0.0 && (1.0 / value).is_finite() {
        Ok(value)
    } else {
        Err(PhysicsError::OutOfRange {
            field,
            value,
            expected: "must be finite and positive with a finite inverse",
        })
    }
}

/// What few bodies have, kept out of line ([`Body::extras`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Extras {
    pub filter: Filter,
    /// Its own shape's flags.
    pub flags: ShapeFlags,
    pub parts: Option<Parts>,
}

impl Extras {
    /// The extras of a body with this filter, flags and parts; None when it has none.
    pub fn boxed(filter: Filter, flags: ShapeFlags, parts: Option<Parts>) -> Option<Box<Extras>> {
        (filter != Filter::DEFAULT || flags.any() || parts.is_some()).then(|| {
            Box::new(Extras {
                filter,
                flags,
                parts,
            })
        })
    }
}

/// A rigid body as the World keeps it.
#[derive(Clone, Debug)]
pub struct Body {
    pub(crate) id: BodyId,
    /// The body's own shape, centred on its origin (and on its centre of mass unless it has
    /// parts).
    pub(crate) shape: Shape,
    /// What few bodies have (a filter other than the default, further shapes), out of line so
    /// that a plain body stays small: the step reads every body's fields, and a filter is 24
    /// bytes. None for a body of one shape with the default filter.
    pub(crate) extras: Option<Box<Extras>>,
    /// Whether `extras` holds parts: asked of every jointed and paired body each step, and a
    /// body with a filter but one shape (a ragdoll's bone) need not go to the heap to learn
    /// its centre of mass is its origin.
    pub(crate) has_parts: bool,
    /// `shape.bounding_radius()` (m), kept: the narrow phase and the sleep test read it for
    /// every pair and body each step (a square root for a box, a load from the heap for a
    /// polygon).
    pub(crate) bounding_radius: Real,
    /// `shape.min_extent()` (m), kept for the continuous collision test each step.
    pub(crate) min_extent: Real,
    /// The centre of mass (m), what the solver moves.
    pub(crate) position: Vec2,
    pub(crate) angle: Real,
    pub(crate) rot: Rot,
    pub(crate) linear_velocity: Vec2,
    pub(crate) angular_velocity: Real,
    pub(crate) force: Vec2,
    pub(crate) torque: Real,
    pub(crate) mass: Real,
    pub(crate) inv_mass: Real,
    pub(crate) inertia: Real,
    pub(crate) inv_inertia: Real,
    pub(crate) friction: Real,
    pub(crate) restitution: Real,
    /// False while the body sleeps (it then costs nothing per step).
    pub(crate) awake: bool,
    /// How long the body has been slower than the sleep threshold (s).
    pub(crate) sleep_time: Real,
    /// While asleep: the island it fell asleep with (a slot index), so it wakes with it.
    pub(crate) sleep_island: u32,
    /// Moved by its velocity only (infinite mass, see [`MassSpec::Kinematic`]).
    pub(crate) kinematic: bool,
}

impl Body {
    /// Build a body from a definition that has passed [`BodyDef::validate`].
    pub(crate) fn from_def(id: BodyId, def: &BodyDef) -> Body {
        let (data, own_density) = match def.mass {
            MassSpec::Static | MassSpec::Kinematic => (None, 1.0),
            MassSpec::Density(d) => (Some(mass_data(placed(&def.shape, d, &def.parts), None)), d),
            MassSpec::Mass(m) => {
                let data = mass_data(placed(&def.shape, 1.0, &def.parts), Some(m));
                (
                    Some(data),
                    m / mass_data(placed(&def.shape, 1.0, &def.parts), None).mass,
                )
            }
        };
        let (mass, inv_mass, inertia, inv_inertia) = match data {
            None => (Real::INFINITY, 0.0, Real::INFINITY, 0.0),
            Some(d) => (d.mass, 1.0 / d.mass, d.inertia, 1.0 / d.inertia),
        };
        let parts = (!def.parts.is_empty()).then(|| Body::parts_of(def, data, own_density));
        let rot = Rot::from_angle(def.angle);
        let kinematic = def.mass == MassSpec::Kinematic;
        let is_static = inv_mass == 0.0 && !kinematic;
        Body {
            id,
            shape: def.shape.clone(),
            bounding_radius: parts
                .as_ref()
                .map_or_else(|| def.shape.bounding_radius(), |p| p.bounding_radius()),
            min_extent: parts
                .as_ref()
                .map_or_else(|| def.shape.min_extent(), |p| p.min_extent()),
            position: match &parts {
                None => def.position,
                Some(p) => def.position + rot.rotate(p.local_center),
            },
            has_parts: parts.is_some(),
            extras: Extras::boxed(def.filter, def.flags, parts),
            angle: def.angle,
            rot,
            linear_velocity: if is_static {
                Vec2::ZERO
            } else {
                def.linear_velocity
            },
            angular_velocity: if is_static { 0.0 } else { def.angular_velocity },
            force: Vec2::ZERO,
            torque: 0.0,
            mass,
            inv_mass,
            inertia,
            inv_inertia,
            friction: def.friction,
            restitution: def.restitution,
            // Asleep, it is an island of its own: its slot is no other sleeping island's root.
            awake: def.awake,
            sleep_time: if def.awake { 0.0 } else { CREATED_ASLEEP },
            sleep_island: id.index,
            kinematic,
        }
    }

    /// The shapes of `def`, a body of several, around its centre of mass (`data`; a static or
    /// kinematic body turns about its origin). The parts keep their share of a body given by
    /// mass as their density (the own shape's is `own_density`), so that `to_def` gives the
    /// same body back.
    fn parts_of(def: &BodyDef, data: Option<super::part::MassData>, own_density: Real) -> Parts {
        let own = Part {
            shape: def.shape.clone(),
            pose: Transform {
                p: Vec2::ZERO,
                q: Rot::IDENTITY,
            },
            friction: def.friction,
            restitution: def.restitution,
            filter: def.filter,
            flags: def.flags,
        };
        let scale = own_density
            / match def.mass {
                MassSpec::Mass(_) => 1.0,
                _ => own_density,
            };
        let defs: Vec<PartDef> = def
            .parts
            .iter()
            .map(|p| PartDef {
                density: p.density * scale,
                ..p.clone()
            })
            .collect();
        let mut parts = Parts::new(own, &defs, data.map_or(Vec2::ZERO, |d| d.center));
        parts.own_density = own_density;
        parts
    }

    /// This body's id.
    pub fn id(&self) -> BodyId {
        self.id
    }
    /// The body's own shape, centred on its origin.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }
    /// The body's further shapes, placed from its origin (empty for a body of one shape).
    pub fn parts(&self) -> &[PartDef] {
        self.compound().map_or(&[], |p| &p.defs)
    }
    /// The body's origin, world coordinates (m): where its own shape is centred, the centre
    /// of mass unless it has parts.
    pub fn position(&self) -> Vec2 {
        match self.compound() {
            None => self.position,
            Some(p) => self.position - self.rot.rotate(p.local_center),
        }
    }
    /// The centre of mass, world coordinates (m).
    pub fn center_of_mass(&self) -> Vec2 {
        self.position
    }
    /// The centre of mass in the body's frame, from its origin (m; zero with no parts).
    pub fn local_center(&self) -> Vec2 {
        self.compound().map_or(Vec2::ZERO, |p| p.local_center)
    }
    /// Orientation (rad), accumulated: not wrapped to (-pi, pi].
    pub fn angle(&self) -> Real {
        self.angle
    }
    /// Collision filter (its own shape's, for a body of several).
    pub fn filter(&self) -> Filter {
        self.extras.as_ref().map_or(Filter::DEFAULT, |e| e.filter)
    }
    /// What its own shape reports, and whether it is a sensor.
    pub fn flags(&self) -> ShapeFlags {
        self.extras.as_ref().map_or(ShapeFlags::NONE, |e| e.flags)
    }
    /// Whether any of its shapes reports anything or is a sensor.
    pub(crate) fn any_flags(&self) -> bool {
        self.flags().any()
            || self
                .compound()
                .is_some_and(|p| p.all.iter().any(|part| part.flags.any()))
    }
    /// Whether any of its shapes has a flag that `pick` picks.
    pub(crate) fn asks(&self, pick: impl Fn(&ShapeFlags) -> bool) -> bool {
        pick(&self.flags())
            || self
                .compound()
                .is_some_and(|p| p.all.iter().any(|part| pick(&part.flags)))
    }
    /// A body of several shapes: all of them, in the centre-of-mass frame. None for a body of
    /// one shape, whose centre of mass is its origin.
    #[inline]
    pub(crate) fn compound(&self) -> Option<&Parts> {
        if !self.has_parts {
            return None;
        }
        self.extras.as_ref().and_then(|e| e.parts.as_ref())
    }
    /// Set the collision filter (of its own shape, for a body of several).
    pub(crate) fn set_filter(&mut self, filter: Filter) {
        let mut extras = self.extras.take().map_or_else(Extras::default, |e| *e);
        extras.filter = filter;
        if let Some(own) = extras.parts.as_mut().map(|p| &mut p.all[0]) {
            own.filter = filter;
        }
        self.extras = Extras::boxed(extras.filter, extras.flags, extras.parts);
    }
    /// Orientation as a rotation.
    pub fn rotation(&self) -> Rot {
        self.rot
    }
    /// Body-to-world transform, from the body's origin.
    pub fn transform(&self) -> Transform {
        Transform {
            p: self.position(),
            q: self.rot,
        }
    }
    /// Each of the body's shapes with its pose in the centre-of-mass frame.
    pub(crate) fn shapes(&self) -> impl Iterator<Item = (&Shape, Transform)> + Clone {
        let own = self
            .compound()
            .is_none()
            .then_some((&self.shape, Transform::IDENTITY));
        let parts = self.compound().into_iter().flat_map(|p| p.all.iter());
        own.into_iter().chain(parts.map(|p| (&p.shape, p.pose)))
    }
    /// The box around all the body's shapes as it is now.
    #[inline]
    pub(crate) fn aabb(&self) -> super::shape::Aabb {
        match self.compound() {
            None => self.shape.aabb(self.frame()),
            Some(parts) => parts.aabb(self.frame()),
        }
    }
    /// The transform from the centre-of-mass frame, in which the World keeps the shapes.
    #[inline]
    pub(crate) fn frame(&self) -> Transform {
        Transform {
            p: self.position,
            q: self.rot,
        }
    }
    /// Linear velocity (m/s).
    pub fn linear_velocity(&self) -> Vec2 {
        self.linear_velocity
    }
    /// Angular velocity (rad/s).
    pub fn angular_velocity(&self) -> Real {
        self.angular_velocity
    }
    /// Force accumulated for the next step (N); cleared after each step.
    pub fn force(&self) -> Vec2 {
        self.force
    }
    /// Torque accumulated for the next step (N m); cleared after each step.
    pub fn torque(&self) -> Real {
        self.torque
    }
    /// Mass (kg); infinite for static bodies.
    pub fn mass(&self) -> Real {
        self.mass
    }
    /// 1 / mass (1/kg); zero for static bodies.
    pub fn inv_mass(&self) -> Real {
        self.inv_mass
    }
    /// Moment of inertia about the centre of mass (kg m^2); infinite for static bodies.
    pub fn inertia(&self) -> Real {
        self.inertia
    }
    /// Friction coefficient.
    pub fn friction(&self) -> Real {
        self.friction
    }
    /// Coefficient of restitution.
    pub fn restitution(&self) -> Real {
        self.restitution
    }
    /// True for immovable bodies (not kinematic ones, which move).
    pub fn is_static(&self) -> bool {
        self.inv_mass == 0.0 && !self.kinematic
    }
    /// True for kinematic bodies: moved by their velocity, never by contacts or forces.
    pub fn is_kinematic(&self) -> bool {
        self.kinematic
    }
    /// True for a kinematic body with a non-zero velocity: it pushes and wakes what it meets.
    pub(crate) fn is_moving_kinematic(&self) -> bool {
        self.kinematic && (self.linear_velocity != Vec2::ZERO || self.angular_velocity != 0.0)
    }
    /// False while the body sleeps (resting with its island). Static bodies report true.
    pub fn is_awake(&self) -> bool {
        self.awake
    }
    /// True for a body created asleep that has not woken since.
    pub(crate) fn is_created_asleep(&self) -> bool {
        !self.awake && self.sleep_time == CREATED_ASLEEP
    }
    /// True for dynamic bodies that are awake: the ones the solver moves this step.
    pub(crate) fn is_active(&self) -> bool {
        self.awake && self.inv_mass > 0.0
    }
    /// Kinetic energy, translational plus rotational (J).
    pub fn kinetic_energy(&self) -> Real {
        if self.inv_mass == 0.0 {
            return 0.0;
        }
        0.5 * self.mass * self.linear_velocity.length_squared()
            + 0.5 * self.inertia * self.angular_velocity * self.angular_velocity
    }
    /// The definition that would recreate this body in its current state (a body of several
    /// shapes by its densities, the rest by their mass).
    pub fn to_def(&self) -> BodyDef {
        BodyDef {
            shape: self.shape.clone(),
            position: self.position(),
            angle: self.angle,
            linear_velocity: self.linear_velocity,
            angular_velocity: self.angular_velocity,
            mass: if self.kinematic {
                MassSpec::Kinematic
            } else if self.is_static() {
                MassSpec::Static
            } else if let Some(p) = self.compound() {
                MassSpec::Density(p.own_density)
            } else {
                MassSpec::Mass(self.mass)
            },
            friction: self.friction,
            restitution: self.restitution,
            filter: self.filter(),
            parts: self.parts().to_vec(),
            flags: self.flags(),
            awake: self.awake,
        }
    }
    /// True when every number in the body's state is finite.
    pub fn is_finite(&self) -> bool {
        is_finite_vec(self.position)
            && self.angle.is_finite()
            && is_finite_vec(self.linear_velocity)
            && self.angular_velocity.is_finite()
    }
}
