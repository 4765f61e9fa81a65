//! The World: bodies, gravity, settings, and `step(dt)`.

use super::body::{Body, BodyDef, BodyId};
use super::broad_phase::{pair_of, Proxy, SweepAndPrune};
use super::collide::collide;
use super::contact::{Contact, ContactInfo, ContactPoint, ContactPointInfo};
use super::error::{finite, positive, PhysicsError};
use super::math::{cross, Real, Rot, Vec2};
use super::settings::{Settings, SolverKind};
use super::solver::soft_step::Softness;
use super::solver::wide::WideSolver;
use super::solver::{self, clamp_speed, Limits, Moving, SolverBody};

/// Export and import of the full state (checkpoints); a child module so it reads private fields.
#[path = "snapshot.rs"]
pub mod snapshot;

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
    /// Contacts between bodies that sleep (or sleep and static): kept for warm starting and to
    /// wake islands, never solved.
    sleeping_contacts: Vec<Contact>,
    solver_bodies: Vec<SolverBody>,
    wide: WideSolver,
    split_impulse: solver::sequential::SplitImpulse,
    // Adaptive stiffness, reused every step: each contact's and each slot's tier, and the
    // contacts and bodies of the tiers above the base while they are solved apart.
    contact_tier: Vec<u8>,
    body_tier: Vec<u8>,
    tier_contacts: [Vec<Contact>; TIERS],
    tier_bodies: Vec<u32>,
    // Sleep bookkeeping, reused every step.
    wake_queue: Vec<u32>,
    island_parent: Vec<u32>,
    island_rest: Vec<Real>,
    changed: Vec<u32>,
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
            sleeping_contacts: Vec::new(),
            solver_bodies: Vec::new(),
            wide: WideSolver::default(),
            split_impulse: Default::default(),
            contact_tier: Vec::new(),
            body_tier: Vec::new(),
            tier_contacts: Default::default(),
            tier_bodies: Vec::new(),
            wake_queue: Vec::new(),
            island_parent: Vec::new(),
            island_rest: Vec::new(),
            changed: Vec::new(),
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
        self.wake_all();
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
        if gravity != self.gravity {
            // A tilt changes what "at rest" means for everything.
            self.wake_all();
        }
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
        self.check_speed(
            def.linear_velocity,
            def.angular_velocity,
            def.shape.bounding_radius(),
        )?;
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
        let body = Body::from_def(id, def);
        let passive = body.is_static();
        slot.body = Some(body);
        self.body_count += 1;
        self.broad_phase.insert(index, passive);
        Ok(id)
    }

    /// Remove a body and every contact it had; returns the removed body.
    pub fn remove_body(&mut self, id: BodyId) -> Result<Body, PhysicsError> {
        self.body(id).ok_or(PhysicsError::UnknownBody(id))?;
        // Whatever rested on this body must notice it is gone.
        let i = id.index;
        for c in self.contacts.iter().chain(&self.sleeping_contacts) {
            if c.a == i || c.b == i {
                self.wake_queue.push(if c.a == i { c.b } else { c.a });
            }
        }
        self.wake_queued();
        self.sleeping_contacts.retain(|c| c.a != i && c.b != i);
        let slot = &mut self.slots[id.index as usize];
        let body = slot.body.take().ok_or(PhysicsError::UnknownBody(id))?;
        slot.generation = slot.generation.wrapping_add(1);
        self.free.push(id.index);
        self.body_count -= 1;
        self.broad_phase.remove(id.index);
        self.contacts.retain(|c| c.a != id.index && c.b != id.index);
        Ok(body)
    }

    /// Refuse speeds beyond the World's speed cap: linear speed, and the rim speed |w| r of a
    /// body of bounding radius r. (The solver clamps speeds anyway; a velocity given at the
    /// API beyond the cap is a mistake worth naming.)
    fn check_speed(&self, v: Vec2, w: Real, radius: Real) -> Result<(), PhysicsError> {
        let max = self.settings.max_linear_speed;
        let expected = "must not exceed Settings::max_linear_speed (default 400 m/s)";
        if v.length() > max {
            return Err(PhysicsError::OutOfRange {
                field: "velocity (speed)",
                value: v.length(),
                expected,
            });
        }
        if w.abs() * radius > max {
            return Err(PhysicsError::OutOfRange {
                field: "angular_velocity (rim speed)",
                value: w.abs() * radius,
                expected,
            });
        }
        Ok(())
    }

    /// Remove every body and contact; settings, gravity and time are kept.
    pub fn clear(&mut self) {
        self.slots.clear();
        self.free.clear();
        self.body_count = 0;
        self.broad_phase.clear();
        self.contacts.clear();
        self.previous.clear();
        self.sleeping_contacts.clear();
    }

    /// The body with this id, if it is still in the world.
    pub fn body(&self, id: BodyId) -> Option<&Body> {
        self.slots
            .get(id.index as usize)
            .filter(|s| s.generation == id.generation)
            .and_then(|s| s.body.as_ref())
    }

    /// A body by id, woken (with its island) first: anything that pushes a body wakes it.
    fn body_mut(&mut self, id: BodyId) -> Result<&mut Body, PhysicsError> {
        if self.body(id).is_some_and(|b| !b.awake) {
            self.wake_queue.push(id.index);
            self.wake_queued();
        }
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

    /// Number of dynamic bodies that are awake (the ones a step moves).
    pub fn awake_count(&self) -> usize {
        self.bodies().filter(|b| b.is_active()).count()
    }

    /// Wake every sleeping body.
    pub fn wake_all(&mut self) {
        let sleeping = self
            .slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.body.as_ref().is_some_and(|b| !b.awake));
        self.wake_queue.extend(sleeping.map(|(i, _)| i as u32));
        self.wake_queued();
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
        let radius = self
            .body(id)
            .ok_or(PhysicsError::UnknownBody(id))?
            .shape
            .bounding_radius();
        self.check_speed(linear, angular, radius)?;
        let b = self.body_mut(id)?;
        if !b.is_static() {
            b.linear_velocity = linear;
            b.angular_velocity = angular;
        }
        Ok(())
    }

    /// Number of contacts (touching or speculative pairs), sleeping ones included.
    pub fn contact_count(&self) -> usize {
        self.contacts.len() + self.sleeping_contacts.len()
    }

    /// The contacts found in the last step, with the impulses the solver applied.
    pub fn contacts(&self) -> impl Iterator<Item = ContactInfo> + '_ {
        self.contacts
            .iter()
            .chain(&self.sleeping_contacts)
            .map(move |c| {
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
            .filter(|b| b.inv_mass > 0.0)
            .map(|b| -b.mass * self.gravity.dot(b.position))
            .sum()
    }

    /// Advance the world by `dt` seconds.
    ///
    /// The pipeline of the appendix: (1) integrate forces and gravity into velocities,
    /// (2) find contacts, (3) solve contact impulses, (4) integrate positions. Contacts depend
    /// on positions only, so they are found first (which also wakes whatever an awake body is
    /// about to touch); the soft-step solver runs (1), (3) and (4) inside each substep. Then
    /// resting islands fall asleep. Forces and torques are cleared after the step.
    pub fn step(&mut self, dt: Real) -> Result<(), PhysicsError> {
        positive("dt", dt)?;
        if self.broad_phase.active_is_empty() {
            // Everything is static or asleep (anything pushed would have been woken): nothing
            // moves, nothing to find or solve.
            self.time += dt as f64;
            self.steps += 1;
            return Ok(());
        }
        let limits = Limits {
            max_linear_speed: self.settings.max_linear_speed,
            max_rotation: self.settings.max_rotation,
        };
        self.find_contacts(dt, self.settings.speculative_distance);
        self.load_solver_bodies();
        match self.settings.solver {
            SolverKind::Sequential => {
                solver::integrate_velocities(&mut self.solver_bodies, Moving::All, dt, limits);
                solver::sequential::solve(
                    &mut self.solver_bodies,
                    &mut self.contacts,
                    &self.settings,
                    dt,
                );
                solver::integrate_positions(&mut self.solver_bodies, Moving::All, dt, limits);
                self.split_impulse.correct(
                    &mut self.solver_bodies,
                    &self.contacts,
                    &self.settings,
                    dt,
                );
            }
            SolverKind::SoftStep => self.solve_soft_step(dt, limits),
        }
        self.store_solver_bodies();
        self.move_kinematic(dt);
        if self.settings.enable_sleep {
            self.update_sleep(dt);
        }
        self.time += dt as f64;
        self.steps += 1;
        Ok(())
    }

    /// The soft step, with adaptive stiffness: islands whose load calls for it are solved apart,
    /// with 2 or 4 times the substeps, relax passes and contact stiffness
    /// (`Settings::adaptive_stiffness`); the rest, usually everything, in one solve as before.
    fn solve_soft_step(&mut self, dt: Real, limits: Limits) {
        let top = if self.settings.adaptive_stiffness {
            self.assign_tiers()
        } else {
            0
        };
        if top == 0 {
            solver::soft_step::solve(
                &mut self.solver_bodies,
                Moving::All,
                &mut self.contacts,
                &mut self.wide,
                &self.settings,
                dt,
                limits,
            );
            return;
        }
        let mut has_contacts = [false; TIERS];
        for &t in &self.contact_tier {
            has_contacts[t as usize] = true;
        }
        // Usually every contact is in one tier (a stack, a pyramid, a pile): solve them where
        // they are. Otherwise each tier's contacts are moved to a list of their own.
        let split = has_contacts.iter().filter(|&&h| h).count() > 1;
        if split {
            for group in &mut self.tier_contacts {
                group.clear();
            }
            for (c, &t) in self.contacts.iter().zip(&self.contact_tier) {
                self.tier_contacts[t as usize].push(*c);
            }
        }
        let dynamic = self
            .solver_bodies
            .iter()
            .filter(|b| b.inv_mass > 0.0)
            .count();
        for tier in 0..=top {
            self.tier_bodies.clear();
            let (bodies, body_tier) = (&self.solver_bodies, &self.body_tier);
            self.tier_bodies.extend(
                (0..body_tier.len() as u32).filter(|&i| {
                    body_tier[i as usize] == tier && bodies[i as usize].inv_mass > 0.0
                }),
            );
            if self.tier_bodies.is_empty() {
                continue;
            }
            let settings = if tier == 0 {
                self.settings.clone()
            } else {
                let scale = (1u32 << tier) as Real;
                Settings {
                    substeps: self.settings.substeps << tier,
                    relax_iterations: self.settings.relax_iterations * RELAX_SCALE[tier as usize],
                    contact_hertz: self.settings.contact_hertz * scale,
                    ..self.settings.clone()
                }
            };
            let contacts: &mut [Contact] = if split {
                &mut self.tier_contacts[tier as usize]
            } else if has_contacts[tier as usize] {
                &mut self.contacts
            } else {
                // Bodies touching nothing: only integrated.
                &mut []
            };
            solver::soft_step::solve(
                &mut self.solver_bodies,
                // Every moving body in this tier (a pyramid, a pile): the plain loop.
                if self.tier_bodies.len() == dynamic {
                    Moving::All
                } else {
                    Moving::Only(&self.tier_bodies)
                },
                contacts,
                &mut self.wide,
                &settings,
                dt,
                limits,
            );
        }
        if split {
            // Back into one list sorted by key, as the next step's matching expects.
            self.contacts.clear();
            for group in &self.tier_contacts {
                self.contacts.extend_from_slice(group);
            }
            self.contacts.sort_unstable_by_key(|c| c.key);
        }
    }

    /// Give every awake island a stiffness tier from its contacts: tier 1 where a contact's
    /// lasting force is `stiff_load_ratio` times the lighter body's weight or more (a tall
    /// stack or pyramid), or the two bodies' masses differ that much; tier 2 where the masses
    /// differ by `extreme_mass_ratio` or more.
    /// Fills `contact_tier` and `body_tier`; returns the highest tier (0: nothing needs more).
    fn assign_tiers(&mut self) -> u8 {
        let g = self.gravity.length();
        let g_ref = if g > 1e-3 { g } else { 9.81 };
        let (stiff, extreme) = (
            self.settings.stiff_load_ratio,
            self.settings.extreme_mass_ratio,
        );
        self.contact_tier.clear();
        let mut top = 0u8;
        for c in &self.contacts {
            let (ma, mb) = (
                self.solver_bodies[c.a as usize].inv_mass,
                self.solver_bodies[c.b as usize].inv_mass,
            );
            // Inverse masses: the lighter body has the larger one; static bodies have zero.
            let light_inv = ma.max(mb);
            let heavy_inv = ma.min(mb);
            let load = if light_inv > 0.0 {
                c.load * light_inv / g_ref
            } else {
                0.0
            };
            let masses = if heavy_inv > 0.0 {
                light_inv / heavy_inv
            } else {
                0.0
            };
            // A contact that has just closed carries a load nobody has measured yet: while a
            // stack settles its loads ramp up over about five steps, and at the base settings
            // it sinks 2.6 cm in them. Such a contact is solved as a loaded one until it is
            // old enough for its load to count.
            let unmeasured = c.age < NEW_CONTACT_STEPS
                && c.points[..c.count]
                    .iter()
                    .any(|p| p.separation <= self.settings.linear_slop);
            let tier = if masses >= extreme {
                2
            } else if load >= stiff || masses >= stiff || unmeasured {
                1
            } else {
                0
            };
            top = top.max(tier);
            self.contact_tier.push(tier);
        }
        if top == 0 {
            return 0;
        }
        // Islands: union-find over contacts between dynamic awake bodies; an island takes
        // the highest tier of its contacts, and so do all its contacts and bodies.
        let n = self.solver_bodies.len();
        self.island_parent.clear();
        self.island_parent.extend(0..n as u32);
        let moving = |i: u32, bodies: &[SolverBody]| bodies[i as usize].inv_mass > 0.0;
        for c in &self.contacts {
            if moving(c.a, &self.solver_bodies) && moving(c.b, &self.solver_bodies) {
                let (ra, rb) = (
                    find(&mut self.island_parent, c.a),
                    find(&mut self.island_parent, c.b),
                );
                if ra != rb {
                    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                    self.island_parent[hi as usize] = lo;
                }
            }
        }
        self.body_tier.clear();
        self.body_tier.resize(n, 0);
        for (k, c) in self.contacts.iter().enumerate() {
            let t = self.contact_tier[k];
            for i in [c.a, c.b] {
                if moving(i, &self.solver_bodies) {
                    let root = find(&mut self.island_parent, i) as usize;
                    self.body_tier[root] = self.body_tier[root].max(t);
                }
            }
        }
        for i in 0..n as u32 {
            let root = find(&mut self.island_parent, i) as usize;
            self.body_tier[i as usize] = self.body_tier[root];
        }
        for (k, c) in self.contacts.iter().enumerate() {
            let i = if moving(c.a, &self.solver_bodies) {
                c.a
            } else {
                c.b
            };
            self.contact_tier[k] = self.body_tier[i as usize];
        }
        top
    }

    /// Copy what the solver needs into the compact solver array (awake dynamic bodies only;
    /// everything else is fixed).
    fn load_solver_bodies(&mut self) {
        let g = self.gravity;
        self.solver_bodies.clear();
        self.solver_bodies
            .extend(self.slots.iter().map(|slot| match &slot.body {
                Some(b) if b.is_active() => SolverBody {
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
                // Infinite mass that moves: contacts see its velocity, nothing changes it.
                Some(b) if b.kinematic => SolverBody {
                    v: b.linear_velocity,
                    w: b.angular_velocity,
                    ..SolverBody::FIXED
                },
                _ => SolverBody::FIXED,
            }));
        // One more fixed body, last, for the empty lanes of the wide solver's bundles.
        self.solver_bodies.push(SolverBody::FIXED);
    }

    /// Write velocities and the step's motion back to the bodies; clear forces.
    fn store_solver_bodies(&mut self) {
        for (slot, sb) in self.slots.iter_mut().zip(&self.solver_bodies) {
            let Some(b) = slot.body.as_mut() else {
                continue;
            };
            b.force = Vec2::ZERO;
            b.torque = 0.0;
            if !b.is_active() {
                continue;
            }
            b.linear_velocity = sb.v;
            b.angular_velocity = sb.w;
            b.position += sb.dp;
            b.angle += sb.dtheta;
            b.rot = Rot::from_angle(b.angle);
        }
    }

    /// Kinematic bodies move by their own velocity over the step (they are fixed bodies to the
    /// solver, which only reads their velocity).
    fn move_kinematic(&mut self, dt: Real) {
        for b in self.slots.iter_mut().filter_map(|s| s.body.as_mut()) {
            if b.is_moving_kinematic() {
                b.position += dt * b.linear_velocity;
                b.angle += dt * b.angular_velocity;
                b.rot = Rot::from_angle(b.angle);
            }
        }
    }

    /// Islands and sleep: bodies joined by contacts form islands; an island whose every body
    /// has rested (|v| + |w| r below the threshold) for `time_to_sleep` falls asleep together.
    fn update_sleep(&mut self, dt: Real) {
        let threshold = self.settings.sleep_threshold;
        let n = self.slots.len();
        self.island_parent.clear();
        self.island_parent.extend(0..n as u32);
        for slot in self.slots.iter_mut() {
            if let Some(b) = slot.body.as_mut().filter(|b| b.is_active()) {
                let speed = b.linear_velocity.length()
                    + b.angular_velocity.abs() * b.shape.bounding_radius();
                b.sleep_time = if speed > threshold {
                    0.0
                } else {
                    b.sleep_time + dt
                };
            }
        }
        // Union-find over contacts between awake dynamic bodies (static bodies join nothing).
        let active =
            |slots: &[Slot], i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        for c in &self.contacts {
            if active(&self.slots, c.a) && active(&self.slots, c.b) {
                let (ra, rb) = (
                    find(&mut self.island_parent, c.a),
                    find(&mut self.island_parent, c.b),
                );
                if ra != rb {
                    // Deterministic: the lower root wins.
                    let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                    self.island_parent[hi as usize] = lo;
                }
            }
        }
        // The island rests as long as its most restless body.
        self.island_rest.clear();
        self.island_rest.resize(n, Real::INFINITY);
        for i in 0..n as u32 {
            if let Some(b) = self.slots[i as usize]
                .body
                .as_ref()
                .filter(|b| b.is_active())
            {
                let root = find(&mut self.island_parent, i) as usize;
                self.island_rest[root] = self.island_rest[root].min(b.sleep_time);
            }
        }
        self.changed.clear();
        for i in 0..n as u32 {
            let root = find(&mut self.island_parent, i);
            if let Some(b) = self.slots[i as usize]
                .body
                .as_mut()
                .filter(|b| b.is_active())
            {
                if self.island_rest[root as usize] >= self.settings.time_to_sleep {
                    b.awake = false;
                    b.linear_velocity = Vec2::ZERO;
                    b.angular_velocity = 0.0;
                    b.sleep_island = root;
                    self.changed.push(i);
                }
            }
        }
        if self.changed.is_empty() {
            return;
        }
        self.broad_phase.set_passive(&self.changed, true);
        // Contacts with no awake body left are kept aside, unsolved, for when the island wakes.
        let slots = &self.slots;
        let mut kept = 0;
        for k in 0..self.contacts.len() {
            let c = self.contacts[k];
            if !active(slots, c.a) && !active(slots, c.b) {
                // Not kept with a kinematic body: it finds the sleeper again when it moves.
                let kinematic =
                    |i: u32| slots[i as usize].body.as_ref().is_some_and(|b| b.kinematic);
                if !kinematic(c.a) && !kinematic(c.b) {
                    self.sleeping_contacts.push(c);
                }
            } else {
                self.contacts[kept] = c;
                kept += 1;
            }
        }
        self.contacts.truncate(kept);
    }

    /// Wake the islands of the bodies in the wake queue: their bodies rejoin the active list
    /// and their contacts (with the impulses they slept with) rejoin the solver.
    fn wake_queued(&mut self) {
        if self.wake_queue.is_empty() {
            return;
        }
        self.changed.clear();
        for k in 0..self.wake_queue.len() {
            let i = self.wake_queue[k] as usize;
            let Some(island) = self.slots[i]
                .body
                .as_ref()
                .filter(|b| !b.awake)
                .map(|b| b.sleep_island)
            else {
                continue;
            };
            for (j, slot) in self.slots.iter_mut().enumerate() {
                if let Some(b) = slot
                    .body
                    .as_mut()
                    .filter(|b| !b.awake && b.sleep_island == island)
                {
                    b.awake = true;
                    b.sleep_time = 0.0;
                    self.changed.push(j as u32);
                }
            }
        }
        self.wake_queue.clear();
        if self.changed.is_empty() {
            return;
        }
        self.broad_phase.set_passive(&self.changed, false);
        let slots = &self.slots;
        let active = |i: u32| slots[i as usize].body.as_ref().is_some_and(Body::is_active);
        let before = self.contacts.len();
        let mut k = 0;
        while k < self.sleeping_contacts.len() {
            let c = self.sleeping_contacts[k];
            if active(c.a) || active(c.b) {
                self.contacts.push(c);
                self.sleeping_contacts.swap_remove(k);
            } else {
                k += 1;
            }
        }
        if self.contacts.len() != before {
            self.contacts.sort_unstable_by_key(|c| c.key);
        }
    }

    /// Broad phase, then narrow phase, then match points with last step's for warm starting.
    ///
    /// `speculative` > 0 also keeps points that are up to that far apart, plus however far
    /// the pair can close in `dt` (so fast bodies meet the surface instead of tunnelling).
    /// A sleeping body that an awake one is about to touch wakes with its island.
    fn find_contacts(&mut self, dt: Real, speculative: Real) {
        // Proxies: each body's box grown by half the speculative distance plus how far it can
        // travel this step.
        let g = self.gravity;
        self.proxies.clear();
        self.proxies
            .extend(self.slots.iter().map(|slot| match &slot.body {
                Some(b) => {
                    let reach = if b.is_active() || b.kinematic {
                        travel(b, g, dt)
                    } else {
                        0.0
                    };
                    Proxy {
                        aabb: b
                            .shape
                            .aabb(b.transform())
                            .inflated(0.5 * speculative + reach),
                    }
                }
                None => Proxy {
                    aabb: super::shape::Aabb {
                        min: Vec2::ZERO,
                        max: Vec2::ZERO,
                    },
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
            if a.inv_mass == 0.0 && b.inv_mass == 0.0 {
                // A kinematic body meets static and kinematic ones without a contact.
                continue;
            }
            let reach = closing_reach(a, b, g, dt);
            let manifold = collide(
                &a.shape,
                a.transform(),
                &b.shape,
                b.transform(),
                speculative + reach,
            );
            if manifold.count == 0 {
                continue;
            }
            // Wake a sleeping body only if the gap can close this step. A speculative point
            // farther out than that treats the sleeper as fixed; waking on it made a body
            // resting 2 cm from an awake neighbour sleep and wake every 0.5 s forever.
            let nearest = manifold
                .points()
                .iter()
                .map(|p| p.separation)
                .fold(Real::INFINITY, Real::min);
            // A kinematic body at rest wakes nothing (it is ground until it moves).
            let resting_kinematic = |x: &Body| x.kinematic && !x.is_moving_kinematic();
            let mut woken = false;
            if nearest <= reach + self.settings.linear_slop
                && !resting_kinematic(a)
                && !resting_kinematic(b)
            {
                for (i, body) in [(ia, a), (ib, b)] {
                    if !body.awake {
                        self.wake_queue.push(i);
                        woken = true;
                    }
                }
            }
            if !(a.is_active() || b.is_active() || woken) {
                // A sleeper beside a kinematic body at rest: nothing to solve.
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
                touches_static: a.inv_mass == 0.0 || b.inv_mass == 0.0,
                points: [ContactPoint::default(); 2],
                count: manifold.count,
                softness: Softness::RIGID,
                hertz: previous.map_or(0.0, |c| c.hertz),
                load: previous.map_or(0.0, |c| c.load),
                force: previous.map_or(0.0, |c| c.force),
                age: previous.map_or(0, |c| c.age.saturating_add(1)),
                block: None,
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
                    cp.approach_velocity = prev.approach_velocity;
                }
            }
            self.contacts.push(contact);
        }
        self.wake_queued();
    }
}

/// Adaptive stiffness: the base tier and the two above it (2 and 4 times the work).
const TIERS: usize = 3;

/// Adaptive stiffness: relax passes per tier, as multiples of `Settings::relax_iterations`.
/// Tier 2 gets 8 (not 4) times: with 4, the 4 m box of 1000 kg on two 1 kg boxes overlapped
/// 9.8 mm (bound 10) and slid 2.3 cm; with 8, 2.5 mm and 0.04 mm. Its islands are small.
const RELAX_SCALE: [u32; TIERS] = [1, 2, 8];

/// Adaptive stiffness: how many steps a new touching contact is solved as a loaded one
/// before its measured load decides (`World::assign_tiers`).
const NEW_CONTACT_STEPS: u8 = 8;

/// Union-find root of `i`, halving paths as it goes.
#[inline]
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = p;
    }
    i
}

/// How far two bodies can close on each other in `dt` (m): their relative linear motion, each
/// one's rotational reach, and what their relative acceleration adds. Gravity moves both alike
/// and cancels, so boxes falling side by side get no speculative contacts with each other.
#[inline]
fn closing_reach(a: &Body, b: &Body, g: Vec2, dt: Real) -> Real {
    let motion = |x: &Body| {
        if x.kinematic {
            (
                x.linear_velocity,
                x.angular_velocity.abs() * x.shape.bounding_radius(),
                Vec2::ZERO,
            )
        } else if x.is_active() {
            (
                x.linear_velocity,
                x.angular_velocity.abs() * x.shape.bounding_radius(),
                g + x.inv_mass * x.force,
            )
        } else {
            (Vec2::ZERO, 0.0, Vec2::ZERO)
        }
    };
    let (va, wa, aa) = motion(a);
    let (vb, wb, ab) = motion(b);
    dt * ((vb - va).length() + wa + wb) + dt * dt * (ab - aa).length()
}

/// How far any point of body `b` can move in `dt` (m): linear plus rotational reach, plus
/// what gravity and applied force add within the step.
#[inline]
fn travel(b: &Body, g: Vec2, dt: Real) -> Real {
    let accel = g + b.inv_mass * b.force;
    dt * (b.linear_velocity.length() + b.angular_velocity.abs() * b.shape.bounding_radius())
        + dt * dt * accel.length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{vec2, Shape};

    /// A 12 m plank on the ground with 40 small boxes resting on it: the plank has more
    /// contacts than the wide solver has colours, so some of them overflow to the scalar code.
    fn crowded_plank() -> World {
        let settings = Settings {
            enable_sleep: false,
            ..Settings::default()
        };
        let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
        w.add_body(&BodyDef::fixed(Shape::rect(40.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        w.add_body(&BodyDef::dynamic(Shape::rect(12.0, 0.5), vec2(0.0, 0.25)))
            .unwrap();
        for i in 0..40 {
            let x = -5.85 + 0.3 * i as Real;
            w.add_body(&BodyDef::dynamic(Shape::rect(0.25, 0.25), vec2(x, 0.625)))
                .unwrap();
        }
        w
    }

    /// The overflow path (contacts the colouring could not place, solved one by one after the
    /// bundles) and the four-lane bundles solve the same physics: stepping the crowded plank
    /// with the usual 32 colours (some contacts overflow) and with none (every contact takes
    /// the scalar path) ends with every body within 0.1 mm. The two differ only in the order
    /// the contacts are solved in, which moves a resting scene by round-off.
    #[test]
    fn overflow_contacts_solve_like_the_wide_bundles() {
        let mut wide = crowded_plank();
        let mut scalar = crowded_plank();
        scalar.wide.colours = Some(0);
        let mut overflowed = 0;
        for _ in 0..120 {
            wide.step(1.0 / 60.0).unwrap();
            scalar.step(1.0 / 60.0).unwrap();
            overflowed = overflowed.max(wide.wide.overflow.len());
            assert_eq!(scalar.wide.overflow.len(), scalar.contacts.len());
        }
        assert!(
            overflowed > 0,
            "the plank's 40 contacts must exceed the colours"
        );
        for (a, b) in wide.bodies().zip(scalar.bodies()) {
            let d = (a.position() - b.position()).length();
            assert!(d < 1e-4, "body {} differs by {d} m", a.id());
            assert!((a.angle() - b.angle()).abs() < 1e-3);
        }
    }
}
