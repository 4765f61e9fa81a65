//! Answering `…/query` requests from the World as it is between ticks.

use super::Simulation;
use crate::physics::{Aabb, QueryFilter, RayHit, ShapeRef};
use crate::protocol::{BodyRef, QueryAnswer, QueryFilterSpec, RayHitInfo, ShapeHit, WorldQuery};
use crate::service::wire::{vec2, vector};
use crate::service::world_query::MAX_HITS;

fn filter(f: QueryFilterSpec) -> QueryFilter {
    QueryFilter {
        category: f.category,
        mask: f.mask,
    }
}

fn shape_hit(s: ShapeRef) -> ShapeHit {
    ShapeHit {
        id: BodyRef::from(s.body),
        shape: s.shape,
    }
}

fn ray_hit(h: RayHit) -> RayHitInfo {
    RayHitInfo {
        hit: shape_hit(h.shape),
        point: vector(h.point),
        normal: vector(h.normal),
        fraction: h.fraction as f32,
    }
}

impl Simulation {
    /// The answer to `q` from the World after the last step (a refusal names the field).
    pub fn answer_query(&mut self, q: &WorldQuery) -> QueryAnswer {
        let frame = self.frame;
        let query = self.world.query();
        let hits = |v: Vec<RayHit>| QueryAnswer::Hits {
            frame,
            hits: v.into_iter().map(ray_hit).collect(),
        };
        let shapes = |v: Vec<ShapeRef>| QueryAnswer::Shapes {
            frame,
            shapes: v.into_iter().map(shape_hit).collect(),
        };
        let answer = match *q {
            WorldQuery::RayClosest {
                origin,
                translation,
                filter: f,
            } => query
                .ray_closest(vec2(origin), vec2(translation), filter(f))
                .map(|h| hits(h.into_iter().collect())),
            WorldQuery::RayAll {
                origin,
                translation,
                filter: f,
                limit,
            } => query
                .ray_all(
                    vec2(origin),
                    vec2(translation),
                    filter(f),
                    limit.min(MAX_HITS) as usize,
                )
                .map(hits),
            WorldQuery::Point { point, filter: f } => {
                query.at_point(vec2(point), filter(f)).map(shapes)
            }
            WorldQuery::Box {
                min,
                max,
                filter: f,
            } => {
                let aabb = Aabb {
                    min: vec2(min),
                    max: vec2(max),
                };
                query.in_box(aabb, filter(f)).map(shapes)
            }
        };
        answer.unwrap_or_else(|e| QueryAnswer::Refused {
            reason: e.to_string(),
        })
    }
}
