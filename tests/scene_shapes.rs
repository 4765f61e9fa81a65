//! Circles, capsules and polygons in scene files: sizes, mass, a polygon recentred on its
//! centroid with the body moved there, and refusals that name the vertex or the field.

#![cfg(feature = "scene")]

mod common;

use common::scene::*;

/// The refusal of a polygon body named `name` with `vertices` (TOML, e.g. `[[0, 0], [1, 0]]`).
fn polygon_refusal(name: &str, vertices: &str) -> String {
    refusal(
        name,
        &format!("{{ type = \"polygon\", vertices = {vertices} }}"),
    )
}

/// `message` starts with `start`.
fn assert_starts(message: &str, start: &str) {
    assert!(message.starts_with(start), "{message}");
}
use tiltbox::physics::{vec2, MassSpec, Shape, World};
use tiltbox::scene::{Scene, SceneError};

#[test]
fn circle_is_read_and_its_mass_is_density_times_pi_r_squared() {
    let b = parse_body(&shaped(
        "ball",
        "{ type = \"circle\", radius = 0.5 }",
        "position = [1, 2]\ndensity = 3",
    ))
    .unwrap();
    assert_eq!(b.def.shape, Shape::Circle { radius: 0.5 });
    assert_eq!(b.def.position, vec2(1.0, 2.0));
    let mut world = World::default();
    let id = world.add_body(&b.def).unwrap();
    let expected = std::f64::consts::PI * 0.25 * 3.0;
    let mass = world.body(id).unwrap().mass() as f64;
    assert!((mass - expected).abs() < 1e-5, "{mass} vs {expected}");
}

#[test]
fn capsule_length_is_end_to_end_along_x() {
    let b = parse_body(&shaped(
        "pill",
        "{ type = \"capsule\", length = 3, radius = 0.5 }",
        "position = [0, 2]\nangle = 0.25\nmass = 2",
    ))
    .unwrap();
    assert_eq!(b.def.shape, Shape::capsule(3.0, 0.5));
    assert_eq!(
        b.def.shape,
        Shape::Capsule {
            half_length: 1.0,
            radius: 0.5
        }
    );
    // Capsules and circles sit on their position: no centroid shift, whatever the angle.
    assert_eq!(b.def.position, vec2(0.0, 2.0));
    assert_eq!(b.def.angle, 0.25);
    assert_eq!(b.def.mass, MassSpec::Mass(2.0));
}

#[test]
fn polygon_is_recentred_on_its_centroid_and_the_body_moved_there() {
    // Right triangle (0,0), (3,0), (0,2): centroid (1, 2/3), area 3.
    let b = parse_body(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [3, 0], [0, 2]] }",
        "position = [10, 0]\ndensity = 2",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(11.0, 2.0 / 3.0)),
        "{:?}",
        b.def.position
    );
    let Shape::Polygon(p) = &b.def.shape else {
        panic!("expected a polygon, got {:?}", b.def.shape)
    };
    let expected = [
        vec2(-1.0, -2.0 / 3.0),
        vec2(2.0, -2.0 / 3.0),
        vec2(-1.0, 4.0 / 3.0),
    ];
    assert_eq!(p.vertices().len(), 3);
    for (v, e) in p.vertices().iter().zip(expected) {
        assert!(close(*v, e), "{v:?} vs {e:?}");
    }
    // The same polygon as the engine builds from those points.
    let (reference, _) =
        tiltbox::physics::Polygon::new(&[vec2(0.0, 0.0), vec2(3.0, 0.0), vec2(0.0, 2.0)]).unwrap();
    assert_eq!(b.def.shape, Shape::from(reference));
    // mass = density x area = 2 x 3.
    let mut world = World::default();
    let id = world.add_body(&b.def).unwrap();
    assert!((world.body(id).unwrap().mass() - 6.0).abs() < 1e-4);

    // Turned a quarter turn counter-clockwise, the centroid turns with the body:
    // position + R(pi/2) (1, 2/3) = (10 - 2/3, 1).
    let b = parse_body(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [3, 0], [0, 2]] }",
        "position = [10, 0]\nangle = 1.5707963267948966\ndensity = 2",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(10.0 - 2.0 / 3.0, 1.0)),
        "{:?}",
        b.def.position
    );
    // A polygon centred on its position stays there.
    let b = parse_body(&shaped(
        "square",
        "{ type = \"polygon\", vertices = [[-1, -1], [1, -1], [1, 1], [-1, 1]] }",
        "position = [4, 5]\nangle = 0.7\ndensity = 1",
    ))
    .unwrap();
    assert!(
        close(b.def.position, vec2(4.0, 5.0)),
        "{:?}",
        b.def.position
    );
}

#[test]
fn static_polygon_builds_into_a_world_where_its_vertices_were_given() {
    let scene = Scene::from_toml_str(&shaped(
        "ramp",
        "{ type = \"polygon\", vertices = [[0, 0], [4, 0], [4, 1]] }",
        "position = [-2, 0]\nstatic = true",
    ))
    .unwrap();
    let (world, ids) = scene.build_world().unwrap();
    let body = world.body(ids[0]).unwrap();
    assert!(body.is_static());
    // World-space vertices are the ones written plus position.
    let aabb = body.shape().aabb(body.transform());
    assert!(close(aabb.min, vec2(-2.0, 0.0)), "{aabb:?}");
    assert!(close(aabb.max, vec2(2.0, 1.0)), "{aabb:?}");
}

#[test]
fn clockwise_polygon_names_the_vertex_and_its_value() {
    let e = Scene::from_toml_str(&with_ground(&shaped(
        "wedge",
        "{ type = \"polygon\", vertices = [[0, 0], [0, 1], [1, 0.5]] }",
        "position = [0, 1]\ndensity = 1",
    )))
    .unwrap_err();
    let s = e.to_string();
    assert_starts(
        &s,
        r#"body "wedge" (#1): shape.vertices[1] = [0, 1]: turns clockwise"#,
    );
    assert!(s.contains("counter-clockwise"), "{s}");
    match e {
        SceneError::Invalid { field, value, .. } => {
            assert_eq!(field, "shape.vertices[1]");
            assert_eq!(value.as_deref(), Some("[0, 1]"));
        }
        other => panic!("expected Invalid, got {other:?}"),
    }
    // A dent (a reflex corner) in an otherwise counter-clockwise list.
    let s = polygon_refusal("dent", "[[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]]");
    assert_starts(
        &s,
        r#"body "dent" (#1): shape.vertices[2] = [1, 0.5]: turns clockwise"#,
    );
}

#[test]
fn polygon_vertex_count_must_be_3_to_8() {
    let s = polygon_refusal("stick", "[[0, 0], [1, 0]]");
    assert_starts(
        &s,
        r#"body "stick" (#1): shape.vertices: must hold 3 to 8 points, got 2"#,
    );
    let nine: Vec<String> = (0..9)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 9.0;
            format!("[{}, {}]", a.cos(), a.sin())
        })
        .collect();
    let s = refusal(
        "nonagon",
        &format!("{{ type = \"polygon\", vertices = [{}] }}", nine.join(", ")),
    );
    assert_starts(
        &s,
        r#"body "nonagon" (#1): shape.vertices: must hold 3 to 8 points, got 9"#,
    );
    // A vertex that is not a pair is named with its index.
    let s = polygon_refusal("odd", "[[0, 0], [1, 0, 2], [0, 1]]");
    assert_eq!(
        s,
        r#"body "odd" (#1): shape.vertices[1] = [1, 0, 2]: must be a pair [x, y] (metres)"#
    );
}

#[test]
fn nan_vertex_is_refused_naming_the_vertex() {
    let s = polygon_refusal("bad", "[[0, 0], [1, nan], [0, 1]]");
    assert_eq!(
        s,
        r#"body "bad" (#1): shape.vertices[1] = [1, NaN]: coordinates must be finite numbers"#
    );
    let s = polygon_refusal("far", "[[0, 0], [inf, 0], [0, 1]]");
    assert!(s.contains("shape.vertices[1] = [inf, 0]"), "{s}");
}

#[test]
fn polygon_position_and_angle_errors_show_the_value_written() {
    let s = parse_body(&shaped(
        "tri",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0], [0, 1]] }",
        "position = [0, nan]\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "tri" (#1): position.y = NaN: must be a finite number"#
    );
    let s = parse_body(&shaped(
        "tri",
        "{ type = \"polygon\", vertices = [[0, 0], [1, 0], [0, 1]] }",
        "position = [0, 1]\nangle = inf\ndensity = 1",
    ))
    .unwrap_err();
    assert_eq!(
        s,
        r#"body "tri" (#1): angle = inf: must be a finite number"#
    );
}

#[test]
fn capsule_no_longer_than_its_ends_is_refused() {
    let s = refusal("pill", "{ type = \"capsule\", length = 1, radius = 0.5 }");
    assert_starts(
        &s,
        r#"body "pill" (#1): shape.length = 1: must be more than twice shape.radius = 0.5"#,
    );
    let s = refusal("pill", "{ type = \"capsule\", length = 0.4, radius = 0.5 }");
    assert!(s.contains("shape.length = 0.4"), "{s}");
    let s = refusal("pill", "{ type = \"capsule\", length = -2, radius = 0.5 }");
    assert_eq!(s, r#"body "pill" (#1): shape.length = -2: must be > 0"#);
    // The fields are the capsule's own: a rect's width is unknown there.
    let s = refusal("pill", "{ type = \"capsule\", width = 2, radius = 0.5 }");
    assert!(s.contains("width") && s.contains("length"), "{s}");
}

#[test]
fn negative_or_nan_radius_is_refused() {
    let s = refusal("ball", "{ type = \"circle\", radius = -0.5 }");
    assert_eq!(s, r#"body "ball" (#1): shape.radius = -0.5: must be > 0"#);
    let s = refusal("ball", "{ type = \"circle\", radius = nan }");
    assert_eq!(
        s,
        r#"body "ball" (#1): shape.radius = NaN: must be a finite number"#
    );
    let s = refusal("pill", "{ type = \"capsule\", length = 2, radius = -0.1 }");
    assert_eq!(s, r#"body "pill" (#1): shape.radius = -0.1: must be > 0"#);
}

#[test]
fn unknown_shape_type_lists_the_known_ones() {
    let s = refusal("blob", "{ type = \"ellipse\", radius = 1 }");
    assert_starts(&s, r#"body "blob" (#1) at line 10: shape"#);
    for kind in ["rect", "circle", "capsule", "polygon"] {
        assert!(s.contains(kind), "{s}");
    }
}
