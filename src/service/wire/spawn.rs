//! A spawned body from the wire to the engine: its shape through the engine's constructors,
//! its sizes against the daemon's [`Limits`], its place (a polygon's centre of mass at its
//! centroid, by `BodyDef::placed`), then everything the engine checks.

#![allow(clippy::unnecessary_cast)] // Real <-> f32 casts matter with the `f64` feature.

use super::{finite, vec2};
use crate::physics::convex::MAX_VERTICES;
use crate::physics::{BodyDef, PhysicsError, Polygon, Real, Shape, Vec2};
use crate::protocol::{ShapeSpec, SpawnBody, Vector};
use crate::service::command::SpawnDef;
use crate::service::config::Limits;

/// Largest spawn angle (rad): larger finite angles are legal but only lose precision.
const MAX_ANGLE: f32 = 1.0e4;

/// The engine shape for a wire shape, and where its centre of mass sits relative to the
/// body origin the sender gave (non-zero only for a polygon whose vertices are not centred).
/// Refuses what the engine refuses, naming the field (a capsule through `Shape::try_capsule`,
/// the scene files' rule too).
///
/// A polygon is also refused when its vertices lie so far from the origin for their size
/// that their centroid cannot be found to within 1e-4 of the size even after a second
/// centring pass: such a polygon could not be read back from a journal or a checkpoint
/// (`Polygon::centred`), so the daemon would record what it cannot restore.
pub(crate) fn shape_from_spec(spec: &ShapeSpec) -> Result<(Shape, Vec2), PhysicsError> {
    let shape = match *spec {
        ShapeSpec::Rect { width, height } => Shape::rect(width as Real, height as Real),
        ShapeSpec::Circle { radius } => Shape::circle(radius as Real),
        ShapeSpec::Capsule { length, radius } => {
            return Ok((
                Shape::try_capsule(length as Real, radius as Real)?,
                Vec2::ZERO,
            ))
        }
        ShapeSpec::Polygon { ref vertices } => {
            if vertices.len() > MAX_VERTICES {
                // Refused before anything is copied (the payload limit bounds the list).
                return Err(PhysicsError::InvalidShape {
                    field: "shape.vertices".into(),
                    reason: format!(
                        "must hold 3 to {MAX_VERTICES} points, got {}",
                        vertices.len()
                    ),
                });
            }
            let points: Vec<Vec2> = vertices.iter().map(|&v| vec2(v)).collect();
            // `Polygon::new` centres in two passes and refuses what would not read back.
            let (p, centroid) = Polygon::new(&points)?;
            return Ok((Shape::from(p), centroid));
        }
        ShapeSpec::Compound { .. } => {
            return Err(PhysicsError::InvalidShape {
                field: "shape".into(),
                reason: "a compound is not one shape: a body of several shapes is built on \
                         …/build, its shapes listed as parts"
                    .into(),
            })
        }
        ShapeSpec::Segment {
            a,
            b,
            radius,
            prev,
            next,
            one_sided,
        } => Shape::Segment(Box::new(crate::physics::Segment {
            a: vec2(a),
            b: vec2(b),
            radius: radius as Real,
            prev: prev.map(vec2),
            next: next.map(vec2),
            one_sided,
        })),
    };
    shape.validate()?;
    Ok((shape, Vec2::ZERO))
}

/// One size of a wire shape that the daemon's limits bound.
struct Size {
    /// The field, e.g. `shape.radius`.
    field: &'static str,
    /// The value the sender gave.
    given: f32,
    /// What is bounded, when it is not the value itself (e.g. `the diameter`).
    what: Option<&'static str>,
    /// The size in metres checked against `limits.min_size` and `limits.max_coordinate`.
    metres: f32,
}

/// Check a shape the engine accepted (so every number is finite) against the daemon's
/// limits: every size within [`limits.min_size`, `limits.max_coordinate`]; for a polygon
/// (whose coordinates [`check_vertices_as_sent`] bounded), its extent along x and y at
/// most `limits.max_coordinate`, and its thickness (its smallest width, measured across
/// each edge) at least `limits.min_size`. The refusal names the field and the value given.
pub(super) fn check_shape_limits(
    spec: &ShapeSpec,
    shape: &Shape,
    limits: &Limits,
) -> Result<(), String> {
    let (min, max) = (limits.min_size, limits.max_coordinate);
    let sizes = match *spec {
        ShapeSpec::Rect { width, height } => vec![
            Size {
                field: "shape.width",
                given: width,
                what: None,
                metres: width,
            },
            Size {
                field: "shape.height",
                given: height,
                what: None,
                metres: height,
            },
        ],
        ShapeSpec::Circle { radius } => vec![Size {
            field: "shape.radius",
            given: radius,
            what: Some("the diameter"),
            metres: 2.0 * radius,
        }],
        ShapeSpec::Capsule { length, radius } => vec![
            Size {
                field: "shape.length",
                given: length,
                what: None,
                metres: length,
            },
            Size {
                field: "shape.radius",
                given: radius,
                what: Some("the thickness (2 x radius)"),
                metres: 2.0 * radius,
            },
        ],
        ShapeSpec::Polygon { ref vertices } => {
            let (mut lo, mut hi) = (
                Vector::new(f32::MAX, f32::MAX),
                Vector::new(f32::MIN, f32::MIN),
            );
            for v in vertices {
                lo = Vector::new(lo.x.min(v.x), lo.y.min(v.y));
                hi = Vector::new(hi.x.max(v.x), hi.y.max(v.y));
            }
            for (axis, span) in [("x", hi.x - lo.x), ("y", hi.y - lo.y)] {
                if span > max {
                    return Err(format!(
                        "shape.vertices span {span} m along {axis}: must be <= {max} \
                         (limits.max_coordinate)"
                    ));
                }
            }
            if let Shape::Polygon(ref p) = *shape {
                if let Some((edge, thickness)) = polygon_thickness(p) {
                    if thickness < min as Real {
                        return Err(format!(
                            "shape.vertices make a polygon {thickness} m thick (across the edge \
                             from vertices[{edge}]): must be >= {min} (limits.min_size)"
                        ));
                    }
                }
            }
            Vec::new()
        }
        ShapeSpec::Segment { .. } => {
            return Err(
                "shape = segment: a spawned body is dynamic, and segments are for \
                        static and kinematic bodies (put terrain and platforms in the scene \
                        file)"
                    .into(),
            )
        }
        ShapeSpec::Compound { .. } => {
            return Err(
                "shape = compound: a body of several shapes is built on …/build, \
                 its shapes listed as parts"
                    .into(),
            )
        }
    };
    for s in sizes {
        let what = s
            .what
            .map(|w| format!("{w} {} ", s.metres))
            .unwrap_or_default();
        if s.metres > max {
            return Err(format!(
                "{} = {} is out of range: {what}must be <= {max} (limits.max_coordinate)",
                s.field, s.given
            ));
        }
        if s.metres < min {
            return Err(format!(
                "{} = {} is too small: {what}must be >= {min} (limits.min_size)",
                s.field, s.given
            ));
        }
    }
    Ok(())
}

/// The smallest width of a convex polygon (m) and the edge it is measured across: for each
/// edge, how far the farthest vertex lies behind it. The minimum over the edges is the
/// polygon's smallest width in any direction.
fn polygon_thickness(p: &Polygon) -> Option<(usize, Real)> {
    let (v, n) = (p.vertices(), p.normals());
    (0..v.len())
        .map(|i| {
            let depth = v
                .iter()
                .map(|&w| n[i].dot(v[i] - w))
                .fold(0.0 as Real, Real::max);
            (i, depth)
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Checks on a polygon's numbers as sent, before the engine sees them (so that the refusal
/// quotes the `f32` that was sent, whatever the engine's float width): a vertex coordinate
/// beyond +-`max` (which the engine would otherwise report as some other vertex "repeating"
/// it). Non-finite numbers are left to the engine, which names them.
pub(super) fn check_vertices_as_sent(spec: &ShapeSpec, max: f32) -> Result<(), String> {
    match spec {
        // More than MAX_VERTICES is refused first, by shape_from_spec.
        ShapeSpec::Polygon { vertices } if vertices.len() <= MAX_VERTICES => {
            for (i, v) in vertices.iter().enumerate() {
                for (axis, c) in [("x", v.x), ("y", v.y)] {
                    if c.is_finite() && c.abs() > max {
                        return Err(format!(
                            "shape.vertices[{i}].{axis} = {c} is out of range: must be within \
                             +-{max} (limits.max_coordinate)"
                        ));
                    }
                }
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// A spawned body checked against the engine and the daemon's limits, and placed: the
/// definition the tick thread adds. The refusal names the field and the value as sent.
pub(crate) fn spawn_def(b: SpawnBody, limits: &Limits) -> Result<SpawnDef, String> {
    // The shape first (what the engine refuses, then the daemon's limits), then where it
    // goes: the position and angle as given are checked before the centre of mass is
    // computed from them, so a bad one is named as it was sent.
    check_vertices_as_sent(&b.shape, limits.max_coordinate)?;
    let (shape, centroid) = shape_from_spec(&b.shape).map_err(|e| e.to_string())?;
    check_shape_limits(&b.shape, &shape, limits)?;
    let max = limits.max_coordinate;
    check_place(b.position, b.angle, limits)?;
    // A polygon's centre of mass: its centroid, turned with the body (the engine's rule).
    let placed = BodyDef::placed(shape, centroid, vec2(b.position), b.angle as Real)
        .map_err(|e| e.to_string())?;
    let position = placed.position;
    if position.x.abs() > max as Real || position.y.abs() > max as Real {
        return Err(format!(
            "position = [{}, {}] puts the centre of mass at [{}, {}] (position + the centroid \
             of shape.vertices, turned by angle): must be within +-{max} (limits.max_coordinate)",
            b.position.x, b.position.y, position.x, position.y
        ));
    }
    let def = placed
        .with_velocity(vec2(b.velocity))
        .with_angular_velocity(b.angular_velocity as Real)
        .with_density(b.density as Real)
        .with_friction(b.friction as Real)
        .with_restitution(b.restitution as Real);
    // The daemon's friction limit before the engine's own check: the limit a user can act on
    // is the smaller one (config refuses limits.max_friction above the engine's), so a
    // friction above it is always refused in these words, never with the engine's range.
    if b.friction > limits.max_friction {
        return Err(format!(
            "friction = {} is out of range: must be within [0, {}] (limits.max_friction)",
            b.friction, limits.max_friction
        ));
    }
    def.validate().map_err(|e| e.to_string())?;
    if !(limits.min_density..=limits.max_density).contains(&b.density) {
        return Err(format!(
            "density = {} is out of range: must be within {}..={} (limits.min_density, limits.max_density)",
            b.density, limits.min_density, limits.max_density
        ));
    }
    check_motion(b.velocity, b.angular_velocity, limits)?;
    Ok(SpawnDef {
        def,
        name: checked_name(b.name, limits)?,
        colour: b.colour,
    })
}

/// A body's place as sent: its position finite and within `limits.max_coordinate`, its angle
/// finite and within [`MAX_ANGLE`].
pub(super) fn check_place(position: Vector, angle: f32, limits: &Limits) -> Result<(), String> {
    let max = limits.max_coordinate;
    for (field, v) in [("position.x", position.x), ("position.y", position.y)] {
        finite(field, v)?;
        if v.abs() > max {
            return Err(format!(
                "{field} = {v} is out of range: must be within +-{max} (limits.max_coordinate)"
            ));
        }
    }
    check_angle(angle)
}

/// An angle as sent: finite and within [`MAX_ANGLE`] (larger ones only lose precision).
pub(super) fn check_angle(angle: f32) -> Result<(), String> {
    finite("angle", angle)?;
    if angle.abs() > MAX_ANGLE {
        return Err(format!(
            "angle = {angle} is out of range: must be within +-{MAX_ANGLE} rad"
        ));
    }
    Ok(())
}

/// A body's velocity as sent (already known finite): within `limits.max_speed` and
/// `limits.max_angular_speed`.
pub(super) fn check_motion(v: Vector, w: f32, limits: &Limits) -> Result<(), String> {
    let speed = v.x.hypot(v.y);
    if speed > limits.max_speed {
        return Err(format!(
            "|velocity| = {speed} is out of range: must be <= {} m/s (limits.max_speed)",
            limits.max_speed
        ));
    }
    if w.abs() > limits.max_angular_speed {
        return Err(format!(
            "angular_velocity = {w} is out of range: must be within +-{} rad/s (limits.max_angular_speed)",
            limits.max_angular_speed
        ));
    }
    Ok(())
}

/// A name as sent (none: empty), at most `limits.max_name_bytes` long.
pub(super) fn checked_name(name: Option<String>, limits: &Limits) -> Result<String, String> {
    let name = name.unwrap_or_default();
    if name.len() > limits.max_name_bytes as usize {
        return Err(format!(
            "name is {} bytes long, more than limits.max_name_bytes = {}",
            name.len(),
            limits.max_name_bytes
        ));
    }
    Ok(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, CommandKey, Spawn};
    use crate::service::command::Command;
    use crate::service::wire::parse_command;

    fn body() -> SpawnBody {
        SpawnBody::at(
            ShapeSpec::Rect {
                width: 1.0,
                height: 0.5,
            },
            Vector::new(0.0, 3.0),
        )
    }

    fn spawn_err(b: SpawnBody, l: &Limits) -> String {
        let p = encode(&Spawn { bodies: vec![b] }).unwrap();
        parse_command(CommandKey::Spawn, &p, l).unwrap_err()
    }

    /// Why `b` is refused: the error after the `bodies[0]: ` that names it.
    fn refusal(b: SpawnBody, l: &Limits) -> String {
        let e = spawn_err(b, l);
        match e.strip_prefix("bodies[0]: ") {
            Some(reason) => reason.to_owned(),
            None => panic!("not about bodies[0]: {e}"),
        }
    }

    fn spawn_ok(b: SpawnBody) -> SpawnDef {
        let p = encode(&Spawn { bodies: vec![b] }).unwrap();
        match parse_command(CommandKey::Spawn, &p, &Limits::default()) {
            Ok(Command::Spawn(mut v)) => v.remove(0),
            other => panic!("{other:?}"),
        }
    }

    fn with_shape(shape: ShapeSpec) -> SpawnBody {
        SpawnBody { shape, ..body() }
    }

    fn polygon(points: &[(f32, f32)]) -> ShapeSpec {
        ShapeSpec::Polygon {
            vertices: points.iter().map(|&(x, y)| Vector::new(x, y)).collect(),
        }
    }

    #[test]
    fn a_bad_angle_is_named_as_the_angle_not_as_the_position_it_would_give() {
        let l = Limits::default();
        for shape in [body().shape, polygon(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])] {
            let mut b = with_shape(shape);
            b.angle = f32::NAN;
            let e = spawn_err(b.clone(), &l);
            assert_eq!(e, "bodies[0]: angle must be a finite number, got NaN");
            b.angle = f32::INFINITY;
            let e = spawn_err(b, &l);
            assert_eq!(e, "bodies[0]: angle must be a finite number, got inf");
        }
        // a huge but finite position is named as given, not as an overflowed centre of mass
        let mut b = with_shape(polygon(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]));
        b.position.x = 3.4e38;
        let e = refusal(b, &l);
        let want = "position.x = 340000000000000000000000000000000000000 is out of range";
        assert!(e.starts_with(want), "{e}");
    }

    #[test]
    fn circle_and_capsule_sizes_are_refused_naming_the_field_and_the_value_given() {
        let l = Limits::default();
        let circle = |radius| with_shape(ShapeSpec::Circle { radius });
        let capsule = |length, radius| with_shape(ShapeSpec::Capsule { length, radius });
        for (b, want) in [
            (circle(f32::NAN), "shape.radius must be a finite number, got NaN"),
            (circle(f32::INFINITY), "shape.radius must be a finite number, got inf"),
            (circle(0.0), "shape.radius = 0 is out of range: must be > 0"),
            (circle(-0.0), "shape.radius = -0 is out of range: must be > 0"),
            (circle(-1.0), "shape.radius = -1 is out of range: must be > 0"),
            (
                circle(0.004),
                "shape.radius = 0.004 is too small: the diameter 0.008 must be >= 0.01 (limits.min_size)",
            ),
            (
                circle(600.0),
                "shape.radius = 600 is out of range: the diameter 1200 must be <= 1000 (limits.max_coordinate)",
            ),
            (
                circle(3.0e38),
                "shape.radius = 300000000000000000000000000000000000000 is out of range: the diameter inf must be <= 1000",
            ),
            (capsule(1.0, f32::NAN), "shape.radius must be a finite number, got NaN"),
            (capsule(f32::NAN, 0.1), "shape.length must be a finite number, got NaN"),
            (capsule(1.0, 0.0), "shape.radius = 0 is out of range: must be > 0"),
            (
                capsule(0.8, 0.5),
                "shape.length = 0.8 must be more than twice shape.radius = 0.5",
            ),
            // exactly twice the radius: no straight part, refused
            (
                capsule(1.0, 0.5),
                "shape.length = 1 must be more than twice shape.radius = 0.5",
            ),
            (
                capsule(2000.0, 0.5),
                "shape.length = 2000 is out of range: must be <= 1000 (limits.max_coordinate)",
            ),
            (
                capsule(0.5, 0.004),
                "shape.radius = 0.004 is too small: the thickness (2 x radius) 0.008 must be >= 0.01",
            ),
            (
                with_shape(ShapeSpec::Rect { width: 0.005, height: 1.0 }),
                "shape.width = 0.005 is too small: must be >= 0.01 (limits.min_size)",
            ),
            (
                with_shape(ShapeSpec::Rect { width: 1.0, height: 1500.0 }),
                "shape.height = 1500 is out of range: must be <= 1000 (limits.max_coordinate)",
            ),
        ] {
            let shape = b.shape.clone();
            let e = refusal(b, &l);
            assert!(e.contains(want), "{shape:?}: {e}");
        }
        // the smallest and largest accepted
        spawn_ok(circle(0.005));
        spawn_ok(circle(500.0));
        spawn_ok(capsule(0.0101, 0.005));
    }

    #[test]
    fn bad_polygons_are_refused_naming_the_vertex_and_the_value() {
        let l = Limits::default();
        let tri = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
        let octagon = |n: usize| -> Vec<(f32, f32)> {
            (0..n)
                .map(|k| {
                    let a = k as f32 * std::f32::consts::TAU / n as f32;
                    (a.cos(), a.sin())
                })
                .collect()
        };
        let mut nan = tri;
        nan[1].0 = f32::NAN;
        let mut inf = tri;
        inf[2].1 = f32::NEG_INFINITY;
        let mut cw = tri;
        cw.swap(1, 2);
        for (shape, want) in [
            (polygon(&octagon(9)), "shape.vertices must hold 3 to 8 points, got 9"),
            (polygon(&tri[..2]), "shape.vertices must hold 3 to 8 points, got 2"),
            (polygon(&[]), "shape.vertices must hold 3 to 8 points, got 0"),
            (polygon(&nan), "shape.vertices[1] must be finite, got [NaN, 0]"),
            (polygon(&inf), "shape.vertices[2] must be finite, got [0, -inf]"),
            (polygon(&cw), "shape.vertices[1] = [0, 1] turns clockwise there"),
            (
                polygon(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 1.0)]),
                "shape.vertices[1] = [1, 0] is collinear",
            ),
            (
                polygon(&[(5000.0, 0.0), (5001.0, 0.0), (5000.0, 1.0)]),
                "shape.vertices[0].x = 5000 is out of range: must be within +-1000 (limits.max_coordinate)",
            ),
            // near the float range: named as itself, not as a vertex "repeating" it
            (
                polygon(&[(0.0, 0.0), (3.4e38, 0.0), (0.0, 1.0)]),
                "shape.vertices[1].x = 340000000000000000000000000000000000000 is out of range",
            ),
            (
                polygon(&[(-900.0, 0.0), (900.0, 0.0), (0.0, 1.0)]),
                "shape.vertices span 1800 m along x: must be <= 1000 (limits.max_coordinate)",
            ),
            // a sliver 1 m long and about 7 mm thick, drawn diagonally: its bounding box is
            // 1 x 1 m, yet it is thinner than limits.min_size
            (
                polygon(&[(0.0, 0.0), (1.0, 1.0), (0.99, 1.0)]),
                "shape.vertices make a polygon 0.0070",
            ),
        ] {
            let e = refusal(with_shape(shape.clone()), &l);
            assert!(e.contains(want), "{shape:?}: {e}");
        }
        // vertices within the limits, but drawn so far from position that the centre of
        // mass would be at x = 1500
        let mut b = with_shape(polygon(&[(900.0, 0.0), (901.0, 0.0), (900.0, 1.0)]));
        b.position = Vector::new(600.0, 0.0);
        let e = refusal(b, &l);
        assert!(
            e.starts_with("position = [600, 0] puts the centre of mass at [1500.33"),
            "{e}"
        );
        assert!(e.contains("limits.max_coordinate"), "{e}");
    }

    #[test]
    fn ten_thousand_vertices_are_refused_by_size_or_count_without_panicking() {
        let many: Vec<(f32, f32)> = (0..10_000)
            .map(|k| {
                let a = k as f32 * std::f32::consts::TAU / 10_000.0;
                (a.cos(), a.sin())
            })
            .collect();
        let p = encode(&Spawn {
            bodies: vec![with_shape(polygon(&many))],
        })
        .unwrap();
        // version, count, None, variant, varint(10000) = 2 bytes, 80000 bytes of vertices,
        // then position 8, angle 4, velocity 8, spin 4, density/friction/restitution 12, colour 3
        assert_eq!(p.len(), 4 + 2 + 80_000 + 39);
        let mut l = Limits::default();
        let e = parse_command(CommandKey::Spawn, &p, &l).unwrap_err();
        assert_eq!(
            e,
            "payload of 80045 bytes is larger than limits.max_payload_bytes = 65536"
        );
        l.max_payload_bytes = 1 << 20;
        let e = parse_command(CommandKey::Spawn, &p, &l).unwrap_err();
        assert_eq!(
            e,
            "bodies[0]: shape.vertices must hold 3 to 8 points, got 10000"
        );
    }

    #[test]
    fn an_off_centre_polygon_goes_to_position_plus_its_turned_centroid() {
        // Right triangle with legs 3 (x) and 1.5 (y) drawn from (1, 0): centroid (2, 0.5).
        let mut b = with_shape(polygon(&[(1.0, 0.0), (4.0, 0.0), (1.0, 1.5)]));
        b.position = Vector::new(-2.0, 5.0);
        b.angle = 0.5;
        let d = spawn_ok(b).def;
        let (s, c) = (0.5f64.sin(), 0.5f64.cos());
        let want = (-2.0 + c * 2.0 - s * 0.5, 5.0 + s * 2.0 + c * 0.5);
        assert!(
            (d.position.x as f64 - want.0).abs() < 1e-5
                && (d.position.y as f64 - want.1).abs() < 1e-5,
            "{:?} vs {want:?}",
            d.position
        );
        let Shape::Polygon(p) = &d.shape else {
            panic!("{:?}", d.shape)
        };
        let v: Vec<(f64, f64)> = p
            .vertices()
            .iter()
            .map(|v| (v.x as f64, v.y as f64))
            .collect();
        for (got, want) in v.iter().zip([(-1.0, -0.5), (2.0, -0.5), (-1.0, 1.0)]) {
            assert!(
                (got.0 - want.0).abs() < 1e-6 && (got.1 - want.1).abs() < 1e-6,
                "{v:?}"
            );
        }
        assert!((d.shape.area() as f64 - 2.25).abs() < 1e-5);
    }

    #[test]
    fn a_polygon_drawn_far_from_position_is_centred_well_enough_to_be_recorded() {
        // A 5 cm pentagon drawn around (999, 999) with the body origin at (0, 0): one
        // centring pass leaves a residue of about 1e-5 m (the float spacing near 1000 is
        // 6e-5), which Polygon::centred (journal, checkpoint) would refuse.
        for k in 0..50 {
            let a0 = k as f32 * 0.1;
            let pts: Vec<(f32, f32)> = (0..5)
                .map(|i| {
                    let a = a0 + i as f32 * 1.2566;
                    (999.0 + 0.05 * a.cos(), 999.0 + 0.05 * a.sin())
                })
                .collect();
            let mut b = with_shape(polygon(&pts));
            b.position = Vector::new(0.0, 0.0);
            let d = spawn_ok(b);
            let Shape::Polygon(p) = &d.def.shape else {
                unreachable!()
            };
            Polygon::centred(p.vertices()).unwrap();
            assert!((d.def.position - Vec2::new(999.0, 999.0)).length() < 1e-3);
            // and the journal's form reads back exactly
            let bytes = postcard::to_allocvec(&d).unwrap();
            assert_eq!(postcard::from_bytes::<SpawnDef>(&bytes).unwrap(), d);
        }
    }
}
