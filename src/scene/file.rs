//! The TOML schema (what serde reads) and its translation into validated [`Scene`] bodies.
//!
//! A valid document is read in one typed pass (linear in its size). A document that fails
//! that pass is read again in two layers so that every error can say which body it is about:
//! each `[[body]]`, `[[stack]]` and `[[pyramid]]` table kept as a loose, spanned TOML table,
//! then read into its typed entry on its own, in document order, with its name, index and
//! line at hand for the message.

use super::error::{body_label, describe, LineCounter};
use super::joints::{JointEntry, RagdollEntry, RopeEntry};
use super::{Colour, Scene, SceneBody, SceneError, MAX_BODIES};
use crate::physics::error::{finite, non_negative, positive, unit_interval};
use crate::physics::segment::chain;
use crate::physics::{
    BodyDef, Filter, MassSpec, PartDef, PhysicsError, Polygon, Real, Rot, Segment, Settings, Shape,
    ShapeFlags, Vec2,
};
use serde::Deserialize;
use toml::{Spanned, Table};

/// Default friction coefficient of bodies and generated boxes (the engine's default).
const DEFAULT_FRICTION: Real = 0.6;
/// Default density of generated boxes, kg/m^2.
const DEFAULT_DENSITY: Real = 1.0;

fn default_friction() -> Real {
    DEFAULT_FRICTION
}
fn default_density() -> Real {
    DEFAULT_DENSITY
}
fn default_awake() -> bool {
    true
}
fn default_gravity() -> [Real; 2] {
    [0.0, -9.81]
}
fn default_name() -> String {
    "untitled".to_owned()
}

/// The top level of a scene file, its entry tables read as `B`, `S` and `P`: typed entries
/// in one pass (quick), or loose tables read one by one (to name the table in an error).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile<B, S, P> {
    #[serde(default = "default_name")]
    name: String,
    #[serde(default = "default_gravity")]
    gravity: [Real; 2],
    #[serde(default)]
    settings: Settings,
    #[serde(default = "Vec::new")]
    body: Vec<Spanned<B>>,
    #[serde(default = "Vec::new")]
    stack: Vec<Spanned<S>>,
    #[serde(default = "Vec::new")]
    pyramid: Vec<Spanned<P>>,
    #[serde(default = "Vec::new")]
    rope: Vec<RopeEntry>,
    #[serde(default = "Vec::new")]
    ragdoll: Vec<RagdollEntry>,
    #[serde(default = "Vec::new")]
    joint: Vec<JointEntry>,
}

/// What a scene file holds: name, gravity, settings, its entry tables in file order, its
/// ropes and ragdolls, and its joints.
type Split = (
    String,
    [Real; 2],
    Settings,
    Vec<Placed>,
    (Vec<RopeEntry>, Vec<RagdollEntry>),
    Vec<JointEntry>,
);

/// How a scene file's body, stack and pyramid tables become [`Entry`]s.
type Wraps<B, S, P> = (fn(B) -> Entry, fn(S) -> Entry, fn(P) -> Entry);

impl<B, S, P> SceneFile<B, S, P> {
    /// The file's parts, its body, stack and pyramid tables each made an [`Entry`] by `wrap`.
    fn split(self, wrap: Wraps<B, S, P>) -> Split {
        let mut entries =
            Vec::with_capacity(self.body.len() + self.stack.len() + self.pyramid.len());
        push_all(&mut entries, Kind::Body, self.body, wrap.0);
        push_all(&mut entries, Kind::Stack, self.stack, wrap.1);
        push_all(&mut entries, Kind::Pyramid, self.pyramid, wrap.2);
        let generators = (self.rope, self.ragdoll);
        (
            self.name,
            self.gravity,
            self.settings,
            entries,
            generators,
            self.joint,
        )
    }
}

/// A scene file whose entry tables are typed.
type TypedFile = SceneFile<BodyEntry, StackEntry, PyramidEntry>;
/// A scene file whose entry tables are kept as loose TOML tables.
type LooseFile = SceneFile<Table, Table, Table>;

/// One entry table: read, or still loose (read in its turn, to name it in an error).
enum Entry {
    Body(BodyEntry),
    Stack(StackEntry),
    Pyramid(PyramidEntry),
    Loose(Table),
}

/// The `shape` inline table of a `[[body]]`, tagged by `type`; every length in metres.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum ShapeEntry {
    /// `{ type = "rect", width = W, height = H }`: a W x H rectangle centred on `position`.
    Rect { width: Real, height: Real },
    /// `{ type = "circle", radius = R }`: a disc centred on `position`.
    Circle { radius: Real },
    /// `{ type = "capsule", length = L, radius = R }`: a stadium L long end to end along the
    /// body's x axis and 2 R thick, centred on `position`; L > 2 R.
    Capsule { length: Real, radius: Real },
    /// `{ type = "polygon", vertices = [[x, y], ...] }`: 3 to 8 points relative to `position`
    /// in the body's (turned) frame, counter-clockwise, strictly convex. The centre of mass
    /// goes to their centroid.
    /// (Read as lists of any length so that a vertex that is not a pair is reported with its
    /// index, not as toml's bare "invalid length".)
    Polygon { vertices: Vec<Vec<Real>> },
    /// `{ type = "segment", a = [x, y], b = [x, y], radius = R, one_sided = false }`: the line
    /// from a to b (relative to `position`, in the body's turned frame) grown by R (default
    /// 0). Static (the default for it) or kinematic only. One-sided pushes only to the left
    /// of a -> b.
    Segment {
        a: [Real; 2],
        b: [Real; 2],
        #[serde(default)]
        radius: Real,
        #[serde(default)]
        one_sided: bool,
    },
    /// `{ type = "chain", points = [[x, y], ...], loop = false, one_sided = false }`: a
    /// polyline relative to `position` (turned by `angle`), static only, cut into one body per
    /// piece (named `NAME[i]`) whose neighbours keep bodies from catching on its joints.
    /// `loop = true` joins the last point to the first (do not repeat it). One-sided pieces
    /// push only to the left of the walk: list a floor left to right, a container
    /// counter-clockwise.
    Chain {
        points: Vec<Vec<Real>>,
        #[serde(default, rename = "loop")]
        closed: bool,
        #[serde(default)]
        one_sided: bool,
    },
}

/// Read `[x, y]` pairs as written, refusing anything else with the index of the bad one
/// (`field` is e.g. `shape.vertices`).
fn read_points(at: &str, field: &str, list: &[Vec<Real>]) -> Result<Vec<Vec2>, SceneError> {
    let mut points = Vec::with_capacity(list.len());
    for (i, v) in list.iter().enumerate() {
        let field = || format!("{field}[{i}]");
        let written = || {
            let coords: Vec<String> = v.iter().map(Real::to_string).collect();
            Some(format!("[{}]", coords.join(", ")))
        };
        let &[x, y] = v.as_slice() else {
            return Err(SceneError::invalid(
                at,
                field(),
                written(),
                "must be a pair [x, y] (metres)",
            ));
        };
        if !(x.is_finite() && y.is_finite()) {
            return Err(SceneError::invalid(
                at,
                field(),
                written(),
                "coordinates must be finite numbers",
            ));
        }
        points.push(Vec2::new(x, y));
    }
    Ok(points)
}

impl ShapeEntry {
    /// The engine shape, and where its centre of mass sits relative to the body's `position`
    /// in the body's frame (m): the centroid of a polygon's vertices, zero for the others.
    /// Built by the engine's own constructors, as the daemon builds spawned shapes.
    fn to_shape(&self, at: &str) -> Result<(Shape, Vec2), SceneError> {
        let shape = match *self {
            // Sizes checked below by Shape::validate, which names the field and the value.
            ShapeEntry::Rect { width, height } => Shape::rect(width, height),
            ShapeEntry::Circle { radius } => Shape::circle(radius),
            ShapeEntry::Capsule { length, radius } => {
                let capsule =
                    Shape::try_capsule(length, radius).map_err(|e| SceneError::physics(at, e))?;
                return Ok((capsule, Vec2::ZERO));
            }
            ShapeEntry::Polygon { ref vertices } => {
                let points = read_points(at, "shape.vertices", vertices)?;
                let (polygon, centroid) =
                    Polygon::new(&points).map_err(|e| SceneError::physics(at, e))?;
                return Ok((Shape::from(polygon), centroid));
            }
            ShapeEntry::Segment {
                a,
                b,
                radius,
                one_sided,
            } => {
                let mut segment =
                    Segment::new(Vec2::new(a[0], a[1]), Vec2::new(b[0], b[1]), radius);
                segment.one_sided = one_sided;
                Shape::Segment(Box::new(segment))
            }
            // Expanded by `BodyEntry::into_bodies`, never asked for one shape.
            ShapeEntry::Chain { .. } => {
                return Err(SceneError::invalid(
                    at,
                    "shape.type",
                    Some("\"chain\"".into()),
                    "a chain is many bodies",
                ))
            }
        };
        shape.validate().map_err(|e| SceneError::physics(at, e))?;
        Ok((shape, Vec2::ZERO))
    }
}

/// Declares an entry table (`[[body]]`, `[[stack]]`, `[[pyramid]]`): the fields given, then
/// the material every entry ends with, `friction`, `restitution` and `colour` (or `color`).
/// (serde lists the fields in this order when it refuses an unknown one.)
macro_rules! entry_table {
    ($(#[$doc:meta])* struct $entry:ident { $($fields:tt)* }) => {
        $(#[$doc])*
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $entry {
            $($fields)*
            #[serde(default = "default_friction")]
            friction: Real,
            #[serde(default)]
            restitution: Real,
            #[serde(alias = "color")]
            colour: Option<String>,
        }
    };
}

entry_table! {
    /// One `[[body]]` table.
    struct BodyEntry {
        name: Option<String>,
        shape: ShapeEntry,
        position: [Real; 2],
        #[serde(default)]
        angle: Real,
        #[serde(default)]
        velocity: [Real; 2],
        #[serde(default)]
        angular_velocity: Real,
        density: Option<Real>,
        mass: Option<Real>,
        #[serde(default, rename = "static")]
        is_static: bool,
        #[serde(default)]
        kinematic: bool,
        filter: Option<FilterEntry>,
        #[serde(default)]
        parts: Vec<PartEntry>,
        #[serde(default)]
        sensor: bool,
        #[serde(default)]
        contact_events: bool,
        #[serde(default)]
        hit_events: bool,
        #[serde(default = "default_awake")]
        awake: bool,
    }
}

/// A shape's flags from its `sensor`, `contact_events` and `hit_events` keys.
fn shape_flags(sensor: bool, contact_events: bool, hit_events: bool) -> ShapeFlags {
    ShapeFlags {
        contact_events,
        hit_events,
        sensor,
    }
}

/// One of a `[[body]]`'s further shapes: `{ shape = {...}, offset = [x, y], angle = A }`
/// placed from the body's `position` in its (turned) frame, with `density`, `friction`,
/// `restitution` and `filter` the body's unless given.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PartEntry {
    shape: ShapeEntry,
    #[serde(default)]
    offset: [Real; 2],
    #[serde(default)]
    angle: Real,
    density: Option<Real>,
    friction: Option<Real>,
    restitution: Option<Real>,
    filter: Option<FilterEntry>,
    #[serde(default)]
    sensor: bool,
    #[serde(default)]
    contact_events: bool,
    #[serde(default)]
    hit_events: bool,
}

/// A `filter` inline table: `category` and `mask` as integers (bits 0 to 62) or hex strings
/// (`"0x..."`, all 64 bits; `mask = "all"`), `group` an integer.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilterEntry {
    category: Option<Bits>,
    mask: Option<Bits>,
    #[serde(default)]
    group: i32,
}

/// A 64-bit set as TOML can write it: an integer (TOML's are signed 64-bit) or a string.
#[derive(Deserialize)]
#[serde(untagged)]
enum Bits {
    Integer(i64),
    Text(String),
}

impl FilterEntry {
    /// The engine's filter, or an error naming `filter.category` or `filter.mask`.
    fn to_filter(&self, at: &str) -> Result<Filter, SceneError> {
        let bits = |field: &str, bits: &Option<Bits>, default: u64| match bits {
            None => Ok(default),
            Some(Bits::Integer(n)) if *n >= 0 => Ok(*n as u64),
            Some(Bits::Text(t)) if t == "all" => Ok(u64::MAX),
            Some(Bits::Text(t)) => t
                .strip_prefix("0x")
                .and_then(|hex| u64::from_str_radix(&hex.replace('_', ""), 16).ok())
                .ok_or_else(|| bad_bits(at, field, format!("{t:?}"))),
            Some(Bits::Integer(n)) => Err(bad_bits(at, field, n.to_string())),
        };
        Ok(Filter {
            category: bits("filter.category", &self.category, Filter::DEFAULT.category)?,
            mask: bits("filter.mask", &self.mask, Filter::DEFAULT.mask)?,
            group: self.group,
        })
    }
}

fn bad_bits(at: &str, field: &str, value: String) -> SceneError {
    let message = "must be an integer >= 0, a hex string \"0x...\" (64 bits) or \"all\"";
    SceneError::invalid(at, field, Some(value), message)
}

/// Declares the entry table of a box generator: `name`, its count field, then the fields
/// [`Generated`] reads, with the generator's own spacing fields (if any) after `base_y`. Also
/// gives the entry its [`Generated`] view.
macro_rules! generator_entry {
    (
        $(#[$doc:meta])*
        $entry:ident { $count:ident; $($(#[$attr:meta])* $spacing:ident: $ty:ty),* }
    ) => {
        entry_table! {
            $(#[$doc])*
            struct $entry {
                name: Option<String>,
                $count: u32,
                size: Real,
                #[serde(default)]
                x: Real,
                #[serde(default)]
                base_y: Real,
                $($(#[$attr])* $spacing: $ty,)*
                #[serde(default = "default_density")]
                density: Real,
                #[serde(default = "default_awake")]
                awake: bool,
            }
        }

        impl $entry {
            /// The fields every generator has, as written.
            fn generated(&self) -> Generated<'_> {
                Generated {
                    size: self.size,
                    x: self.x,
                    base_y: self.base_y,
                    density: self.density,
                    friction: self.friction,
                    restitution: self.restitution,
                    colour: self.colour.as_deref(),
                    awake: self.awake,
                }
            }
        }
    };
}

generator_entry! {
    /// One `[[stack]]` table: `count` boxes of side `size`, bottom one resting on y = `base_y`,
    /// `gap` apart.
    StackEntry { count; #[serde(default)] gap: Real }
}

generator_entry! {
    /// One `[[pyramid]]` table: `base` boxes of side `size` in the bottom row, one fewer per row.
    PyramidEntry { base; }
}

/// Which array a table came from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Body,
    Stack,
    Pyramid,
}

impl Kind {
    fn table_name(self) -> &'static str {
        match self {
            Kind::Body => "body",
            Kind::Stack => "stack",
            Kind::Pyramid => "pyramid",
        }
    }
}

/// How an error names a generator: `stack "NAME" ([[stack]] #K)`, or `[[stack]] #K`.
fn generator_label(kind: Kind, name: Option<&str>, k: usize) -> String {
    let table = kind.table_name();
    match name {
        Some(name) => format!("{table} {name:?} ([[{table}]] #{k})"),
        None => format!("[[{table}]] #{k}"),
    }
}

/// Parse and validate a scene document.
///
/// The document is first read with every entry table typed, in one pass: a file of 100,000
/// bodies loads in well under a second. Only if that fails is it read again with each entry
/// table kept loose and read in its turn, so that the error names the table, its index and
/// its line, after any refusal of an earlier table, as the file is read top to bottom.
pub(crate) fn parse(text: &str) -> Result<Scene, SceneError> {
    let (name, gravity, settings, mut entries, (ropes, ragdolls), joint_entries) =
        match toml::from_str::<TypedFile>(text) {
            Ok(f) => f.split((Entry::Body, Entry::Stack, Entry::Pyramid)),
            Err(_) => {
                let f: LooseFile = toml::from_str(text).map_err(|e| SceneError::Parse {
                    entry: None,
                    message: e.to_string().trim_end().to_owned(),
                })?;
                f.split((Entry::Loose, Entry::Loose, Entry::Loose))
            }
        };

    let gravity = Vec2::new(gravity[0], gravity[1]);
    check("scene", finite("gravity.x", gravity.x))?;
    check("scene", finite("gravity.y", gravity.y))?;
    settings
        .validate()
        .map_err(|e| SceneError::physics("[settings]", e))?;

    // Document order (by where each table starts), so bodies keep the order in which the
    // file lists them whatever kind of table they come from.
    entries.sort_by_key(|&(start, kind, k, _)| (start, kind as u8, k));
    let mut bodies: Vec<SceneBody> = Vec::with_capacity(entries.len());
    let mut lines = LineCounter::new(text);
    for (start, kind, k, entry) in entries {
        let entry = match entry {
            Entry::Loose(table) => read_loose(kind, k, table, lines.line_of(start), &bodies)?,
            entry => entry,
        };
        match entry {
            Entry::Body(entry) => {
                if let ShapeEntry::Chain { .. } = entry.shape {
                    let pieces = entry.into_chain(bodies.len())?;
                    reserve(&bodies, pieces.len() as u64)?;
                    bodies.extend(pieces);
                } else {
                    reserve(&bodies, 1)?;
                    let index = bodies.len();
                    bodies.push(entry.into_body(index)?);
                }
            }
            Entry::Stack(entry) => {
                let at = generator_label(kind, entry.name.as_deref(), k);
                entry.expand(&at, &mut bodies)?;
            }
            Entry::Pyramid(entry) => {
                let at = generator_label(kind, entry.name.as_deref(), k);
                entry.expand(&at, &mut bodies)?;
            }
            Entry::Loose(_) => unreachable!("read above"),
        }
    }
    // Ropes and ragdolls after every other body (named `NAME[i]`, `NAME.hip`, ...), then the
    // joints, which may name any body, theirs included.
    let mut joints = Vec::with_capacity(joint_entries.len());
    for (k, rope) in ropes.into_iter().enumerate() {
        rope.expand(k, &mut bodies, &mut joints)?;
    }
    for (k, ragdoll) in ragdolls.into_iter().enumerate() {
        ragdoll.expand(k, &mut bodies, &mut joints)?;
    }
    for (k, entry) in joint_entries.into_iter().enumerate() {
        joints.push(entry.into_joint(k, &bodies)?);
    }
    Ok(Scene {
        name,
        gravity,
        settings,
        bodies,
        joints,
    })
}

/// An entry table with where it starts, its kind and its index among the tables of its kind.
type Placed = (usize, Kind, usize, Entry);

/// Append the tables of `kind`, each made an [`Entry`] by `entry`.
fn push_all<T>(
    out: &mut Vec<Placed>,
    kind: Kind,
    tables: Vec<Spanned<T>>,
    entry: impl Fn(T) -> Entry,
) {
    for (k, spanned) in tables.into_iter().enumerate() {
        let start = spanned.span().start;
        out.push((start, kind, k, entry(spanned.into_inner())));
    }
}

/// Read a loose table of `kind` (the `k`-th of its kind, at `line`) into its typed entry; the
/// error names it as the body it would have been (`bodies` so far) or as the generator.
fn read_loose(
    kind: Kind,
    k: usize,
    table: Table,
    line: usize,
    bodies: &[SceneBody],
) -> Result<Entry, SceneError> {
    let name = table
        .get("name")
        .and_then(|v| v.as_str())
        .map(str::to_owned);
    let entry_label = || {
        let label = match kind {
            Kind::Body => body_label(name.as_deref(), bodies.len()),
            _ => generator_label(kind, name.as_deref(), k),
        };
        format!("{label} at line {line}")
    };
    let parse_error = |e: toml::de::Error| SceneError::Parse {
        entry: Some(entry_label()),
        message: describe(&e),
    };
    Ok(match kind {
        Kind::Body => Entry::Body(table.try_into().map_err(parse_error)?),
        Kind::Stack => Entry::Stack(table.try_into().map_err(parse_error)?),
        Kind::Pyramid => Entry::Pyramid(table.try_into().map_err(parse_error)?),
    })
}

/// Refuse a scene that would grow past [`MAX_BODIES`].
fn reserve(bodies: &[SceneBody], more: u64) -> Result<(), SceneError> {
    let total = bodies.len() as u64 + more;
    if total > MAX_BODIES as u64 {
        return Err(SceneError::invalid(
            "scene",
            "bodies",
            Some(total.to_string()),
            format!("a scene holds at most {MAX_BODIES} bodies"),
        ));
    }
    Ok(())
}

/// The engine's check of a number from the file (`finite`, `positive`, `non_negative` or
/// `unit_interval` of `physics::error`), its refusal said about `at`: the messages are the
/// ones the engine gives for the same field and value.
fn check(at: &str, checked: Result<Real, PhysicsError>) -> Result<(), SceneError> {
    checked.map(|_| ()).map_err(|e| SceneError::physics(at, e))
}

/// Parse an optional `"#rrggbb"`, defaulting to [`Colour::GREY`].
fn parse_colour(at: &str, colour: Option<&str>) -> Result<Colour, SceneError> {
    match colour {
        None => Ok(Colour::GREY),
        Some(s) => s.parse().map_err(|_| {
            SceneError::invalid(
                at,
                "colour",
                Some(format!("{s:?}")),
                "expected \"#rrggbb\" (a '#' and six hex digits)",
            )
        }),
    }
}

impl BodyEntry {
    /// A `chain` entry as one static body per piece, named `NAME[i]` (`chain[i]` unnamed);
    /// `index` is the first piece's position in the scene.
    fn into_chain(self, index: usize) -> Result<Vec<SceneBody>, SceneError> {
        let at = body_label(self.name.as_deref(), index);
        let ShapeEntry::Chain {
            ref points,
            closed,
            one_sided,
        } = self.shape
        else {
            return Ok(Vec::new());
        };
        let refuse = |field: &str, written: String| {
            Err(SceneError::invalid(
                &at,
                field,
                Some(written),
                "a chain is static terrain: it takes no mass, density, velocity, kinematic or awake",
            ))
        };
        if self.kinematic {
            return refuse("kinematic", "true".into());
        }
        if !self.awake {
            return refuse("awake", "false".into());
        }
        if let Some(d) = self.density {
            return refuse("density", d.to_string());
        }
        if let Some(m) = self.mass {
            return refuse("mass", m.to_string());
        }
        let [vx, vy] = self.velocity;
        if vx != 0.0 || vy != 0.0 || self.angular_velocity != 0.0 {
            return refuse("velocity", format!("[{vx}, {vy}]"));
        }
        let colour = parse_colour(&at, self.colour.as_deref())?;
        let filter = self.filter(&at)?;
        let local = read_points(&at, "shape.points", points)?;
        let position = Vec2::new(self.position[0], self.position[1]);
        check(&at, finite("position.x", position.x))?;
        check(&at, finite("position.y", position.y))?;
        check(&at, finite("angle", self.angle))?;
        let turn = Rot::from_angle(self.angle);
        let pieces = chain(&local, closed, one_sided).map_err(|e| SceneError::physics(&at, e))?;
        let prefix = self.name.as_deref().unwrap_or("chain");
        pieces
            .into_iter()
            .enumerate()
            .map(|(i, (mid, segment))| {
                let def = BodyDef::fixed(
                    Shape::Segment(Box::new(segment)),
                    position + turn.rotate(mid),
                )
                .with_angle(self.angle)
                .with_friction(self.friction)
                .with_restitution(self.restitution)
                .with_filter(filter);
                def.validate()
                    .map_err(|e| SceneError::physics(at.clone(), e))?;
                Ok(SceneBody {
                    name: format!("{prefix}[{i}]"),
                    def,
                    colour,
                    is_static: true,
                })
            })
            .collect()
    }

    /// Validate and translate; `index` is the body's position in the scene.
    /// The body's collision filter (the default when the table gives none).
    fn filter(&self, at: &str) -> Result<Filter, SceneError> {
        self.filter
            .as_ref()
            .map_or(Ok(Filter::DEFAULT), |f| f.to_filter(at))
    }

    /// The body's parts as the engine places them: from the body's origin, which is the
    /// centroid `own_centroid` of a polygon's vertices (given around `position`), and at their
    /// own centroids.
    fn parts(&self, at: &str, own_centroid: Vec2) -> Result<Vec<PartDef>, SceneError> {
        let filter = self.filter(at)?;
        let mut parts = Vec::with_capacity(self.parts.len());
        for (i, p) in self.parts.iter().enumerate() {
            let (shape, centroid) = p.shape.to_shape(at).map_err(|e| e.in_part(i))?;
            let offset = Vec2::new(p.offset[0], p.offset[1]);
            let turned = crate::physics::Rot::from_angle(p.angle).rotate(centroid);
            let filter = match &p.filter {
                Some(f) => f.to_filter(at).map_err(|e| e.in_part(i))?,
                None => filter,
            };
            parts.push(PartDef {
                shape,
                offset: offset + turned - own_centroid,
                angle: p.angle,
                density: p.density.or(self.density).unwrap_or(1.0),
                friction: p.friction.unwrap_or(self.friction),
                restitution: p.restitution.unwrap_or(self.restitution),
                filter,
                flags: shape_flags(p.sensor, p.contact_events, p.hit_events),
            });
        }
        Ok(parts)
    }

    fn into_body(self, index: usize) -> Result<SceneBody, SceneError> {
        let at = body_label(self.name.as_deref(), index);
        let value = |v: Real| Some(v.to_string());
        let segment = matches!(self.shape, ShapeEntry::Segment { .. });
        if self.kinematic && self.is_static {
            return Err(SceneError::invalid(
                at,
                "kinematic",
                Some("true".into()),
                "a body is static or kinematic, not both (drop one)",
            ));
        }
        if self.kinematic {
            for (field, given) in [("density", self.density), ("mass", self.mass)] {
                if let Some(v) = given {
                    return Err(SceneError::invalid(
                        at,
                        field,
                        value(v),
                        "a kinematic body has neither density nor mass (it moves by its velocity alone)",
                    ));
                }
            }
        }
        // A segment is static unless it says it is kinematic.
        let is_static = self.is_static
            || (segment && !self.kinematic && self.density.is_none() && self.mass.is_none());
        let mass = match (is_static, self.density, self.mass) {
            _ if self.kinematic => MassSpec::Kinematic,
            (true, None, None) => MassSpec::Static,
            (true, Some(d), _) => {
                return Err(SceneError::invalid(
                    at,
                    "density",
                    value(d),
                    "a static body has neither density nor mass (remove it, or drop static = true)",
                ))
            }
            (true, None, Some(m)) => {
                return Err(SceneError::invalid(
                    at,
                    "mass",
                    value(m),
                    "a static body has neither density nor mass (remove it, or drop static = true)",
                ))
            }
            (false, Some(d), None) => MassSpec::Density(d),
            (false, None, Some(m)) => MassSpec::Mass(m),
            (false, Some(d), Some(m)) => {
                return Err(SceneError::invalid(
                    at,
                    "density",
                    value(d),
                    format!("give exactly one of density (kg/m^2) or mass (kg), not both (mass = {m})"),
                ))
            }
            (false, None, None) => {
                return Err(SceneError::invalid(
                    at,
                    "density",
                    None,
                    "missing: a dynamic body needs density (kg/m^2) or mass (kg); walls and grounds need static = true",
                ))
            }
        };
        if is_static {
            let [vx, vy] = self.velocity;
            if vx != 0.0 || vy != 0.0 {
                return Err(SceneError::invalid(
                    at,
                    "velocity",
                    Some(format!("[{vx}, {vy}]")),
                    "a static body does not move",
                ));
            }
            if self.angular_velocity != 0.0 {
                return Err(SceneError::invalid(
                    at,
                    "angular_velocity",
                    value(self.angular_velocity),
                    "a static body does not move",
                ));
            }
        }
        let colour = parse_colour(&at, self.colour.as_deref())?;
        let (shape, centroid) = self.shape.to_shape(&at)?;
        let position = Vec2::new(self.position[0], self.position[1]);
        let placed = if centroid != Vec2::ZERO {
            // A polygon's vertices are given around `position`; its centre of mass is their
            // centroid, turned with the body (the engine's rule, which also reports a bad
            // position or angle as written rather than as the NaN it would make of the centre).
            BodyDef::placed(shape, centroid, position, self.angle)
                .map_err(|e| SceneError::physics(&at, e))?
        } else {
            BodyDef::dynamic(shape, position).with_angle(self.angle)
        };
        let parts = self.parts(&at, centroid)?;
        let def = BodyDef {
            linear_velocity: Vec2::new(self.velocity[0], self.velocity[1]),
            angular_velocity: self.angular_velocity,
            mass,
            friction: self.friction,
            restitution: self.restitution,
            filter: self.filter(&at)?,
            parts,
            flags: shape_flags(self.sensor, self.contact_events, self.hit_events),
            awake: self.awake,
            ..placed
        };
        def.validate()
            .map_err(|e| SceneError::physics(at.clone(), e))?;
        Ok(SceneBody {
            name: self.name.unwrap_or_else(|| format!("body {index}")),
            def,
            colour,
            is_static,
        })
    }
}

/// The fields both generators have, as written: square boxes of side `size` around `x`, on
/// y = `base_y`, of one material and colour.
struct Generated<'a> {
    size: Real,
    x: Real,
    base_y: Real,
    density: Real,
    friction: Real,
    restitution: Real,
    colour: Option<&'a str>,
    awake: bool,
}

impl Generated<'_> {
    /// Check the generator `at` before it adds `total` boxes to `bodies`, in this order: its
    /// `count` field (`count`, `base`) is at least 1; the numbers (size, x, base_y, density,
    /// friction, restitution, then the generator's own `spacing` lengths, each >= 0); its
    /// colour; room in the scene. Returns the colour of its boxes.
    fn check(
        &self,
        at: &str,
        count: (&str, u32),
        spacing: &[(&'static str, Real)],
        total: u64,
        bodies: &[SceneBody],
    ) -> Result<Colour, SceneError> {
        at_least_one(at, count.0, count.1)?;
        check(at, positive("size", self.size))?;
        check(at, finite("x", self.x))?;
        check(at, finite("base_y", self.base_y))?;
        check(at, positive("density", self.density))?;
        check(at, non_negative("friction", self.friction))?;
        check(at, unit_interval("restitution", self.restitution))?;
        for &(field, length) in spacing {
            check(at, non_negative(field, length))?;
        }
        let colour = parse_colour(at, self.colour)?;
        reserve(bodies, total)?;
        Ok(colour)
    }

    /// Validate one box at `position` named `name` in `colour`, and add it.
    fn push(
        &self,
        bodies: &mut Vec<SceneBody>,
        name: String,
        position: Vec2,
        colour: Colour,
    ) -> Result<(), SceneError> {
        let def = BodyDef::dynamic(Shape::rect(self.size, self.size), position)
            .with_density(self.density)
            .with_friction(self.friction)
            .with_restitution(self.restitution)
            .with_awake(self.awake);
        let index = bodies.len();
        def.validate()
            .map_err(|e| SceneError::physics(body_label(Some(&name), index), e))?;
        bodies.push(SceneBody {
            name,
            def,
            colour,
            is_static: false,
        });
        Ok(())
    }
}

/// A generator's count (`count`, `base`) must be at least 1.
fn at_least_one(at: &str, field: &str, count: u32) -> Result<(), SceneError> {
    if count == 0 {
        return Err(SceneError::invalid(
            at,
            field,
            Some("0".into()),
            "must be >= 1",
        ));
    }
    Ok(())
}

impl StackEntry {
    /// Box i (from 0 at the bottom) is centred at (x, base_y + size/2 + i (size + gap)).
    fn expand(self, at: &str, bodies: &mut Vec<SceneBody>) -> Result<(), SceneError> {
        let boxes = self.generated();
        let colour = boxes.check(
            at,
            ("count", self.count),
            &[("gap", self.gap)],
            self.count as u64,
            bodies,
        )?;
        let prefix = self.name.as_deref().unwrap_or("stack");
        for i in 0..self.count {
            let y = self.base_y + 0.5 * self.size + i as Real * (self.size + self.gap);
            boxes.push(
                bodies,
                format!("{prefix}[{i}]"),
                Vec2::new(self.x, y),
                colour,
            )?;
        }
        Ok(())
    }
}

impl PyramidEntry {
    /// Row r (from 0 at the bottom) has base - r boxes, centred on x, at y = base_y + (r + 1/2) size;
    /// box c of the row is at x - (base - r - 1) size / 2 + c size (Box2D's benchmark layout).
    fn expand(self, at: &str, bodies: &mut Vec<SceneBody>) -> Result<(), SceneError> {
        let boxes = self.generated();
        let base = self.base as u64;
        let colour = boxes.check(at, ("base", self.base), &[], base * (base + 1) / 2, bodies)?;
        let prefix = self.name.as_deref().unwrap_or("pyramid");
        for row in 0..self.base {
            let count = self.base - row;
            let y = self.base_y + (0.5 + row as Real) * self.size;
            let x0 = self.x - 0.5 * (count as Real - 1.0) * self.size;
            for col in 0..count {
                let position = Vec2::new(x0 + col as Real * self.size, y);
                boxes.push(bodies, format!("{prefix}[{row},{col}]"), position, colour)?;
            }
        }
        Ok(())
    }
}
