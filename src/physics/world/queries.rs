//! The World's queries: the query tree kept up to date lazily, and the [`Query`] view that
//! answers rays, swept shapes, points, boxes and shapes from it.

use super::World;
use crate::physics::body::Body;
use crate::physics::error::{finite_vec, PhysicsError};
use crate::physics::math::{Real, Transform, Vec2};
use crate::physics::query::geometry::Rounded;
use crate::physics::query::tree::Tree;
use crate::physics::query::{self, QueryFilter, RayHit, ShapeRef};
use crate::physics::shape::{Aabb, Shape};

/// How far a leaf's box reaches past its body's (m): a body may move this much before its
/// leaf is moved (Box2D's `B2_AABB_MARGIN`).
const MARGIN: Real = 0.1;

/// No leaf.
const NO_LEAF: u32 = u32::MAX;

/// The query tree and what it was last brought up to date with.
#[derive(Clone, Debug, Default)]
pub(super) struct QueryIndex {
    tree: Tree,
    /// Each slot's leaf (or [`NO_LEAF`]) and the generation it holds.
    leaves: Vec<(u32, u32)>,
    /// The step the tree was last brought up to date at; none: never, or bodies came or went
    /// since.
    pub synced_at: Option<u64>,
    /// Scratch: the bodies to put (back) in, kept so that a steady sync allocates nothing.
    pending: Vec<(u32, Aabb)>,
}

impl QueryIndex {
    /// Bodies came or went: the next query looks at every slot.
    pub fn touch(&mut self) {
        self.synced_at = None;
    }
}

impl World {
    /// The World's queries, with the query tree brought up to date first: built at the first
    /// query, then at each later query after a step only the bodies that left their leaf's
    /// box (grown by 0.1 m) are moved in it. Take one view for many queries at a step.
    pub fn query(&mut self) -> Query<'_> {
        if self.queries.synced_at != Some(self.steps) {
            self.sync_queries();
        }
        Query { world: self }
    }

    /// The query tree, up to date (after [`World::sync_queries`]).
    pub(super) fn query_tree(&self) -> &Tree {
        &self.queries.tree
    }

    /// Bring every slot's leaf up to date with its body: leaves of bodies gone come out, bodies
    /// new or outside their leaf's box go (back) in, one by one, or all at once by a fresh
    /// build when they are more than half the bodies (the first query's case).
    pub(super) fn sync_queries(&mut self) {
        let World {
            bodies, queries, ..
        } = self;
        let QueryIndex {
            tree,
            leaves,
            pending,
            ..
        } = queries;
        pending.clear();
        leaves.resize(bodies.slots.len(), (NO_LEAF, 0));
        for (slot, (entry, s)) in leaves.iter_mut().zip(&bodies.slots).enumerate() {
            let (leaf, held) = *entry;
            match &s.body {
                Some(b) if leaf != NO_LEAF && held == s.generation => {
                    let aabb = b.aabb();
                    if !tree.leaf_box(leaf).contains(&aabb) {
                        tree.remove(leaf);
                        *entry = (NO_LEAF, 0);
                        pending.push((slot as u32, aabb.inflated(MARGIN)));
                    }
                }
                live => {
                    if leaf != NO_LEAF {
                        tree.remove(leaf);
                        *entry = (NO_LEAF, 0);
                    }
                    if let Some(b) = live {
                        pending.push((slot as u32, b.aabb().inflated(MARGIN)));
                    }
                }
            }
        }
        if 2 * pending.len() > bodies.count {
            let all: Vec<(u32, Aabb)> = bodies
                .slots
                .iter()
                .enumerate()
                .filter_map(|(i, s)| Some((i as u32, s.body.as_ref()?.aabb().inflated(MARGIN))))
                .collect();
            let built;
            (*tree, built) = Tree::build(&all);
            pending.clear();
            for (&(slot, _), leaf) in all.iter().zip(built) {
                leaves[slot as usize] = (leaf, bodies.slots[slot as usize].generation);
            }
        }
        for &(slot, aabb) in pending.iter() {
            leaves[slot as usize] = (
                tree.insert(slot, aabb),
                bodies.slots[slot as usize].generation,
            );
        }
        leaves.truncate(bodies.slots.len());
        queries.synced_at = Some(self.steps);
    }

    pub(super) fn body_in_slot(&self, slot: u32) -> Option<&Body> {
        self.bodies.slots.get(slot as usize)?.body.as_ref()
    }
}

/// The World's queries at one moment (between steps). Results come in a fixed order: hits by
/// fraction, then body and shape; overlaps by body and shape.
pub struct Query<'a> {
    world: &'a World,
}

/// Refuse a ray whose origin or translation is not finite, naming the field.
fn check_ray(origin: Vec2, translation: Vec2) -> Result<(), PhysicsError> {
    check(["origin.x", "origin.y"], origin)?;
    check(["translation.x", "translation.y"], translation)?;
    Ok(())
}

/// Refuse a query input that is not finite, naming it.
fn check(field: [&'static str; 2], v: Vec2) -> Result<Vec2, PhysicsError> {
    finite_vec(field, v)
}

impl<'a> Query<'a> {
    /// The World queried (a query view borrows it whole; read it through here meanwhile).
    pub fn world(&self) -> &'a World {
        self.world
    }

    /// The closest shape `filter` sees that the ray from `origin` along `translation` (m)
    /// meets; shapes the ray starts inside are not met. Each hit shortens the ray, so the cost
    /// grows with the shapes near it.
    pub fn ray_closest(
        &self,
        origin: Vec2,
        translation: Vec2,
        filter: QueryFilter,
    ) -> Result<Option<RayHit>, PhysicsError> {
        check_ray(origin, translation)?;
        let mut best: Option<RayHit> = None;
        self.world
            .queries
            .tree
            .ray(origin, translation, 1.0, |slot, max| {
                let Some(body) = self.world.body_in_slot(slot) else {
                    return max;
                };
                match query::ray_body(body, (origin, translation, max), &filter) {
                    Some((shape, hit)) if better(&best, hit.fraction, body, shape) => {
                        best = Some(ray_hit(
                            body,
                            shape,
                            origin + hit.fraction * translation,
                            hit,
                        ));
                        hit.fraction
                    }
                    _ => max,
                }
            });
        Ok(best)
    }

    /// Every shape `filter` sees that the ray meets, closest first, at most `limit` of them
    /// (the closest); each shape once, where the ray first meets it.
    pub fn ray_all(
        &self,
        origin: Vec2,
        translation: Vec2,
        filter: QueryFilter,
        limit: usize,
    ) -> Result<Vec<RayHit>, PhysicsError> {
        check_ray(origin, translation)?;
        let mut hits = Vec::new();
        self.world
            .queries
            .tree
            .ray(origin, translation, 1.0, |slot, max| {
                let Some(body) = self.world.body_in_slot(slot) else {
                    return max;
                };
                for (i, shape, xf, f) in query::shapes_of(body) {
                    let probe = query::rounded(shape, xf);
                    let hit = filter
                        .sees(&f)
                        .then(|| query::geometry::ray_rounded(&probe, origin, translation, 1.0))
                        .flatten();
                    if let Some(hit) = hit {
                        hits.push(ray_hit(body, i, origin + hit.fraction * translation, hit));
                    }
                }
                max
            });
        hits.sort_by(|a, b| {
            a.fraction
                .total_cmp(&b.fraction)
                .then(a.shape.cmp(&b.shape))
        });
        hits.truncate(limit);
        Ok(hits)
    }

    /// Where `shape`, placed at `pose` and moved by `translation` (m) without turning, first
    /// meets a shape `filter` sees: fraction 0 (with no normal) when it starts overlapping one.
    pub fn cast_shape(
        &self,
        shape: &Shape,
        pose: Transform,
        translation: Vec2,
        filter: QueryFilter,
    ) -> Result<Option<RayHit>, PhysicsError> {
        shape.validate()?;
        check(["pose.x", "pose.y"], pose.p)?;
        check(["translation.x", "translation.y"], translation)?;
        let probe = query::rounded(shape, pose);
        let start = shape.aabb(pose);
        let end = shape.aabb(Transform {
            p: pose.p + translation,
            q: pose.q,
        });
        let swept = Aabb {
            min: start.min.min(end.min),
            max: start.max.max(end.max),
        };
        let mut best: Option<RayHit> = None;
        self.world.queries.tree.query(&swept, |slot| {
            let Some(body) = self.world.body_in_slot(slot) else {
                return true;
            };
            let max = best.map_or(1.0, |b| b.fraction);
            if let Some(hit) = query::cast_body(body, &probe, translation, max, &filter) {
                if better(&best, hit.fraction, body, hit.shape.shape) {
                    best = Some(hit);
                }
            }
            true
        });
        Ok(best)
    }

    /// Every shape `filter` sees that holds `point` (m).
    pub fn at_point(
        &self,
        point: Vec2,
        filter: QueryFilter,
    ) -> Result<Vec<ShapeRef>, PhysicsError> {
        check(["point.x", "point.y"], point)?;
        let probe = Rounded::new([point], 0.0);
        Ok(self.overlapping_probe(
            &probe,
            Aabb {
                min: point,
                max: point,
            },
            &filter,
        ))
    }

    /// Every shape `filter` sees that overlaps the box `aabb` (m; touching is not enough).
    pub fn in_box(&self, aabb: Aabb, filter: QueryFilter) -> Result<Vec<ShapeRef>, PhysicsError> {
        check(["min.x", "min.y"], aabb.min)?;
        check(["max.x", "max.y"], aabb.max)?;
        for (axis, lower_field, upper_field) in [(0, "min.x", "max.x"), (1, "min.y", "max.y")] {
            let (lower, upper) = (aabb.min[axis], aabb.max[axis]);
            if lower > upper {
                return Err(PhysicsError::Reversed {
                    lower_field,
                    lower,
                    upper_field,
                    upper,
                });
            }
        }
        let (lo, hi) = (aabb.min, aabb.max);
        let probe =
            query::geometry::hull(&mut [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)]);
        Ok(self.overlapping_probe(&probe, aabb, &filter))
    }

    /// Every shape `filter` sees that `shape` at `pose` overlaps.
    pub fn overlapping(
        &self,
        shape: &Shape,
        pose: Transform,
        filter: QueryFilter,
    ) -> Result<Vec<ShapeRef>, PhysicsError> {
        shape.validate()?;
        check(["pose.x", "pose.y"], pose.p)?;
        let probe = query::rounded(shape, pose);
        Ok(self.overlapping_probe(&probe, shape.aabb(pose), &filter))
    }

    fn overlapping_probe(
        &self,
        probe: &Rounded,
        aabb: Aabb,
        filter: &QueryFilter,
    ) -> Vec<ShapeRef> {
        let mut out = Vec::new();
        self.world.queries.tree.query(&aabb, |slot| {
            if let Some(body) = self.world.body_in_slot(slot) {
                let id = body.id();
                out.extend(
                    query::overlaps_body(body, probe, |f| filter.sees(f))
                        .map(|shape| ShapeRef { body: id, shape }),
                );
            }
            true
        });
        out.sort_unstable();
        out
    }
}

/// Whether a hit at `fraction` on `body`'s shape `shape` comes before `best` (ties go to the
/// lower body and shape, so the answer does not depend on the tree's order).
fn better(best: &Option<RayHit>, fraction: Real, body: &Body, shape: u32) -> bool {
    let here = ShapeRef {
        body: body.id(),
        shape,
    };
    best.map_or(true, |b| {
        fraction < b.fraction || (fraction == b.fraction && here < b.shape)
    })
}

fn ray_hit(body: &Body, shape: u32, point: Vec2, hit: query::geometry::Crossing) -> RayHit {
    RayHit {
        shape: ShapeRef {
            body: body.id(),
            shape,
        },
        point,
        normal: hit.normal,
        fraction: hit.fraction,
    }
}
