//! The World: bodies, gravity, settings, and `step(dt)`.

use super::body::{Body, BodyDef, BodyId};
use super::broad_phase::{pair_of, Proxy, SweepAndPrune};
use super::collide::collide;
use super::contact::{Contact, ContactInfo, ContactPoint, ContactPointInfo};
use super::error::{finite, positive, PhysicsError};
use super::math::{cross, Real, Rot, Vec2};
use super::settings::{Settings, SolverKind};
use super::solver::soft_step::Softness;
use super::solver::{self, clamp_speed, Limits, SolverBody};

/// One entry of the body array: a body, or a free slot remembering its generation.
#[derive(Clone, Debug)]
struct Slot {
    generation: u32,
    body: Option<Body>,
}

/// A 2D rigid-body world.
///
/// Units throughout: metres, seconds, radians, kilograms. Every method that takes input
/// validates it and refuses what cannot be simulated, so a World never holds NaN.
#[derive(Clone, Debug)]
pub struct World {
    settings: Settings,
    gravity: Vec2,
    slots: Vec<Slot>,
    free: Vec<u32>,
    body_count: usize,
    time: f64,
    steps: u64,
    broad_phase: SweepAndPrune,
    // Buffers reused every step, so a steady step does not allocate.
    proxies: Vec<Proxy>,
    pair_keys: Vec<u64>,
    contacts: Vec<Contact>,
    previous: Vec<Contact>,
    solver_bodies: Vec<SolverBody>,
}

impl Default for World {
    fn default() -> Self {
        World::with_settings(Settings::default(), Vec2::new(0.0, -9.81))
    }
}

impl World {
    /// An empty world with validated `settings` and `gravity` (m/s^2).
    pub fn new(settings: Settings, gravity: Vec2) -> Result<World, PhysicsError> {
        settings.validate()?;
        finite("gravity.x", gravity.x)?;
        finite("gravity.y", gravity.y)?;
        Ok(World::with_settings(settings, gravity))
    }

    fn with_settings(settings: Settings, gravity: Vec2) -> World {
        World {
            settings,
            gravity,
            slots: Vec::new(),
            free: Vec::new(),
            body_count: 0,
            time: 0.0,
            steps: 0,
            broad_phase: SweepAndPrune::default(),
            proxies: Vec::new(),
            pair_keys: Vec::new(),
            contacts: Vec::new(),
            previous: Vec::new(),
            solver_bodies: Vec::new(),
        }
    }

    /// The current settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replace the settings (validated first; on error nothing changes).
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), PhysicsError> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// Gravity (m/s^2).
    pub fn gravity(&self) -> Vec2 {
        self.gravity
    }

    /// Set gravity (m/s^2), effective from the next step.
    pub fn set_gravity(&mut self, gravity: Vec2) -> Result<(), PhysicsError> {
        finite("gravity.x", gravity.x)?;
        finite("gravity.y", gravity.y)?;
        self.gravity = gravity;
        Ok(())
    }

    /// Simulated time so far (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken so far.
    pub fn step_count(&self) -> u64 {
        self.steps
    }

    /// Add a body; the definition is validated first and nothing changes on error.
    pub fn add_body(&mut self, def: &BodyDef) -> Result<BodyId, PhysicsError> {
        def.validate()?;
        let index = match self.free.pop() {
            Some(i) => i,
            None => {
                let i = u32::try_from(self.slots.len())
                    .map_err(|_| PhysicsError::Full(self.body_count))?;
                self.slots.push(Slot {
                    generation: 0,
                    body: None,
                });
                i
            }
        };
        let slot = &mut self.slots[index as usize];
        let id = BodyId {
            index,
            generation: slot.generation,
        };
        slot.body = Some(Body::from_def(id, def));
        self.body_count += 1;
        self.broad_phase.insert(index);
        Ok(id)
    }

    /// Remove a body and every contact it had; returns the removed body.
    pub fn remove_body(&mut self, id: BodyId) -> Result<Body, PhysicsError> {
        self.body(id).ok_or(PhysicsError::UnknownBody(id))?;
        let slot = &mut self.slots[id.index as usize];
        let body = slot.body.take().ok_or(PhysicsError::UnknownBody(id))?;
        slot.generation = slot.generation.wrapping_add(1);
        self.free.push(id.index);
        self.body_count -= 1;
        self.broad_phase.remove(id.index);
        self.contacts.retain(|c| c.a != id.index && c.b != id.index);
        Ok(body)
    }

    /// Remove every body and contact; settings, gravity and time are kept.
    pub fn clear(&mut self) {
        self.slots.clear();
        self.free.clear();
        self.body_count = 0;
        self.broad_phase.clear();
        self.contacts.clear();
        self.previous.clear();
    }

    /// The body with this id, if it is still in the world.
    pub fn body(&self, id: BodyId) -> Option<&Body> {
        self.slots
            .get(id.index as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.body.as_ref())
    }

    fn body_mut(&mut self, id: BodyId) -> Result<&mut Body, PhysicsError> {
        self.slots
            .get_mut(id.index as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.body.as_mut())
            .ok_or(PhysicsError::UnknownBody(id))
    }

    /// Every body, in slot order.
    pub fn bodies(&self) -> impl Iterator<Item = &Body> + '_ {
        self.slots.iter().filter_map(|s| s.body.as_ref())
    }

    /// Number of bodies.
    pub fn body_count(&self) -> usize {
        self.body_count
    }

    /// Add a force (N) through the centre of mass for the next step.
    pub fn apply_force(&mut self, id: BodyId, force: Vec2) -> Result<(), PhysicsError> {
        finite("force.x", force.x)?;
        finite("force.y", force.y)?;
        let b = self.body_mut(id)?;
        b.force += force;
        Ok(())
    }

    /// Add a force (N) at a world point (m) for the next step: force plus torque r x F.
    pub fn apply_force_at(
        &mut self,
        id: BodyId,
        force: Vec2,
        point: Vec2,
    ) -> Result<(), PhysicsError> {
        finite("force.x", force.x)?;
        finite("force.y", force.y)?;
        finite("point.x", point.x)?;
        finite("point.y", point.y)?;
        let b = self.body_mut(id)?;
        b.force += force;
        b.torque += cross(point - b.position, force);
        Ok(())
    }

    /// Add a torque (N m) for the next step.
    pub fn apply_torque(&mut self, id: BodyId, torque: Real) -> Result<(), PhysicsError> {
        finite("torque", torque)?;
        let b = self.body_mut(id)?;
        b.torque += torque;
        Ok(())
    }

    /// Apply an impulse (N s) at the centre of mass now: v += P / m.
    pub fn apply_impulse(&mut self, id: BodyId, impulse: Vec2) -> Result<(), PhysicsError> {
        let p = self
            .body(id)
            .map(|b| b.position)
            .ok_or(PhysicsError::UnknownBody(id))?;
        self.apply_impulse_at(id, impulse, p)
    }

    /// Apply an impulse (N s) at a world point (m) now: v += P / m, w += (r x P) / I.
    pub fn apply_impulse_at(
        &mut self,
        id: BodyId,
        impulse: Vec2,
        point: Vec2,
    ) -> Result<(), PhysicsError> {
        finite("impulse.x", impulse.x)?;
        finite("impulse.y", impulse.y)?;
        finite("point.x", point.x)?;
        finite("point.y", point.y)?;
        let max_v = self.settings.max_linear_speed;
        let max_w = self.settings.max_rotation * 1e3;
        let b = self.body_mut(id)?;
        b.linear_velocity = clamp_speed(b.linear_velocity + b.inv_mass * impulse, max_v);
        let w = b.angular_velocity + b.inv_inertia * cross(point - b.position, impulse);
        b.angular_velocity = if w.is_finite() {
            w.clamp(-max_w, max_w)
        } else {
            0.0
        };
        Ok(())
    }

    /// Set a body's velocities (m/s, rad/s). Ignored for static bodies.
    pub fn set_velocity(
        &mut self,
        id: BodyId,
        linear: Vec2,
        angular: Real,
    ) -> Result<(), PhysicsError> {
        finite("velocity.x", linear.x)?;
        finite("velocity.y", linear.y)?;
        finite("angular_velocity", angular)?;
        let b = self.body_mut(id)?;
        if !b.is_static() {
            b.linear_velocity = linear;
            b.angular_velocity = angular;
        }
        Ok(())
    }

    /// Number of contacts (touching or speculative pairs) found in the last step.
    pub fn contact_count(&self) -> usize {
        self.contacts.len()
    }

    /// The contacts found in the last step, with the impulses the solver applied.
    pub fn contacts(&self) -> impl Iterator<Item = ContactInfo> + '_ {
        self.contacts.iter().map(move |c| {
            let id = |i: u32| BodyId {
                index: i,
                generation: self.slots[i as usize].generation,
            };
            let mut points = [ContactPointInfo {
                point: Vec2::ZERO,
                separation: 0.0,
                normal_impulse: 0.0,
                tangent_impulse: 0.0,
            }; 2];
            for (out, p) in points.iter_mut().zip(&c.points[..c.count]) {
                *out = ContactPointInfo {
                    point: p.point,
                    separation: p.separation,
                    normal_impulse: p.total_normal_impulse,
                    tangent_impulse: p.tangent_impulse,
                };
            }
            ContactInfo {
                body_a: id(c.a),
                body_b: id(c.b),
                normal: c.normal,
                points,
                count: c.count,
            }
        })
    }

    /// Total kinetic energy (J).
    pub fn kinetic_energy(&self) -> Real {
        self.bodies().map(Body::kinetic_energy).sum()
    }

    /// Total potential energy in the current gravity field, relative to the origin (J).
    pub fn potential_energy(&self) -> Real {
        self.bodies()
            .filter(|b| !b.is_static())
            .map(|b| -b.mass * self.gravity.dot(b.position))
            .sum()
    }

    /// Advance the world by `dt` seconds.
    ///
    /// The pipeline of the appendix: (1) integrate forces and gravity into velocities,
    /// (2) find contacts, (3) solve contact impulses, (4) integrate positions. The soft-step
    /// solver runs (1), (3) and (4) inside each substep. Forces and torques are cleared after.
    pub fn step(&mut self, dt: Real) -> Result<(), PhysicsError> {
        positive("dt", dt)?;
        let limits = Limits {
            max_linear_speed: self.settings.max_linear_speed,
            max_rotation: self.settings.max_rotation,
        };
        self.load_solver_bodies();
        match self.settings.solver {
            SolverKind::Sequential => {
                solver::integrate_velocities(&mut self.solver_bodies, dt, limits);
                self.find_contacts(dt, self.settings.speculative_distance);
                solver::sequential::solve(
                    &mut self.solver_bodies,
                    &mut self.contacts,
                    &self.settings,
                    dt,
                );
                solver::integrate_positions(&mut self.solver_bodies, dt, limits);
            }
            SolverKind::SoftStep => {
                self.find_contacts(dt, self.settings.speculative_distance);
                solver::soft_step::solve(
                    &mut self.solver_bodies,
                    &mut self.contacts,
                    &self.settings,
                    dt,
                    limits,
                );
            }
        }
        self.store_solver_bodies();
        self.time += dt as f64;
        self.steps += 1;
        Ok(())
    }

    /// Copy what the solver needs into the compact solver array.
    fn load_solver_bodies(&mut self) {
        let g = self.gravity;
        self.solver_bodies.clear();
        self.solver_bodies
            .extend(self.slots.iter().map(|slot| match &slot.body {
                Some(b) if !b.is_static() => SolverBody {
                    v: b.linear_velocity,
                    w: b.angular_velocity,
                    inv_mass: b.inv_mass,
                    inv_inertia: b.inv_inertia,
                    accel: g + b.inv_mass * b.force,
                    alpha: b.inv_inertia * b.torque,
                    dp: Vec2::ZERO,
                    dtheta: 0.0,
                    dq: Rot::IDENTITY,
                },
                _ => SolverBody::FIXED,
            }));
    }

    /// Write velocities and the step's motion back to the bodies; clear forces.
    fn store_solver_bodies(&mut self) {
        for (slot, sb) in self.slots.iter_mut().zip(&self.solver_bodies) {
            let Some(b) = slot.body.as_mut() else {
                continue;
            };
            if b.is_static() {
                continue;
            }
            b.linear_velocity = sb.v;
            b.angular_velocity = sb.w;
            b.position += sb.dp;
            b.angle += sb.dtheta;
            b.rot = Rot::from_angle(b.angle);
            b.force = Vec2::ZERO;
            b.torque = 0.0;
        }
    }

    /// Broad phase, then narrow phase, then match points with last step's for warm starting.
    ///
    /// `speculative` > 0 also keeps points that are up to that far apart, plus however far
    /// the pair can close in `dt` (so fast bodies meet the surface instead of tunnelling).
    fn find_contacts(&mut self, dt: Real, speculative: Real) {
        // Proxies: each body's box grown by half the speculative distance plus how far it can
        // travel this step.
        let g = self.gravity;
        self.proxies.clear();
        self.proxies
            .extend(self.slots.iter().map(|slot| match &slot.body {
                Some(b) => {
                    let reach = if speculative > 0.0 && !b.is_static() {
                        travel(b, g, dt)
                    } else {
                        0.0
                    };
                    Proxy {
                        aabb: b
                            .shape
                            .aabb(b.transform())
                            .inflated(0.5 * speculative + reach),
                        is_static: b.is_static(),
                    }
                }
                None => Proxy {
                    aabb: super::shape::Aabb {
                        min: Vec2::ZERO,
                        max: Vec2::ZERO,
                    },
                    is_static: true,
                },
            }));
        self.broad_phase
            .find_pairs(&self.proxies, &mut self.pair_keys);

        std::mem::swap(&mut self.contacts, &mut self.previous);
        self.contacts.clear();
        let mut old = 0usize;
        let fm = self.settings.friction_mixing;
        let rm = self.settings.restitution_mixing;
        for &key in &self.pair_keys {
            let (ia, ib) = pair_of(key);
            let (Some(a), Some(b)) = (&self.slots[ia as usize].body, &self.slots[ib as usize].body)
            else {
                continue;
            };
            let margin = if speculative > 0.0 {
                speculative + travel(a, g, dt) + travel(b, g, dt)
            } else {
                0.0
            };
            let manifold = collide(&a.shape, a.transform(), &b.shape, b.transform(), margin);
            if manifold.count == 0 {
                continue;
            }
            // Both lists are sorted by key: advance the cursor in the old one.
            while old < self.previous.len() && self.previous[old].key < key {
                old += 1;
            }
            let previous = self.previous.get(old).filter(|c| c.key == key);
            let mut contact = Contact {
                key,
                a: ia,
                b: ib,
                normal: manifold.normal,
                friction: fm.mix(a.friction, b.friction),
                restitution: rm.mix(a.restitution, b.restitution),
                touches_static: a.is_static() || b.is_static(),
                points: [ContactPoint::default(); 2],
                count: manifold.count,
                softness: Softness::RIGID,
            };
            for (cp, mp) in contact.points.iter_mut().zip(manifold.points()) {
                cp.id = mp.id;
                cp.point = mp.point;
                cp.separation = mp.separation;
                cp.anchor_a = mp.point - a.position;
                cp.anchor_b = mp.point - b.position;
                if let Some(prev) =
                    previous.and_then(|c| c.points[..c.count].iter().find(|p| p.id == mp.id))
                {
                    cp.normal_impulse = prev.normal_impulse;
                    cp.tangent_impulse = prev.tangent_impulse;
                }
            }
            self.contacts.push(contact);
        }
    }
}

/// How far any point of body `b` can move in `dt` (m): linear plus rotational reach, plus
/// what gravity and applied force add within the step.
#[inline]
fn travel(b: &Body, g: Vec2, dt: Real) -> Real {
    let accel = g + b.inv_mass * b.force;
    dt * (b.linear_velocity.length() + b.angular_velocity.abs() * b.shape.bounding_radius())
        + dt * dt * accel.length()
}
