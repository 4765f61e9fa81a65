//! Finding contacts: the broad phase's candidate pairs, the narrow phase's manifolds, and
//! last step's impulses carried over to the points that persist.

use super::islands::TierInput;
use super::*;
use crate::physics::collide::{Manifold, ManifoldPoint};
use crate::physics::math::Transform;

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

        // This step's contacts are written over last step's, in place, while they come in the
        // same order: in a scene at rest every pair keeps its contact and nothing is copied
        // (copying each recycled contact to a new array was 4-5 % of a settled pyramid's
        // step). At the first contact that is new or gone, the ones written so far are copied
        // to a fresh array, and the rest is read from last step's (`previous`).
        let mut in_place = true;
        // In place: contacts[..written] are this step's, the rest last step's.
        let mut written = 0usize;
        #[cfg(test)]
        if self.copy_contacts {
            stop_in_place(&mut self.contacts, &mut self.previous, 0);
            in_place = false;
        }
        self.tier_inputs.clear();
        let mut old = 0usize;
        let fm = self.settings.friction_mixing;
        let rm = self.settings.restitution_mixing;
        let recycling = self.settings.contact_recycling;
        let slop = self.settings.linear_slop;
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
            // Both lists are sorted by key: advance the cursor in the old one. In place, a
            // contact passed over is gone.
            if in_place && self.contacts.get(written).is_some_and(|c| c.key < key) {
                stop_in_place(&mut self.contacts, &mut self.previous, written);
                (in_place, old) = (false, written);
            }
            if !in_place {
                while old < self.previous.len() && self.previous[old].key < key {
                    old += 1;
                }
            }
            let last = if in_place {
                &self.contacts[written..]
            } else {
                &self.previous[old..]
            };
            let previous = last.first().filter(|c| c.key == key);
            // Recycled only between awake dynamic bodies and bodies that do not move (static,
            // or kinematic at rest): nothing to wake, no motion the solver does not see.
            let steady =
                |x: &Body| x.is_active() || (x.inv_mass == 0.0 && !x.is_moving_kinematic());
            let (xf_a, xf_b) = (a.transform(), b.transform());
            let recycled = previous
                .filter(|_| recycling && steady(a) && steady(b))
                .and_then(|c| {
                    let size = a.bounding_radius.min(b.bounding_radius);
                    let max_drift = RECYCLE_DRIFT.min(RECYCLE_SIZE * size);
                    recycle(c, xf_a, xf_b, max_drift)
                });
            let manifold = match recycled {
                Some(manifold) => manifold,
                None => {
                    let reach = closing_reach(a, b, g, dt);
                    let manifold = collide(&a.shape, xf_a, &b.shape, xf_b, speculative + reach);
                    if manifold.count == 0 {
                        continue;
                    }
                    // Wake a sleeping body only if the gap can close this step. A speculative
                    // point farther out than that treats the sleeper as fixed; waking on it made
                    // a body resting 2 cm from an awake neighbour sleep and wake every 0.5 s
                    // forever.
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
                    manifold
                }
            };
            if let (Some(manifold), Some(base)) = (recycled, previous) {
                // The same points as last step: the contact carries over whole (impulses,
                // load, the recycling frame) and only its geometry moves.
                // Everything else in it is recomputed by the solver's prepare.
                let contact = if in_place {
                    written += 1;
                    &mut self.contacts[written - 1]
                } else {
                    self.contacts.push(*base);
                    self.contacts.last_mut().expect("just pushed")
                };
                let age = contact.age;
                contact.normal = manifold.normal;
                contact.friction = fm.mix(a.friction, b.friction);
                contact.restitution = rm.mix(a.restitution, b.restitution);
                contact.age = age.saturating_add(1);
                for (cp, mp) in contact.points.iter_mut().zip(manifold.points()) {
                    cp.point = mp.point;
                    cp.separation = mp.separation;
                    cp.anchor_a = mp.point - a.position;
                    cp.anchor_b = mp.point - b.position;
                }
                self.tier_inputs.push(TierInput::of(contact, slop));
                continue;
            }
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
                hertz: previous.map_or(0.0, |c| c.hertz),
                load: previous.map_or(0.0, |c| c.load),
                force: previous.map_or(0.0, |c| c.force),
                age: previous.map_or(0, |c| c.age.saturating_add(1)),
                local_normal: xf_a.q.inv_rotate(manifold.normal),
                base_rotation: relative_rotation(xf_a.q, xf_b.q),
            };
            for (cp, mp) in contact.points.iter_mut().zip(manifold.points()) {
                cp.id = mp.id;
                cp.point = mp.point;
                cp.separation = mp.separation;
                cp.anchor_a = mp.point - a.position;
                cp.anchor_b = mp.point - b.position;
                cp.local_a = xf_a.apply_inv(mp.point);
                cp.local_b = xf_b.apply_inv(mp.point);
                cp.base_separation = mp.separation;
                if let Some(prev) =
                    previous.and_then(|c| c.points[..c.count].iter().find(|p| p.id == mp.id))
                {
                    cp.normal_impulse = prev.normal_impulse;
                    cp.tangent_impulse = prev.tangent_impulse;
                    cp.approach_velocity = prev.approach_velocity;
                }
            }
            self.tier_inputs.push(TierInput::of(&contact, slop));
            if in_place && previous.is_none() && written < self.contacts.len() {
                // A new contact before last step's others: from here, the old way.
                stop_in_place(&mut self.contacts, &mut self.previous, written);
                (in_place, old) = (false, written);
            }
            if in_place {
                // Over its own last step's contact, or appended after them all.
                if written < self.contacts.len() {
                    self.contacts[written] = contact;
                } else {
                    self.contacts.push(contact);
                }
                written += 1;
            } else {
                self.contacts.push(contact);
            }
        }
        if in_place {
            // Last step's contacts after the last one kept are gone.
            self.contacts.truncate(written);
        }
        self.wake_queued();
    }
}

/// Stop writing this step's contacts in place: last step's become `previous` (the first
/// `written` of them already overwritten by this step's), and this step's so far are copied
/// to a fresh `contacts`.
fn stop_in_place(contacts: &mut Vec<Contact>, previous: &mut Vec<Contact>, written: usize) {
    std::mem::swap(contacts, previous);
    contacts.clear();
    contacts.extend_from_slice(&previous[..written]);
}

/// Contact recycling: how far (m) a point may drift from where it was computed before the
/// pair is collided afresh (`Settings::contact_recycling`)...
const RECYCLE_DRIFT: Real = 1.0e-3;
/// ...and at most this fraction of the smaller body's bounding radius (small bodies).
const RECYCLE_SIZE: Real = 0.005;
/// Contact recycling: the largest relative turn of the pair (sine of the angle) before the
/// pair is collided afresh.
const RECYCLE_TURN: Real = 2.0e-3;

/// B's rotation relative to A's: q_A^T q_B.
#[inline]
fn relative_rotation(qa: Rot, qb: Rot) -> Rot {
    Rot {
        c: qa.c * qb.c + qa.s * qb.s,
        s: qa.c * qb.s - qa.s * qb.c,
    }
}

/// The manifold of `base` at the bodies' new transforms, if they have hardly moved against
/// each other since it was computed (no point drifted `max_drift` metres, the pair turned less
/// than [`RECYCLE_TURN`]); None when the pair must be collided afresh.
///
/// Each point is fixed in both bodies (`local_a`, `local_b`, one world point when computed):
/// it lies halfway between its two material points now, the normal turns with A, and the
/// separation grows by how far the points have moved apart along the normal. For a vertex
/// of one body on a face of the other that is exact; only the clipping, which would slide a
/// clipped point along the face, is not redone.
///
/// Inlined: called, it handed its manifold back through memory, and the caller's reads of it
/// waited on the stores (a tenth of `find_contacts`' own time on a settled pile).
#[inline(always)]
fn recycle(base: &Contact, xf_a: Transform, xf_b: Transform, max_drift: Real) -> Option<Manifold> {
    let turn = relative_rotation(xf_a.q, xf_b.q);
    let q0 = base.base_rotation;
    if (q0.c * turn.s - q0.s * turn.c).abs() > RECYCLE_TURN {
        return None;
    }
    let normal = xf_a.q.rotate(base.local_normal);
    let mut manifold = Manifold::EMPTY;
    manifold.normal = normal;
    manifold.count = base.count;
    for (mp, p) in manifold.points.iter_mut().zip(&base.points[..base.count]) {
        let (pa, pb) = (xf_a.apply(p.local_a), xf_b.apply(p.local_b));
        let drift = pb - pa;
        if drift.length_squared() > max_drift * max_drift {
            return None;
        }
        *mp = ManifoldPoint {
            point: 0.5 * (pa + pb),
            separation: p.base_separation + drift.dot(normal),
            id: p.id,
        };
    }
    Some(manifold)
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
                x.angular_velocity.abs() * x.bounding_radius,
                Vec2::ZERO,
            )
        } else if x.is_active() {
            (
                x.linear_velocity,
                x.angular_velocity.abs() * x.bounding_radius,
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
    dt * (b.linear_velocity.length() + b.angular_velocity.abs() * b.bounding_radius)
        + dt * dt * accel.length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{vec2, Shape};

    /// A 1 m box resting on a fixed floor (top at y = 0), sleep off, after `steps` steps.
    fn box_on_floor(recycling: bool, steps: usize) -> World {
        let settings = Settings {
            enable_sleep: false,
            contact_recycling: recycling,
            ..Settings::default()
        };
        let mut w = World::new(settings, vec2(0.0, -10.0)).unwrap();
        w.add_body(&BodyDef::fixed(Shape::rect(20.0, 1.0), vec2(0.0, -0.5)))
            .unwrap();
        w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.3, 0.5)))
            .unwrap();
        for _ in 0..steps {
            w.step(1.0 / 60.0).unwrap();
        }
        w
    }

    /// The floor's and the box's transforms, and the box's shape.
    fn poses(w: &World) -> (Transform, Transform, Shape) {
        let body = |i: usize| w.slots[i].body.as_ref().unwrap();
        (
            body(0).transform(),
            body(1).transform(),
            body(1).shape.clone(),
        )
    }

    /// The box moved by `d` (m) and turned by `turn` (rad) about its centre.
    fn moved(xf: Transform, d: Vec2, turn: Real) -> Transform {
        Transform {
            p: xf.p + d,
            q: Rot::from_angle(xf.q.angle() + turn),
        }
    }

    /// A box that moves 0.4 mm sideways, 0.3 mm down and turns 1 mrad (its corners drift up
    /// to 1.2 mm, so the test allows 2) keeps the same two
    /// corner points on the floor's face: the recycled manifold has the fresh one's normal,
    /// ids and separations (to 1 um: f32 round-off on metre coordinates is 0.1 um, and the
    /// anchored points are the box's own corners, so nothing else differs), and its points
    /// lie within the 0.4 mm the corners slid.
    #[test]
    fn a_recycled_manifold_is_the_fresh_one_for_a_small_motion() {
        let w = box_on_floor(true, 30);
        let contact = w.contacts[0];
        let (xf_floor, xf_box, shape) = poses(&w);
        let xf = moved(xf_box, vec2(4.0e-4, -3.0e-4), 1.0e-3);
        let recycled = recycle(&contact, xf_floor, xf, 2.0e-3).expect("a small motion recycles");
        let floor = w.slots[0].body.as_ref().unwrap().shape.clone();
        let fresh = collide(&floor, xf_floor, &shape, xf, 0.02);
        assert_eq!((recycled.count, fresh.count), (2, 2));
        assert!((recycled.normal - fresh.normal).length() < 1e-6);
        for p in fresh.points() {
            let q = recycled
                .points()
                .iter()
                .find(|q| q.id == p.id)
                .expect("the same features");
            assert!(
                (q.separation - p.separation).abs() < 1e-6,
                "separation {} against {}",
                q.separation,
                p.separation
            );
            assert!((q.point - p.point).length() < 5e-4);
        }
    }

    /// Past 1 mm of drift at a point, or 2 mrad of turn, the pair is collided afresh.
    #[test]
    fn recycling_stops_when_a_pair_drifts_or_turns() {
        let w = box_on_floor(true, 30);
        let contact = w.contacts[0];
        let (xf_floor, xf_box, _) = poses(&w);
        let drifted = moved(xf_box, vec2(1.2e-3, 0.0), 0.0);
        assert!(recycle(&contact, xf_floor, drifted, 1.0e-3).is_none());
        let turned = moved(xf_box, Vec2::ZERO, 2.5e-3);
        assert!(recycle(&contact, xf_floor, turned, 1.0).is_none());
        let still = moved(xf_box, vec2(1.0e-4, 0.0), 1.0e-4);
        assert!(recycle(&contact, xf_floor, still, 1.0e-3).is_some());
    }

    /// Recycling changes nothing a user can see in a resting stack: ten boxes stepped 5 s
    /// with recycling and without end with every centre within 0.05 mm (the recycled
    /// separations are exact for corners on faces; what differs is round-off, which the
    /// springs damp), while the recycled world really reused its manifolds (a point's
    /// separation moved on from the one it was computed with).
    #[test]
    fn recycling_leaves_a_resting_stack_where_fresh_manifolds_put_it() {
        let stack = |recycling: bool| {
            let mut w = box_on_floor(recycling, 0);
            for i in 1..10 {
                let y = 0.5 + i as Real;
                w.add_body(&BodyDef::dynamic(Shape::rect(1.0, 1.0), vec2(0.3, y)))
                    .unwrap();
            }
            for _ in 0..300 {
                w.step(1.0 / 60.0).unwrap();
            }
            w
        };
        let (on, off) = (stack(true), stack(false));
        for (a, b) in on.bodies().zip(off.bodies()) {
            let d = (a.position() - b.position()).length();
            assert!(d < 5e-5, "body {} differs by {d} m", a.id());
        }
        let reused = on
            .contacts
            .iter()
            .flat_map(|c| c.points[..c.count].iter())
            .filter(|p| p.separation != p.base_separation)
            .count();
        assert!(reused > 0, "no contact was recycled");
        let fresh = off
            .contacts
            .iter()
            .flat_map(|c| c.points[..c.count].iter())
            .all(|p| p.separation == p.base_separation);
        assert!(fresh, "without recycling every manifold is fresh");
    }
}
