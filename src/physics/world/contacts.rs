//! Finding contacts: the broad phase's candidate pairs, the narrow phase's manifolds, and
//! last step's impulses carried over to the points that persist.

use super::*;

impl World {
    /// Broad phase, then narrow phase, then match points with last step's for warm starting.
    ///
    /// `speculative` > 0 also keeps points that are up to that far apart, plus however far
    /// the pair can close in `dt` (so fast bodies meet the surface instead of tunnelling).
    /// A sleeping body that an awake one is about to touch wakes with its island.
    pub(super) fn find_contacts(&mut self, dt: Real, speculative: Real) {
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
                    aabb: crate::physics::shape::Aabb {
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
                creep: 0.0,
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
                    cp.slip = prev.slip;
                    cp.stuck = prev.stuck;
                }
            }
            self.contacts.push(contact);
        }
        self.wake_queued();
    }
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
