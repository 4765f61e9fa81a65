//! Exact geometry for queries on rounded convex cores: every shape is a convex core of one to
//! eight vertices (a circle's centre, a capsule's or segment's two ends, a polygon) grown by a
//! radius, as the narrow phase sees it (`collide::core`).
//!
//! - point to core: 0 inside a polygon of three vertices or more, else the nearest edge;
//! - core to core: 0 where they cross, else the nearest vertex-edge pair (two convex sets
//!   apart are nearest at a vertex of one);
//! - a ray against a rounded core: the first crossing of the core's edges pushed out by the
//!   radius and of the circles about its vertices (Minkowski: the rounded core is their union);
//! - a shape cast is a ray from the origin against the difference of the two cores (the
//!   offsets at which they meet) grown by both radii.

use crate::physics::math::{cross, Real, Vec2};

/// The most vertices a core has: a polygon's eight, or the hull of two polygons' difference.
pub(crate) const MAX_CORE: usize = 16;

/// A convex core in world coordinates: its vertices counter-clockwise (one, two, or three to
/// sixteen) and the radius it is grown by (m). Kept inline, so a query allocates nothing.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rounded {
    points: [Vec2; MAX_CORE],
    count: usize,
    pub radius: Real,
}

impl Rounded {
    /// The core of `vertices` (at most [`MAX_CORE`]; the rest are dropped) grown by `radius`.
    pub fn new(vertices: impl IntoIterator<Item = Vec2>, radius: Real) -> Rounded {
        let mut r = Rounded {
            points: [Vec2::ZERO; MAX_CORE],
            count: 0,
            radius,
        };
        for (slot, v) in r.points.iter_mut().zip(vertices) {
            *slot = v;
            r.count += 1;
        }
        r
    }

    /// The vertices, counter-clockwise (m).
    pub fn vertices(&self) -> &[Vec2] {
        &self.points[..self.count]
    }

    /// The same core moved by `by` (m).
    pub fn moved(&self, by: Vec2) -> Rounded {
        Rounded::new(self.vertices().iter().map(|&v| v + by), self.radius)
    }
}

/// Where a ray first meets a surface: the fraction of its translation and the surface's
/// outward normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    pub fraction: Real,
    pub normal: Vec2,
}

/// The nearest point of segment `a`-`b` to `p`.
fn nearest_on_segment(p: Vec2, a: Vec2, b: Vec2) -> Vec2 {
    let e = b - a;
    let len2 = e.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    a + e * ((p - a).dot(e) / len2).clamp(0.0, 1.0)
}

/// The edges of a core, each as (start, end): a segment's two sides, a point's none.
fn edges(v: &[Vec2]) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
    let n = v.len();
    let count = if n < 2 { 0 } else { n };
    (0..count).map(move |i| (v[i], v[(i + 1) % n]))
}

/// Whether `p` lies inside (or on) a core of three or more vertices.
fn inside_polygon(v: &[Vec2], p: Vec2) -> bool {
    v.len() >= 3 && edges(v).all(|(a, b)| cross(b - a, p - a) >= 0.0)
}

/// The distance (m) from `p` to a core, and the core's nearest point.
pub(crate) fn point_to_core(v: &[Vec2], p: Vec2) -> (Real, Vec2) {
    if inside_polygon(v, p) {
        return (0.0, p);
    }
    if v.len() == 1 {
        return ((p - v[0]).length(), v[0]);
    }
    edges(v)
        .map(|(a, b)| {
            let q = nearest_on_segment(p, a, b);
            ((p - q).length(), q)
        })
        .fold((Real::INFINITY, p), |m, d| if d.0 < m.0 { d } else { m })
}

/// Whether segments `a0`-`a1` and `b0`-`b1` cross.
fn segments_cross(a0: Vec2, a1: Vec2, b0: Vec2, b1: Vec2) -> bool {
    let d1 = cross(a1 - a0, b0 - a0);
    let d2 = cross(a1 - a0, b1 - a0);
    let d3 = cross(b1 - b0, a0 - b0);
    let d4 = cross(b1 - b0, a1 - b0);
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && (d1 != 0.0 || d2 != 0.0)
}

/// The distance (m) between two cores, and the nearest point of each (the same point where
/// they cross).
pub(crate) fn core_to_core(a: &[Vec2], b: &[Vec2]) -> (Real, Vec2, Vec2) {
    if let Some(&p) = a.iter().find(|&&p| inside_polygon(b, p)) {
        return (0.0, p, p);
    }
    if let Some(&p) = b.iter().find(|&&p| inside_polygon(a, p)) {
        return (0.0, p, p);
    }
    for (a0, a1) in edges(a) {
        if edges(b).any(|(b0, b1)| segments_cross(a0, a1, b0, b1)) {
            return (0.0, a0, a0);
        }
    }
    let mut best = (Real::INFINITY, Vec2::ZERO, Vec2::ZERO);
    for &p in a {
        let (d, q) = point_to_core(b, p);
        if d < best.0 {
            best = (d, p, q);
        }
    }
    for &p in b {
        let (d, q) = point_to_core(a, p);
        if d < best.0 {
            best = (d, q, p);
        }
    }
    best
}

/// The first t in [0, max] at which `origin + t d` enters the circle of `radius` about `c`.
fn ray_circle(origin: Vec2, d: Vec2, c: Vec2, radius: Real, max: Real) -> Option<Crossing> {
    let s = origin - c;
    let (a, b, k) = (d.dot(d), s.dot(d), s.dot(s) - radius * radius);
    let disc = b * b - a * k;
    if a <= 0.0 || b >= 0.0 || disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    (0.0..=max).contains(&t).then(|| Crossing {
        fraction: t,
        normal: (s + t * d).normalize_or_zero(),
    })
}

/// The first t in [0, max] at which `origin + t d` crosses edge `a`-`b` pushed out by
/// `radius` from the outside (the edge's outward normal is (e.y, -e.x) / |e|).
fn ray_edge(
    origin: Vec2,
    d: Vec2,
    (a, b): (Vec2, Vec2),
    radius: Real,
    max: Real,
) -> Option<Crossing> {
    let e = b - a;
    let len = e.length();
    if len <= 0.0 {
        return None;
    }
    let n = Vec2::new(e.y, -e.x) / len;
    let (approach, gap) = (d.dot(n), (origin - a).dot(n) - radius);
    if approach >= 0.0 || gap < 0.0 {
        return None;
    }
    let t = -gap / approach;
    let along = (origin + t * d - a).dot(e) / (len * len);
    ((0.0..=max).contains(&t) && (0.0..=1.0).contains(&along)).then_some(Crossing {
        fraction: t,
        normal: n,
    })
}

/// The first t in [0, max] at which `origin + t d` enters the rounded core; none when the
/// origin starts inside it (a ray does not hit what it starts in) or never reaches it.
pub(crate) fn ray_rounded(shape: &Rounded, origin: Vec2, d: Vec2, max: Real) -> Option<Crossing> {
    let v = shape.vertices();
    if point_to_core(v, origin).0 <= shape.radius {
        return None;
    }
    let on_edges = edges(v).filter_map(|e| ray_edge(origin, d, e, shape.radius, max));
    let on_circles = v
        .iter()
        .filter(|_| shape.radius > 0.0)
        .filter_map(|&c| ray_circle(origin, d, c, shape.radius, max));
    on_edges
        .chain(on_circles)
        .min_by(|x, y| x.fraction.total_cmp(&y.fraction))
}

/// The most points [`hull`] takes: every difference of two cores' vertices.
const MAX_CLOUD: usize = 64;

/// The convex hull of `points` (at most 64; sorted in place), counter-clockwise without
/// collinear points (Andrew's monotone chain); one or two points when they are all on a point
/// or a line. Radius 0.
pub(crate) fn hull(points: &mut [Vec2]) -> Rounded {
    let keep = points.len().min(MAX_CLOUD);
    let points = &mut points[..keep];
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut unique = 0;
    for i in 0..points.len() {
        if unique == 0 || points[i] != points[unique - 1] {
            points[unique] = points[i];
            unique += 1;
        }
    }
    let points = &points[..unique];
    if points.len() < 3 {
        return Rounded::new(points.iter().copied(), 0.0);
    }
    let mut out = [Vec2::ZERO; 2 * MAX_CLOUD + 2];
    let mut len = 0;
    for pass in 0..2 {
        let start = len;
        let order: &mut dyn Iterator<Item = &Vec2> = match pass {
            0 => &mut points.iter(),
            _ => &mut points.iter().rev(),
        };
        for &p in order {
            while len >= start + 2 && cross(out[len - 1] - out[len - 2], p - out[len - 2]) <= 0.0 {
                len -= 1;
            }
            out[len] = p;
            len += 1;
        }
        len -= 1;
    }
    Rounded::new(out[..len].iter().copied(), 0.0)
}

/// The offsets at which core `a` (moved by them) meets core `b`: the hull of b - a.
pub(crate) fn difference(b: &[Vec2], a: &[Vec2]) -> Rounded {
    let mut cloud = [Vec2::ZERO; MAX_CLOUD];
    let mut n = 0;
    for &q in b {
        for &p in a {
            if n < MAX_CLOUD {
                cloud[n] = q - p;
                n += 1;
            }
        }
    }
    hull(&mut cloud[..n])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    fn square() -> Vec<Vec2> {
        vec![
            vec2(-1.0, -1.0),
            vec2(1.0, -1.0),
            vec2(1.0, 1.0),
            vec2(-1.0, 1.0),
        ]
    }

    #[test]
    fn a_ray_meets_a_square_a_disc_and_a_capsule_where_the_closed_forms_say() {
        let sq = Rounded::new(square(), 0.0);
        let hit = ray_rounded(&sq, vec2(-5.0, 0.5), vec2(10.0, 0.0), 1.0).unwrap();
        assert!((hit.fraction - 0.4).abs() < 1e-6 && hit.normal == vec2(-1.0, 0.0));
        let disc = Rounded::new(vec![vec2(3.0, 0.0)], 2.0);
        // From (0, 1) along +x the disc x^2 + y^2 = 4 about (3, 0) is entered at x = 3 - sqrt(3).
        let hit = ray_rounded(&disc, vec2(-3.0, 1.0), vec2(6.0, 0.0), 1.0).unwrap();
        let x = 3.0 - (3.0 as Real).sqrt();
        assert!((hit.fraction - (x + 3.0) / 6.0).abs() < 1e-6);
        assert!((hit.normal - vec2(x - 3.0, 1.0) / 2.0).length() < 1e-6);
        // A capsule from (0, 0) to (4, 0) of radius 0.5: its side at y = 0.5, its end at x = 4.5.
        let cap = Rounded::new(vec![vec2(0.0, 0.0), vec2(4.0, 0.0)], 0.5);
        let down = ray_rounded(&cap, vec2(2.0, 3.0), vec2(0.0, -10.0), 1.0).unwrap();
        assert!((down.fraction - 0.25).abs() < 1e-6 && down.normal == vec2(0.0, 1.0));
        let left = ray_rounded(&cap, vec2(10.0, 0.0), vec2(-10.0, 0.0), 1.0).unwrap();
        assert!(
            (left.fraction - 0.55).abs() < 1e-6 && (left.normal - vec2(1.0, 0.0)).length() < 1e-6
        );
        // Too short, pointing away, or starting inside: no hit.
        assert!(ray_rounded(&sq, vec2(-5.0, 0.5), vec2(3.0, 0.0), 1.0).is_none());
        assert!(ray_rounded(&sq, vec2(-5.0, 0.5), vec2(-3.0, 0.0), 1.0).is_none());
        assert!(ray_rounded(&sq, vec2(0.0, 0.0), vec2(3.0, 0.0), 1.0).is_none());
    }

    #[test]
    fn cores_are_apart_by_their_nearest_vertex_and_edge_or_cross() {
        let sq = square();
        let tri = vec![vec2(3.0, 0.0), vec2(5.0, -1.0), vec2(5.0, 1.0)];
        let (d, pa, pb) = core_to_core(&sq, &tri);
        assert!((d - 2.0).abs() < 1e-6 && pa.x == 1.0 && pb == vec2(3.0, 0.0));
        let cross_bar = vec![vec2(0.0, -3.0), vec2(0.0, 3.0)];
        assert_eq!(core_to_core(&sq, &cross_bar).0, 0.0);
        let x = vec![vec2(-2.0, 0.0), vec2(2.0, 0.0)];
        assert_eq!(core_to_core(&x, &cross_bar).0, 0.0);
        let apart = vec![vec2(3.0, 0.0), vec2(6.0, 0.0)];
        assert!((core_to_core(&x, &apart).0 - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_hull_of_a_cloud_is_its_convex_rim_counter_clockwise() {
        let mut cloud = square();
        cloud.extend([vec2(0.0, 0.0), vec2(0.5, -0.2), vec2(1.0, 0.0)]);
        let h = hull(&mut cloud);
        let h = h.vertices();
        assert_eq!(h.len(), 4);
        for i in 0..4 {
            let (a, b, c) = (h[i], h[(i + 1) % 4], h[(i + 2) % 4]);
            assert!(cross(b - a, c - b) > 0.0);
        }
        assert_eq!(
            hull(&mut [vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(2.0, 2.0)])
                .vertices()
                .len(),
            2
        );
        // Two unit squares 3 m apart meet when the second has moved by the difference's offsets.
        let moved: Vec<Vec2> = square().iter().map(|&p| p + vec2(3.0, 0.0)).collect();
        let diff = difference(&moved, &square());
        let hit = ray_rounded(&diff, Vec2::ZERO, vec2(2.0, 0.0), 1.0).unwrap();
        assert!((hit.fraction - 0.5).abs() < 1e-6 && hit.normal == vec2(-1.0, 0.0));
    }
}
