//! Every tunable of the engine, in one place, with documented defaults.

use super::error::{finite, non_negative, positive, PhysicsError};
use super::math::Real;
use serde::{Deserialize, Serialize};

/// Which contact solver `World::step` runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// The appendix's solver (box2d-lite lineage): sequential impulses, `iterations` passes
    /// per step, with the Baumgarte position correction solved apart (split impulse) so it
    /// never adds energy. What it cannot do: hold a jittered stack of 20 or 50 boxes, or a
    /// 1000 kg box on a 1 kg one (the 10 iterations do not carry the load down; the light box
    /// is squeezed 0.5 m deep), which the soft step does (`docs/accuracy.md`).
    Sequential,
    /// Box2D v3-style soft step: `substeps` substeps of soft contacts, a relax pass and a
    /// restitution pass, with speculative contacts.
    SoftStep,
}

/// How two bodies' coefficients combine into the pair's coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mixing {
    /// sqrt(a b): Box2D's rule; zero if either is zero.
    GeometricMean,
    /// a b: the appendix's friction rule (P_tmax = muA muB Pn).
    Product,
    /// min(a, b).
    Min,
    /// max(a, b).
    Max,
}

impl Mixing {
    /// The pair coefficient for coefficients `a` and `b`.
    #[inline]
    pub fn mix(self, a: Real, b: Real) -> Real {
        match self {
            Mixing::GeometricMean => (a * b).sqrt(),
            Mixing::Product => a * b,
            Mixing::Min => a.min(b),
            Mixing::Max => a.max(b),
        }
    }
}

/// The most workers a World may have ([`Settings::workers`]).
pub const MAX_WORKERS: u32 = 64;

/// The engine's tunables. `Settings::default()` is the soft-step solver with Box2D v3's
/// defaults; `Settings::sequential()` is the appendix / box2d-lite configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Which solver runs. Default: soft step.
    pub solver: SolverKind,
    /// Sequential solver: velocity iterations per step. Default 10 (the appendix suggests 8-10).
    pub iterations: u32,
    /// Soft step: substeps per step. Default 4 (Box2D v3).
    pub substeps: u32,
    /// Penetration allowed before position correction pushes back (m). Keeps resting contacts
    /// alive from one step to the next. Default 0.005 (Box2D v3); box2d-lite uses 0.01.
    pub linear_slop: Real,
    /// Sequential solver: fraction of the penetration beyond the slop removed per step
    /// (Baumgarte factor, bias = factor / dt * penetration). Default 0.2 (box2d-lite).
    pub bias_factor: Real,
    /// Start each step's solve from the previous step's impulses (matched by feature id).
    pub warm_starting: bool,
    /// Clamp the running total of each impulse rather than each increment (box2d-lite's
    /// "accumulate impulses"). Sequential solver only; the soft step always accumulates.
    pub accumulate_impulses: bool,
    /// Friction mixing rule. Default: geometric mean.
    pub friction_mixing: Mixing,
    /// Restitution mixing rule. Default: geometric mean, e = sqrt(eA eB).
    pub restitution_mixing: Mixing,
    /// Approach speed below which restitution is ignored (m/s), so resting contacts do not
    /// jitter. Default 1 m/s (Box2D).
    pub restitution_threshold: Real,
    /// Soft step: contact stiffness (Hz), capped at a quarter of the substep rate. Default 60
    /// (the cap at 4 substeps of 1/60 s). Box2D v3 uses 30; at 30 Hz we measured a 20-box
    /// stack with 1 cm jitter toppling within 30 s, at 60 Hz it stands (docs/accuracy.md).
    /// Contacts with static bodies get twice this, within the same cap (so at the defaults
    /// the same 60 Hz).
    pub contact_hertz: Real,
    /// Soft step: stiffen a contact beyond `contact_hertz` when the load it carried last step
    /// would sink it deeper than `linear_slop` (k >= F / slop), up to `max_contact_hertz_ratio`
    /// times the substep rate; the spring then falls by at most 2 % per step. Default **off**
    /// (Box2D v3's fixed springs): on, with the default 4 substeps, a pile of 2,000 boxes never
    /// came to rest (1,860 still moving at 1-2 m/s after 10 s), because every contact in it
    /// stiffens and the Gauss-Seidel passes cannot settle that many stiff springs. It is what
    /// extreme mass ratios need: the stiff configuration (`tiltbox report`'s third column,
    /// 8 substeps and 4 relax passes) turns it on, and holds a 1000:1 mass ratio within 2 slops.
    pub load_aware_stiffness: bool,
    /// Soft step: give each island the work its load calls for ("leave out what a scene does
    /// not need"). An island is loaded when a contact in it has carried at least
    /// `stiff_load_ratio` times the weight of the lighter body it touches for two steps
    /// running, or where a body carries the weight of one that much heavier (a quarter of it
    /// or more, or lying under it as they first touch). Without gravity no contact asks for
    /// anything. A loaded island braced
    /// sideways (a pyramid, a pile: less than twice as tall as wide, along gravity, with at
    /// least `stiff_load_ratio` bodies) keeps the base substeps with a relax pass, a normal
    /// relax pass and creeping springs, or twice the substeps and stiffness where it is 80
    /// bodies deep or more on average (a pyramid of base 159 and up). Any other loaded island (a stack) is solved with 1.5
    /// times the substeps and contact stiffness, and with 1.75 times from 2.25 times that load
    /// (a spring's compression goes as load / omega^2) or where masses differ by
    /// `stiff_load_ratio`. An island where a body carries the weight of one
    /// `extreme_mass_ratio` times its mass, or with a joint joining such masses, gets four
    /// times the substeps and stiffness (joints' too) and eight times the relax passes. Every other island keeps
    /// the base settings and pays nothing. Default **on**: with it the defaults pass every
    /// case of the stiff suite (jittered 20- and 50-box stacks, 100:1 and 1000:1 mass ratios
    /// both ways, the symmetric pyramid of base 30), which fixed settings pass only at 2.2-2.5
    /// times the cost of every step.
    pub adaptive_stiffness: bool,
    /// Soft step, adaptive stiffness: the load ratio (a contact's force over the lighter body's
    /// weight, or the pair's mass ratio) from which an island gets more work. Default 12: a
    /// stack of 10 boxes stays on the base settings, a stack of 20 does not.
    pub stiff_load_ratio: Real,
    /// Soft step, adaptive stiffness: the mass ratio across a contact whose lighter body
    /// carries the heavier one's weight, or across a joint, from which an island gets four
    /// times the work. Default 100 (a 1 kg box under 100 kg).
    pub extreme_mass_ratio: Real,
    /// Soft step: ceiling for load-aware stiffening, as a fraction of the substep rate.
    /// Default 0.5 (a spring at half the substep rate still resolves within a substep).
    pub max_contact_hertz_ratio: Real,
    /// Soft step: contact damping ratio (dimensionless). Default 10.
    pub contact_damping_ratio: Real,
    /// Soft step: the fastest overlap recovery (m/s), per contact. Default 3 (Box2D's contact
    /// push-out). A contact's spring pushes no faster; overlap beyond its reach is pushed out
    /// in position, no faster either, and never becomes velocity.
    pub max_push_out_speed: Real,
    /// Soft step: contacts are created this far before the surfaces touch (m), plus how far
    /// the bodies can move in one step. Default 4 x linear slop = 0.02.
    pub speculative_distance: Real,
    /// Soft step: relax passes (no bias) after each substep's position update. Default 1.
    pub relax_iterations: u32,
    /// Reuse a contact's manifold while its two bodies have hardly moved against each other
    /// since it was computed: each point stays fixed in both bodies and its separation follows
    /// their motion along the normal, which is exact for a vertex on a face until the clipping
    /// changes. A pair is collided afresh once a point drifts 1 mm (at most 0.5 % of the
    /// smaller body's size) or the pair turns 2 mrad. Default
    /// on: a pyramid at rest then skips most of its narrow phase.
    pub contact_recycling: bool,
    /// Let bodies that rest with their island sleep, costing nothing until something touches
    /// them, a force or impulse is applied, or gravity changes. Default on.
    pub enable_sleep: bool,
    /// Speed under which a body counts as resting (m/s): |v| + |w| x bounding radius. Default
    /// 0.05 (Box2D).
    pub sleep_threshold: Real,
    /// How long a whole island must rest before it sleeps (s). Default 0.5 (Box2D).
    pub time_to_sleep: Real,
    /// Speed cap for any body (m/s), so a bad impulse cannot run away. Default 400 (Box2D: 4 m per step at 100 Hz).
    pub max_linear_speed: Real,
    /// Largest rotation a body may make in one (sub)step (rad). Default 0.25 pi (Box2D).
    pub max_rotation: Real,
    /// Approach speed above which a contact of a shape with hit events reports a hit (m/s).
    /// Default 1 (Box2D's `hitEventThreshold`).
    pub hit_event_threshold: Real,
    /// Threads that share a step: the one that steps the World and `workers - 1` of the
    /// World's own, which sleep between steps. The results are the same to the bit for any
    /// number. Default 1 (no thread of its own); at most 64.
    pub workers: u32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings::soft_step()
    }
}

impl Settings {
    /// Soft-step defaults after Box2D v3: 4 substeps, damping ratio 10, push-out 3 m/s, fixed
    /// springs, with 60 Hz contacts (Box2D: 30; see the fields for why).
    pub fn soft_step() -> Settings {
        Settings {
            solver: SolverKind::SoftStep,
            iterations: 10,
            substeps: 4,
            linear_slop: 0.005,
            bias_factor: 0.2,
            warm_starting: true,
            accumulate_impulses: true,
            friction_mixing: Mixing::GeometricMean,
            restitution_mixing: Mixing::GeometricMean,
            restitution_threshold: 1.0,
            contact_hertz: 60.0,
            load_aware_stiffness: false,
            max_contact_hertz_ratio: 0.5,
            adaptive_stiffness: true,
            stiff_load_ratio: 12.0,
            extreme_mass_ratio: 100.0,
            contact_damping_ratio: 10.0,
            max_push_out_speed: 3.0,
            speculative_distance: 0.02,
            relax_iterations: 1,
            contact_recycling: true,
            enable_sleep: true,
            sleep_threshold: 0.05,
            time_to_sleep: 0.5,
            max_linear_speed: 400.0,
            max_rotation: 0.25 * super::math::PI,
            hit_event_threshold: 1.0,
            workers: 1,
        }
    }

    /// The soft step with every island on heavy fixed settings: 8 substeps, 4 relax passes,
    /// 120 Hz contacts (a quarter of the 480 Hz substep rate, the cap, so static contacts
    /// get no more) and load-aware stiffening, adaptive stiffness off. Before adaptive stiffness
    /// this was the only configuration that passed the stiff suite; the defaults now pass it
    /// too (`Settings::adaptive_stiffness`), paying only where an island needs it, so this is
    /// kept for comparison: it costs 2.2-2.5 times the base step everywhere.
    pub fn soft_step_stiff() -> Settings {
        Settings {
            substeps: 8,
            relax_iterations: 4,
            contact_hertz: 120.0,
            load_aware_stiffness: true,
            adaptive_stiffness: false,
            ..Settings::soft_step()
        }
    }

    /// The appendix / box2d-lite configuration: sequential impulses, 10 iterations, allowed
    /// penetration 0.01 m, bias factor 0.2, warm starting and accumulated impulses on (see
    /// [`SolverKind::Sequential`] for what it cannot do).
    pub fn sequential() -> Settings {
        Settings {
            solver: SolverKind::Sequential,
            linear_slop: 0.01,
            ..Settings::soft_step()
        }
    }

    /// Refuse settings the solver cannot run with, naming the field and the value.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        let count = |field: &'static str, v: u32, max: u32| {
            if (1..=max).contains(&v) {
                Ok(())
            } else {
                Err(PhysicsError::OutOfRange {
                    field,
                    value: v as Real,
                    expected: if max == 64 {
                        "must be within 1..=64"
                    } else {
                        "must be within 1..=1000"
                    },
                })
            }
        };
        count("iterations", self.iterations, 1000)?;
        count("substeps", self.substeps, 64)?;
        count("workers", self.workers, MAX_WORKERS)?;
        if self.relax_iterations > 64 {
            return Err(PhysicsError::OutOfRange {
                field: "relax_iterations",
                value: self.relax_iterations as Real,
                expected: "must be within 0..=64",
            });
        }
        non_negative("linear_slop", self.linear_slop)?;
        non_negative("bias_factor", self.bias_factor)?;
        if self.bias_factor > 1.0 {
            return Err(PhysicsError::OutOfRange {
                field: "bias_factor",
                value: self.bias_factor,
                expected: "must be within [0, 1]",
            });
        }
        non_negative("restitution_threshold", self.restitution_threshold)?;
        non_negative("hit_event_threshold", self.hit_event_threshold)?;
        positive("contact_hertz", self.contact_hertz)?;
        non_negative("contact_damping_ratio", self.contact_damping_ratio)?;
        non_negative("max_contact_hertz_ratio", self.max_contact_hertz_ratio)?;
        positive("stiff_load_ratio", self.stiff_load_ratio)?;
        positive("extreme_mass_ratio", self.extreme_mass_ratio)?;
        positive("max_push_out_speed", self.max_push_out_speed)?;
        non_negative("speculative_distance", self.speculative_distance)?;
        non_negative("sleep_threshold", self.sleep_threshold)?;
        non_negative("time_to_sleep", self.time_to_sleep)?;
        positive("max_linear_speed", self.max_linear_speed)?;
        positive("max_rotation", self.max_rotation)?;
        finite("max_rotation", self.max_rotation)?;
        Ok(())
    }
}
