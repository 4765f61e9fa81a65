//! Convex polygons: validation, edge normals and mass properties from the geometry.
//!
//! A [`Polygon`] is always centred on its centroid (the body's centre of mass), counter-
//! clockwise and strictly convex: [`Polygon::new`] refuses anything else and says which vertex
//! is at fault. The narrow phase also builds two-vertex "polygons" (a capsule's core segment)
//! through crate-internal constructors that skip the shape checks.

use super::error::PhysicsError;
use super::math::{cross, Real, Transform, Vec2};
use serde::{Deserialize, Serialize};

/// Most vertices a polygon may have.
pub const MAX_VERTICES: usize = 8;

/// Smallest |sin| of the turn between neighbouring edges: below it three vertices are taken
/// as collinear (about 0.06 degrees), which would give an edge normal of no use to the
/// narrow phase.
const MIN_TURN_SIN: Real = 1.0e-3;

/// Smallest extent a polygon may have (m): 0.1 mm.
pub const MIN_SPAN: Real = 1.0e-4;
/// Largest extent a polygon may have (m): 100 km.
pub const MAX_SPAN: Real = 1.0e5;

/// A convex polygon in body coordinates (m), counter-clockwise, centred on its centroid, with
/// outward unit edge normals. Edge `i` runs from `vertices[i]` to `vertices[(i + 1) % count]`
/// and has `normals[i]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PolygonVertices", into = "PolygonVertices")]
pub struct Polygon {
    pub(crate) vertices: [Vec2; MAX_VERTICES],
    pub(crate) normals: [Vec2; MAX_VERTICES],
    pub(crate) count: usize,
    /// Distance from the body origin to the farthest vertex (m), kept since every step asks
    /// for it per pair and per body (3.5 % of mixed_shapes' step when it was recomputed).
    radius: Real,
}

/// The serialized form of a [`Polygon`]: its vertices only. Reading one back re-runs the
/// checks and recomputes the normals, so no file or payload can smuggle in a bad polygon.
#[derive(Serialize, Deserialize)]
struct PolygonVertices(Vec<[Real; 2]>);

impl From<Polygon> for PolygonVertices {
    fn from(p: Polygon) -> Self {
        PolygonVertices(p.vertices().iter().map(|v| [v.x, v.y]).collect())
    }
}

impl TryFrom<PolygonVertices> for Polygon {
    type Error = PhysicsError;
    fn try_from(v: PolygonVertices) -> Result<Self, PhysicsError> {
        let points: Vec<Vec2> = v.0.iter().map(|p| Vec2::new(p[0], p[1])).collect();
        Polygon::centred(&points)
    }
}

fn bad(field: String, reason: String) -> PhysicsError {
    PhysicsError::InvalidShape { field, reason }
}

impl Polygon {
    /// A polygon from 3 to 8 vertices (m) listed counter-clockwise, moved so that its centroid
    /// is the origin. Returns the polygon and the centroid of the points as given, so a caller
    /// who placed the vertices around a body origin can move the body there
    /// (`position + R centroid`).
    ///
    /// Refuses non-finite coordinates, fewer than 3 or more than 8 vertices, repeated or
    /// collinear vertices, clockwise order and any non-convex corner, naming the vertex.
    pub fn new(points: &[Vec2]) -> Result<(Polygon, Vec2), PhysicsError> {
        check_points(points)?;
        // Twice: vertices drawn far from their origin lose digits in the first subtraction, so
        // the first centroid is off by up to a rounding step of the coordinates; the second,
        // computed near the origin, takes that out (a 5 cm polygon drawn at (999, 999) would
        // otherwise fail `Polygon::centred` when read back).
        let first = centroid_of(points);
        let once: Vec<Vec2> = points.iter().map(|&p| p - first).collect();
        let second = centroid_of(&once);
        let centred: Vec<Vec2> = once.iter().map(|&p| p - second).collect();
        let centroid = first + second;
        // What is built here must read back through `centred`; a tiny polygon drawn very far
        // from its origin keeps a residue no second pass removes, and is refused here rather
        // than when a checkpoint or journal is read.
        Polygon::centred(&centred).map_err(|_| {
            bad(
                "shape.vertices".into(),
                format!(
                    "lie around [{}, {}], too far from the body's origin for their size: their \
                     centroid cannot be found precisely; give them relative to the position",
                    centroid.x, centroid.y
                ),
            )
        })?;
        Ok((Polygon::from_checked(&centred), centroid))
    }

    /// A polygon from vertices that are already centred on their centroid (a polygon read
    /// back from a snapshot or a journal): the same checks as [`Polygon::new`], plus the
    /// centroid must be the origin to within 1e-4 of the polygon's size. Nothing is moved, so
    /// a round trip is bit-exact.
    pub fn centred(points: &[Vec2]) -> Result<Polygon, PhysicsError> {
        check_points(points)?;
        let c = centroid_of(points);
        let size = points.iter().fold(0.0 as Real, |m, p| m.max(p.length()));
        if c.length() > 1.0e-4 * size {
            return Err(bad(
                "shape.vertices".into(),
                format!(
                    "have their centroid at [{}, {}], not at the origin (the centre of mass)",
                    c.x, c.y
                ),
            ));
        }
        Ok(Polygon::from_checked(points))
    }

    /// The rectangle with half extents `h` (m), centred on the origin.
    /// Edges: 0 bottom, 1 right, 2 top, 3 left.
    pub(crate) fn rect(h: Vec2) -> Polygon {
        // Built directly: the normals are the axes exactly (normalising the edges would
        // round them), and the narrow phase builds two of these per box pair every step.
        Polygon::quad(
            [
                Vec2::new(-h.x, -h.y),
                Vec2::new(h.x, -h.y),
                Vec2::new(h.x, h.y),
                Vec2::new(-h.x, h.y),
            ],
            [
                Vec2::new(0.0, -1.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
                Vec2::new(-1.0, 0.0),
            ],
            h.length(),
        )
    }

    /// [`Polygon::rect`] moved by `xf`, built in place: the edge half-vectors rotated once
    /// instead of four vertices and four normals.
    pub(crate) fn rect_at(h: Vec2, xf: Transform) -> Polygon {
        let (c, s) = (xf.q.c, xf.q.s);
        let (ex, ey) = (Vec2::new(c * h.x, s * h.x), Vec2::new(-s * h.y, c * h.y));
        Polygon::quad(
            [
                xf.p - ex - ey,
                xf.p + ex - ey,
                xf.p + ex + ey,
                xf.p - ex + ey,
            ],
            [
                Vec2::new(s, -c),
                Vec2::new(c, s),
                Vec2::new(-s, c),
                Vec2::new(-c, -s),
            ],
            h.length(),
        )
    }

    /// A four-sided polygon from its vertices (counter-clockwise), their edges' unit normals
    /// and its bounding radius (m), taken as given.
    fn quad(vertices: [Vec2; 4], normals: [Vec2; 4], radius: Real) -> Polygon {
        let mut p = Polygon {
            vertices: [Vec2::ZERO; MAX_VERTICES],
            normals: [Vec2::ZERO; MAX_VERTICES],
            count: 4,
            radius,
        };
        p.vertices[..4].copy_from_slice(&vertices);
        p.normals[..4].copy_from_slice(&normals);
        p
    }

    /// The segment from (-half_length, 0) to (half_length, 0) as a two-sided "polygon": edge 0
    /// faces -y, edge 1 (running back) faces +y. A capsule is this core plus a radius.
    pub(crate) fn segment(half_length: Real) -> Polygon {
        let mut p = Polygon {
            vertices: [Vec2::ZERO; MAX_VERTICES],
            normals: [Vec2::ZERO; MAX_VERTICES],
            count: 2,
            radius: half_length.abs(),
        };
        p.vertices[0] = Vec2::new(-half_length, 0.0);
        p.vertices[1] = Vec2::new(half_length, 0.0);
        p.normals[0] = Vec2::new(0.0, -1.0);
        p.normals[1] = Vec2::new(0.0, 1.0);
        p
    }

    /// The segment from `a` to `b` (body frame, m) as a two-sided "polygon": edge 0 faces
    /// the right of a -> b, edge 1 (running back) its left. A segment shape's core.
    pub(crate) fn between(a: Vec2, b: Vec2) -> Polygon {
        let mut p = Polygon::segment(0.0);
        let d = (b - a).normalize();
        p.vertices[0] = a;
        p.vertices[1] = b;
        p.normals[0] = Vec2::new(d.y, -d.x);
        p.normals[1] = Vec2::new(-d.y, d.x);
        p.radius = a.length().max(b.length());
        p
    }

    /// A single point: a circle's core.
    pub(crate) fn point() -> Polygon {
        Polygon {
            vertices: [Vec2::ZERO; MAX_VERTICES],
            normals: [Vec2::ZERO; MAX_VERTICES],
            count: 1,
            radius: 0.0,
        }
    }

    /// Build from points that passed [`check_points`]: normals are the edges turned
    /// clockwise (outward for a counter-clockwise polygon), normalised.
    fn from_checked(points: &[Vec2]) -> Polygon {
        let n = points.len();
        let mut vertices = [Vec2::ZERO; MAX_VERTICES];
        let mut normals = [Vec2::ZERO; MAX_VERTICES];
        vertices[..n].copy_from_slice(points);
        for i in 0..n {
            let e = points[(i + 1) % n] - points[i];
            normals[i] = Vec2::new(e.y, -e.x).normalize();
        }
        Polygon {
            vertices,
            normals,
            count: n,
            radius: points.iter().fold(0.0 as Real, |m, v| m.max(v.length())),
        }
    }

    /// The vertices, counter-clockwise (m).
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices[..self.count]
    }

    /// The outward unit normal of each edge.
    pub fn normals(&self) -> &[Vec2] {
        &self.normals[..self.count]
    }

    /// Area (m^2): the sum of the triangle fan from the centroid.
    pub fn area(&self) -> Real {
        let v = self.vertices();
        (0..v.len())
            .map(|i| 0.5 * cross(v[i], v[(i + 1) % v.len()]))
            .sum()
    }

    /// Polar second moment of area about the centroid (m^4): the sum over the fan's triangles
    /// (0, e1, e2) of cross(e1, e2) (e1.e1 + e1.e2 + e2.e2) / 12. Multiplied by density it is
    /// the moment of inertia; divided by the area it is I / m.
    pub fn second_moment(&self) -> Real {
        let v = self.vertices();
        (0..v.len())
            .map(|i| {
                let (e1, e2) = (v[i], v[(i + 1) % v.len()]);
                cross(e1, e2) * (e1.dot(e1) + e1.dot(e2) + e2.dot(e2)) / 12.0
            })
            .sum()
    }

    /// Distance from the centroid to the farthest vertex (m), for the polygon as built (not
    /// for a [`Polygon::transformed`] copy, whose vertices are in world space).
    pub fn radius(&self) -> Real {
        self.radius
    }

    /// The polygon moved by `xf` (vertices transformed, normals rotated).
    pub(crate) fn transformed(&self, xf: Transform) -> Polygon {
        // Filled slot by slot rather than copied whole: only `count` of the eight are used.
        let mut out = Polygon {
            vertices: [Vec2::ZERO; MAX_VERTICES],
            normals: [Vec2::ZERO; MAX_VERTICES],
            count: self.count,
            radius: self.radius,
        };
        for i in 0..self.count {
            out.vertices[i] = xf.apply(self.vertices[i]);
            out.normals[i] = xf.q.rotate(self.normals[i]);
        }
        out
    }
}

/// The area centroid of a simple polygon (triangle fan from the first vertex, which keeps the
/// arithmetic near the polygon and so loses less precision far from the origin).
fn centroid_of(points: &[Vec2]) -> Vec2 {
    let o = points[0];
    let mut area = 0.0;
    let mut moment = Vec2::ZERO;
    for i in 1..points.len() - 1 {
        let (e1, e2) = (points[i] - o, points[i + 1] - o);
        let a = 0.5 * cross(e1, e2);
        area += a;
        moment += a * (e1 + e2) / 3.0;
    }
    o + moment / area
}

/// The shape checks shared by [`Polygon::new`] and [`Polygon::centred`].
fn check_points(points: &[Vec2]) -> Result<(), PhysicsError> {
    let n = points.len();
    if !(3..=MAX_VERTICES).contains(&n) {
        return Err(bad(
            "shape.vertices".into(),
            format!("must hold 3 to {MAX_VERTICES} points, got {n}"),
        ));
    }
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return Err(bad(
                format!("shape.vertices[{i}]"),
                format!("must be finite, got [{}, {}]", p.x, p.y),
            ));
        }
    }
    let size = points
        .iter()
        .flat_map(|p| [(p.x - points[0].x).abs(), (p.y - points[0].y).abs()])
        .fold(0.0 as Real, Real::max);
    // Outside this range the products below under- or overflow in f32 and the checks would
    // blame the wrong thing; no simulated body is that small or that large anyway.
    if !(MIN_SPAN..=MAX_SPAN).contains(&size) {
        return Err(bad(
            "shape.vertices".into(),
            format!("span {size} m: a polygon must span {MIN_SPAN} m to {MAX_SPAN} m"),
        ));
    }
    for i in 0..n {
        let (p, q) = (points[i], points[(i + 1) % n]);
        if (q - p).length() <= 1.0e-4 * size {
            let j = (i + 1) % n;
            return Err(bad(
                format!("shape.vertices[{j}]"),
                format!(
                    "= [{}, {}] repeats vertex {i}: vertices must be distinct",
                    q.x, q.y
                ),
            ));
        }
    }
    for i in 0..n {
        let (p, q, r) = (points[i], points[(i + 1) % n], points[(i + 2) % n]);
        let (e1, e2) = (q - p, r - q);
        let j = (i + 1) % n;
        let turn = cross(e1, e2);
        if turn <= MIN_TURN_SIN * e1.length() * e2.length() {
            let why = if turn < 0.0 {
                "turns clockwise there: list vertices counter-clockwise, and the polygon must be convex"
            } else {
                "is collinear with its neighbours: drop it"
            };
            return Err(bad(
                format!("shape.vertices[{j}]"),
                format!("= [{}, {}] {why}", q.x, q.y),
            ));
        }
    }
    // Every corner turning left is not enough: a star winds twice. The angles must add up to
    // one full turn, which for left turns means the total area is positive and the edges
    // never cross; checking that each edge's normal sweeps forward catches the star.
    let mut swept = 0.0;
    for i in 0..n {
        let (e1, e2) = (
            points[(i + 1) % n] - points[i],
            points[(i + 2) % n] - points[(i + 1) % n],
        );
        swept += cross(e1, e2).atan2(e1.dot(e2));
    }
    if swept > 1.5 * super::math::PI * 2.0 {
        return Err(bad(
            "shape.vertices".into(),
            "wind around more than once (a star): the polygon must be convex".into(),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::math::vec2;

    #[test]
    fn unit_square_mass_properties_match_closed_form() {
        let (p, c) = Polygon::new(&[
            vec2(0.0, 0.0),
            vec2(1.0, 0.0),
            vec2(1.0, 1.0),
            vec2(0.0, 1.0),
        ])
        .unwrap();
        assert!((c - vec2(0.5, 0.5)).length() < 1e-6);
        assert!((p.area() - 1.0).abs() < 1e-6);
        // Square of side a: J = a^4 / 6.
        assert!((p.second_moment() - 1.0 / 6.0).abs() < 1e-6);
        assert_eq!(p.normals()[0], vec2(0.0, -1.0));
    }

    #[test]
    fn a_rectangle_built_in_place_is_the_checked_polygon_moved() {
        // The narrow phase's rectangle shortcuts against the general path: the checked
        // polygon of the same corners, moved vertex by vertex. Tolerance: a few f32 ulps of
        // the 3 m coordinates (the two round differently, 1e-6 relative).
        let h = vec2(0.35, 1.2);
        let corners = [
            vec2(-h.x, -h.y),
            vec2(h.x, -h.y),
            vec2(h.x, h.y),
            vec2(-h.x, h.y),
        ];
        let (checked, _) = Polygon::new(&corners).unwrap();
        let rect = Polygon::rect(h);
        // (`Polygon::new` recentres on the computed centroid, which rounds.)
        for (v, w) in rect.vertices().iter().zip(checked.vertices()) {
            assert!((*v - *w).length() < 1e-6, "{v} against {w}");
        }
        for (n, m) in rect.normals().iter().zip(checked.normals()) {
            assert!((*n - *m).length() < 1e-6, "{n} against {m}");
        }
        assert!((rect.radius - h.length()).abs() < 1e-6);
        for angle in [0.0, 0.3, -2.0, 3.0] {
            let xf = Transform {
                p: vec2(1.5, -2.5),
                q: crate::physics::math::Rot::from_angle(angle),
            };
            let (fast, slow) = (Polygon::rect_at(h, xf), checked.transformed(xf));
            assert_eq!(fast.count, 4);
            for i in 0..4 {
                assert!((fast.vertices[i] - slow.vertices[i]).length() < 3e-6);
                assert!((fast.normals[i] - slow.normals[i]).length() < 1e-6);
            }
        }
    }

    #[test]
    fn right_triangle_centroid_and_inertia() {
        // Legs a = 3 (x), b = 2 (y): centroid (a/3, b/3), J about centroid = A (a^2 + b^2) / 18.
        let (p, c) = Polygon::new(&[vec2(0.0, 0.0), vec2(3.0, 0.0), vec2(0.0, 2.0)]).unwrap();
        assert!((c - vec2(1.0, 2.0 / 3.0)).length() < 1e-6);
        assert!((p.area() - 3.0).abs() < 1e-5);
        assert!((p.second_moment() - 3.0 * 13.0 / 18.0).abs() < 1e-5);
    }

    #[test]
    fn regular_hexagon_second_moment() {
        // Regular hexagon of circumradius R: J = (5 sqrt 3 / 8) R^4.
        let r: Real = 0.5;
        let pts: Vec<Vec2> = (0..6)
            .map(|k| {
                let a = k as Real * std::f64::consts::FRAC_PI_3 as Real;
                vec2(r * a.cos(), r * a.sin())
            })
            .collect();
        let (p, c) = Polygon::new(&pts).unwrap();
        assert!(c.length() < 1e-6);
        let expected = 5.0 * (3.0 as Real).sqrt() / 8.0 * r.powi(4);
        assert!((p.second_moment() - expected).abs() < 1e-6 * 10.0);
    }

    #[test]
    fn bad_polygons_are_refused_naming_the_vertex() {
        let msg = |pts: &[Vec2]| Polygon::new(pts).unwrap_err().to_string();
        let v = |pts: &[(Real, Real)]| pts.iter().map(|&(x, y)| vec2(x, y)).collect::<Vec<_>>();
        // (vertices, what the message must contain)
        type Case<'a> = (&'a [(Real, Real)], &'a [&'a str]);
        let cases: [Case; 6] = [
            (
                &[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)],
                &["shape.vertices[1]", "clockwise"],
            ),
            (
                &[(0.0, 0.0), (2.0, 0.0), (1.0, 0.5), (2.0, 2.0), (0.0, 2.0)],
                &["shape.vertices[2]"],
            ),
            (&[(0.0, 0.0), (1.0, 0.0)], &["3 to 8", "got 2"]),
            (
                &[(0.0, 0.0), (Real::NAN, 0.0), (0.0, 1.0)],
                &["shape.vertices[1]", "NaN"],
            ),
            (
                &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 1.0)],
                &["collinear"],
            ),
            (
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 0.0), (0.0, 1.0)],
                &["repeats"],
            ),
        ];
        for (pts, wanted) in cases {
            let m = msg(&v(pts));
            assert!(wanted.iter().all(|w| m.contains(w)), "{pts:?}: {m}");
        }
        // A pentagram: every corner turns left, yet it winds twice.
        let star: Vec<Vec2> = (0..5)
            .map(|k| {
                let a = (k * 2) as Real * 2.0 * super::super::math::PI / 5.0;
                vec2(a.cos(), a.sin())
            })
            .collect();
        let s = msg(&star);
        assert!(s.contains("more than once"), "{s}");
    }

    #[test]
    fn a_small_polygon_drawn_far_away_reads_back() {
        // A 5 cm pentagon around (999, 999): its centred form must pass `centred`.
        let pts: Vec<Vec2> = (0..5)
            .map(|k| {
                let a = k as Real * 2.0 * super::super::math::PI / 5.0;
                vec2(999.0 + 0.025 * a.cos(), 999.0 + 0.025 * a.sin())
            })
            .collect();
        let (p, c) = Polygon::new(&pts).unwrap();
        assert!((c - vec2(999.0, 999.0)).length() < 1e-3);
        assert_eq!(Polygon::centred(p.vertices()).unwrap(), p);
    }

    #[test]
    fn every_polygon_built_far_from_the_origin_reads_back() {
        // Pentagons of 0.5 mm to 5 cm drawn around 1 km, 10 km and 100 km, 200 turns each: what
        // `new` builds must pass `centred` (the checkpoint and journal read-back); what it
        // cannot build it refuses (there, vertices closer than the f32 spacing repeat).
        let mut built_at_1_km = 0;
        for centre in [999.0, 9_999.0, 99_999.0] {
            for r in [0.05, 0.01, 0.005, 0.002, 0.001, 0.0005] {
                for n in 0..200 {
                    let pts: Vec<Vec2> = (0..5)
                        .map(|k| {
                            let a = k as Real * 1.256_637 + n as Real * 0.013;
                            vec2(centre + r * a.cos(), centre + 0.37 + r * a.sin())
                        })
                        .collect();
                    if let Ok((p, _)) = Polygon::new(&pts) {
                        assert!(Polygon::centred(p.vertices()).is_ok(), "{pts:?}");
                        built_at_1_km += usize::from(centre < 1_000.0);
                    }
                }
            }
        }
        // At 1 km f32 coordinates are 61 um apart, far below the smallest pentagon's 0.5 mm:
        // every one of those 1,200 must be built, not refused.
        assert_eq!(built_at_1_km, 1_200);
    }

    #[test]
    fn serde_round_trip_rechecks_and_is_exact() {
        let (p, _) = Polygon::new(&[vec2(0.1, 0.0), vec2(1.0, 0.3), vec2(0.2, 0.9)]).unwrap();
        let json = serde_json_like(&p);
        let back = Polygon::try_from(json).unwrap();
        assert_eq!(back, p);
        let off = PolygonVertices(vec![[1.0, 1.0], [2.0, 1.0], [1.0, 2.0]]);
        let e = Polygon::try_from(off).unwrap_err().to_string();
        assert!(e.contains("centroid"), "{e}");
    }

    fn serde_json_like(p: &Polygon) -> PolygonVertices {
        PolygonVertices::from(*p)
    }
}
