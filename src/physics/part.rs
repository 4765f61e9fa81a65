//! Bodies of several shapes: a body's further shapes (its parts), each placed in the body's
//! frame with its own material and filter, and the mass, centre and inertia they add up to.
//!
//! A body's own shape ([`super::BodyDef::shape`]) sits at its origin; each part is placed
//! relative to that origin. The centre of mass is then no longer the origin: the World keeps
//! the centre (the solver moves it and the bodies turn about it) and every part in a frame
//! centred on it, while the API reports the origin ([`super::Body::position`]). A body with no
//! parts keeps its centre at its origin and pays nothing for any of this.

use super::builder::builder_setters;
use super::error::{check_material, finite, finite_vec, positive, PhysicsError};
use super::events::ShapeFlags;
use super::filter::Filter;
use super::math::{Real, Rot, Transform, Vec2};
use super::part_tree::{PartTree, TREE_FROM};
use super::shape::{Aabb, Shape};
use serde::{Deserialize, Serialize};

/// The most shapes a body may have, its own included (a contact names its shapes in 16 bits).
pub const MAX_SHAPES: usize = 1024;

/// One further shape of a body: where it sits and what it is made of.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartDef {
    /// The shape, centred on its own centroid (as [`Shape`]s are).
    pub shape: Shape,
    /// Where the shape's centre sits, in the body's frame from its origin (m).
    pub offset: Vec2,
    /// How far the shape is turned in the body's frame (rad, counter-clockwise).
    pub angle: Real,
    /// Density (kg/m^2); read for dynamic bodies given by density, and for the share of a
    /// body's mass a part takes when the body is given by mass.
    pub density: Real,
    /// Coulomb friction coefficient, >= 0.
    pub friction: Real,
    /// Coefficient of restitution in [0, 1].
    pub restitution: Real,
    /// Which other shapes it collides with (default: all).
    #[serde(default)]
    pub filter: Filter,
    /// What it reports, and whether it is a sensor (default: nothing, not a sensor).
    #[serde(default)]
    pub flags: ShapeFlags,
}

impl PartDef {
    /// A part of `shape` centred at `offset` (m, body frame), unturned, density 1 kg/m^2,
    /// friction 0.6, restitution 0, the default filter.
    pub fn new(shape: Shape, offset: Vec2) -> PartDef {
        PartDef {
            shape,
            offset,
            angle: 0.0,
            density: 1.0,
            friction: 0.6,
            restitution: 0.0,
            filter: Filter::DEFAULT,
            flags: ShapeFlags::NONE,
        }
    }

    builder_setters! {
        /// Set the angle in the body's frame (rad).
        with_angle(angle: Real) => angle = angle;
        /// Set the density (kg/m^2).
        with_density(density: Real) => density = density;
        /// Set the friction coefficient.
        with_friction(friction: Real) => friction = friction;
        /// Set the coefficient of restitution.
        with_restitution(restitution: Real) => restitution = restitution;
        /// Set the collision filter.
        with_filter(filter: Filter) => filter = filter;
        /// Set what it reports and whether it is a sensor.
        with_flags(flags: ShapeFlags) => flags = flags;
    }

    /// Refuse what cannot be simulated, naming the field (the caller names the part).
    pub fn validate(&self) -> Result<(), PhysicsError> {
        self.shape.validate()?;
        finite_vec(["offset.x", "offset.y"], self.offset)?;
        finite("angle", self.angle)?;
        positive("density", self.density)?;
        check_material(self.friction, self.restitution)
    }

    /// The part's pose in the body's frame about its origin.
    fn pose(&self) -> Transform {
        Transform {
            p: self.offset,
            q: Rot::from_angle(self.angle),
        }
    }
}

/// A shape of a body of several, as the World keeps it: placed in the body's frame centred on
/// its centre of mass.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    pub shape: Shape,
    /// The shape's pose in the body's centre-of-mass frame.
    pub pose: Transform,
    pub friction: Real,
    pub restitution: Real,
    pub filter: Filter,
    pub flags: ShapeFlags,
}

impl Part {
    /// The part's box with its body at `body` (the centre-of-mass frame).
    pub fn aabb(&self, body: Transform) -> Aabb {
        self.shape.aabb(body.then(self.pose))
    }
}

/// The shapes of a body of several: its own first, then its parts, each in the
/// centre-of-mass frame; and the definitions they came from (what `to_def` gives back).
#[derive(Clone, Debug)]
pub(crate) struct Parts {
    pub all: Vec<Part>,
    /// The centre of mass in the body's frame from its origin (m).
    pub local_center: Vec2,
    /// The parts as given, with the share of a body given by mass as their densities.
    pub defs: Vec<PartDef>,
    /// The density of the body's own shape (kg/m^2; its share of a body given by mass).
    pub own_density: Real,
    /// Over the shapes' boxes in the centre-of-mass frame, for a body of more than
    /// [`TREE_FROM`] shapes.
    pub tree: Option<PartTree>,
}

/// A body's mass properties worked out from its shapes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MassData {
    /// Mass (kg).
    pub mass: Real,
    /// Centre of mass in the body's frame from its origin (m).
    pub center: Vec2,
    /// Moment of inertia about the centre of mass (kg m^2).
    pub inertia: Real,
}

/// The mass properties of shapes placed at poses with densities (kg/m^2), scaled to a total
/// of `total` kg when given: m = sum m_i, c = sum m_i c_i / m, and by the parallel-axis
/// theorem I = sum (I_i + m_i |c_i - c|^2), each I_i about the shape's own centroid.
pub(crate) fn mass_data<'a>(
    shapes: impl Iterator<Item = (&'a Shape, Vec2, Real)> + Clone,
    total: Option<Real>,
) -> MassData {
    let bare: Real = shapes.clone().map(|(s, _, d)| d * s.area()).sum();
    let scale = total.map_or(1.0, |m| m / bare);
    let mass = bare * scale;
    let moment: Vec2 = shapes
        .clone()
        .map(|(s, c, d)| d * scale * s.area() * c)
        .fold(Vec2::ZERO, |a, b| a + b);
    let center = moment / mass;
    let inertia = shapes
        .map(|(s, c, d)| {
            let m = d * scale * s.area();
            s.inertia(m) + m * (c - center).length_squared()
        })
        .sum();
    MassData {
        mass,
        center,
        inertia,
    }
}

impl Parts {
    /// The shapes of a body whose own shape `own` (with its material and filter) sits at the
    /// origin, plus `defs`, all moved into the frame centred on `local_center`.
    pub fn new(own: Part, defs: &[PartDef], local_center: Vec2) -> Parts {
        let shift = |pose: Transform| Transform {
            p: pose.p - local_center,
            q: pose.q,
        };
        let mut all = Vec::with_capacity(defs.len() + 1);
        all.push(Part {
            pose: shift(own.pose),
            ..own
        });
        all.extend(defs.iter().map(|d| Part {
            shape: d.shape.clone(),
            pose: shift(d.pose()),
            friction: d.friction,
            restitution: d.restitution,
            filter: d.filter,
            flags: d.flags,
        }));
        let tree = (all.len() > TREE_FROM).then(|| {
            let boxes: Vec<Aabb> = all.iter().map(|p| p.shape.aabb(p.pose)).collect();
            PartTree::new(&boxes)
        });
        Parts {
            all,
            local_center,
            defs: defs.to_vec(),
            own_density: 1.0,
            tree,
        }
    }

    /// The radius about the centre of mass that holds every shape (m).
    pub fn bounding_radius(&self) -> Real {
        self.all
            .iter()
            .map(|p| p.pose.p.length() + p.shape.bounding_radius())
            .fold(0.0, Real::max)
    }

    /// The smallest of the shapes' shortest extents (m): a body is fast when it moves a
    /// fraction of it in a step.
    pub fn min_extent(&self) -> Real {
        self.all
            .iter()
            .map(|p| p.shape.min_extent())
            .fold(Real::INFINITY, Real::min)
    }

    /// The union of the shapes' boxes with the body at `body` (its centre-of-mass frame).
    pub fn aabb(&self, body: Transform) -> Aabb {
        let mut boxes = self.all.iter().map(|p| p.aabb(body));
        let first = boxes.next().expect("a body has its own shape");
        boxes.fold(first, |a, b| Aabb {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
        })
    }
}

/// The pose of each part (their defs) in the body frame, with the body's own shape first at the
/// origin, and each one's density (the own shape's `own_density`).
pub(crate) fn placed<'a>(
    own: &'a Shape,
    own_density: Real,
    defs: &'a [PartDef],
) -> impl Iterator<Item = (&'a Shape, Vec2, Real)> + Clone {
    std::iter::once((own, Vec2::ZERO, own_density))
        .chain(defs.iter().map(|d| (&d.shape, d.offset, d.density)))
}
