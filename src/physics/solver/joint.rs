//! Joints in the solver: every kind is built from the same parts, written once and shared by
//! both solvers.
//!
//! - a **point block**: the anchors meet, C = d = (cB + rB) - (cA + rA), solved as one 2x2
//!   block (K = J M^-1 J^T with J = [-I, -[rA]x, I, [rB]x]);
//! - **rows**, one-dimensional: C is the joint angle (J = [0, -1, 0, 1]), the travel of B's
//!   anchor along or across an axis fixed in A (J = [-u, -(d + rA) x u, u, rB x u]), or the
//!   anchors' distance (J = [-u, -rA x u, u, rB x u], u = d / |d|).
//!
//! Each row holds its value at a target (rigidly, as a spring, or with a correction factor),
//! drives it at a speed (a motor, its impulse capped at h times its force), or keeps it on one
//! side of a bound (a limit: speculative while open, C / h, so a fast joint stops at the bound
//! instead of passing it). The soft step solves them as Box2D v3 does: soft (the joint's
//! `constraint_hertz`) in the biased pass, rigid in the relax pass, springs in both, warm
//! started every substep. The sequential solver solves them once per step as box2d-lite's
//! `Joint` does, with a Baumgarte bias of 0.2 C / dt in the velocity. Positions are read from the bodies' motion since the start of
//! the step (dp, dq), so nothing is recomputed from the World between substeps.

use super::graph::OVERFLOW;
use super::softness::Softness;
use super::{Selected, SharedRows, SolverBody};
use crate::physics::joint::{JointImpulses, JointKind, Limit, Motor, Spring};
use crate::physics::math::{cross, Real, Vec2};
use crate::physics::team::{block, Region, SharedSlice};

/// What a row measures.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measure {
    /// The joint angle: B's angle minus A's minus the reference (rad).
    Angle,
    /// The travel of B's anchor from A's along the axis fixed in A (m).
    Along,
    /// The same across the axis (m).
    Across,
    /// The anchors' distance (m).
    Length,
}

/// How a row or the point block pulls its value to its target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Pull {
    /// Rigidly: soft at the joint's stiffness in the biased pass, rigid in the relax pass.
    Joint,
    /// A spring, in every pass.
    Spring(Spring),
    /// A fraction of the error per substep in the biased pass (the motor joint).
    Correct(Real),
}

/// What a row does with its value.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    /// Holds it at the row's target.
    Hold(Pull),
    /// Drives it at a speed (rad/s or m/s).
    Motor(Real),
    /// Keeps it at or above the target.
    Lower,
    /// Keeps it at or below the target.
    Upper,
}

/// One row of a joint.
#[derive(Clone, Copy, Debug)]
struct Row {
    measure: Measure,
    role: Role,
    /// The value held or bounded (rad or m).
    target: Real,
    /// Largest force or torque (N, N m); infinity: none.
    max: Real,
    /// This solve's spring, and whether it acts in the relax pass too.
    soft: Softness,
    always: bool,
    /// Largest impulse per substep (N s).
    max_impulse: Real,
    /// Accumulated impulse (per substep during a solve, per step between steps).
    impulse: Real,
}

/// The point block of a joint, as the solve passes read it (its pull and largest force are
/// in [`JointCold`]).
#[derive(Clone, Copy, Debug)]
struct PointBlock {
    soft: Softness,
    always: bool,
    max_impulse: Real,
    impulse: Vec2,
}

/// Where a joint's bodies and anchors are at the start of the step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    /// The anchors' arms from the centres of mass, in world axes (m).
    pub ra: Vec2,
    pub rb: Vec2,
    /// cB - cA (m).
    pub centres: Vec2,
    /// The joint angle (rad).
    pub angle: Real,
    /// The axis fixed in A, in world axes (unit).
    pub axis: Vec2,
}

/// A joint as one solve sees it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointConstraint {
    /// Its bodies' solver indices (a fixed body for the world).
    pub a: u32,
    pub b: u32,
    frame: Frame,
    point: Option<PointBlock>,
    /// Its rows: `JointSet::rows[rows.0..rows.1]`.
    rows: (u32, u32),
}

/// What only prepare and store read of a joint, kept apart so that the solve passes stream
/// less of each joint (the square root of the point block's cap, not its size, was what held
/// joint_grid up).
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointCold {
    /// The joint's slot in the World.
    pub slot: u32,
    /// Its rigid rows' stiffness (Hz) and damping ratio, and their spring this solve.
    hertz: Real,
    zeta: Real,
    soft: Softness,
    /// The point block's pull and largest force (N).
    point: Option<(Pull, Real)>,
    /// The force (N) and torque (N m) on B at the end of the solve (the force: last step's
    /// until the store).
    pub force: Vec2,
    pub torque: Real,
}

/// The joint's pose during a solve.
#[derive(Clone, Copy, Debug)]
struct Pose {
    ra: Vec2,
    rb: Vec2,
    d: Vec2,
    angle: Real,
    axis: Vec2,
}

/// A row's Jacobian at a pose: J = [-u, -ka, u, kb], and its value.
#[derive(Clone, Copy, Debug)]
struct Jacobian {
    u: Vec2,
    ka: Real,
    kb: Real,
    value: Real,
}

impl JointCold {
    /// A placeholder, overwritten before it is read.
    const EMPTY: JointCold = JointCold {
        slot: 0,
        hertz: 0.0,
        zeta: 0.0,
        soft: Softness::RIGID,
        point: None,
        force: Vec2::ZERO,
        torque: 0.0,
    };
}

impl Row {
    const fn new(measure: Measure, role: Role, target: Real, max: Real) -> Row {
        Row {
            measure,
            role,
            target,
            max,
            soft: Softness::RIGID,
            always: false,
            max_impulse: Real::INFINITY,
            impulse: 0.0,
        }
    }
}

/// Where [`parts`] puts a joint's rows: the set's own, a run of them made ready, or nowhere
/// (counted only).
trait RowSink {
    /// Rows put so far.
    fn len(&self) -> usize;
    fn push(&mut self, row: Row);
    /// Set the target of row `i` (rad or m).
    fn set_target(&mut self, i: usize, target: Real);
}

impl RowSink for Vec<Row> {
    fn len(&self) -> usize {
        self.len()
    }
    fn push(&mut self, row: Row) {
        self.push(row);
    }
    fn set_target(&mut self, i: usize, target: Real) {
        self[i].target = target;
    }
}

/// Counts rows, keeps none.
struct RowCount(usize);

impl RowSink for RowCount {
    fn len(&self) -> usize {
        self.0
    }
    fn push(&mut self, _: Row) {
        self.0 += 1;
    }
    fn set_target(&mut self, _: usize, _: Real) {}
}

/// Fills a run of rows counted before.
struct RowRun<'a> {
    rows: &'a mut [Row],
    len: usize,
}

impl RowSink for RowRun<'_> {
    fn len(&self) -> usize {
        self.len
    }
    fn push(&mut self, row: Row) {
        self.rows[self.len] = row;
        self.len += 1;
    }
    fn set_target(&mut self, i: usize, target: Real) {
        self.rows[i].target = target;
    }
}

/// The rows a kind's coordinate gets from its spring, motor and limit, in Box2D's order
/// (spring, motor, limits: the hard rows last, so they have the last word).
fn coordinate_rows(
    measure: Measure,
    spring: Option<Spring>,
    motor: Option<Motor>,
    limit: Option<Limit>,
    rows: &mut impl RowSink,
) {
    if let Some(s) = spring.filter(|s| s.hertz > 0.0) {
        rows.push(Row::new(
            measure,
            Role::Hold(Pull::Spring(s)),
            0.0,
            Real::INFINITY,
        ));
    }
    if let Some(m) = motor {
        rows.push(Row::new(measure, Role::Motor(m.speed), 0.0, m.max));
    }
    if let Some(l) = limit {
        rows.push(Row::new(measure, Role::Lower, l.lower, Real::INFINITY));
        rows.push(Row::new(measure, Role::Upper, l.upper, Real::INFINITY));
    }
}

/// The kind's point block (with its pull and largest force); its rows, in solve order, pushed
/// onto `rows`.
fn parts(kind: &JointKind, length: Real, rows: &mut impl RowSink) -> Option<(Pull, Real)> {
    let first = rows.len();
    let hold = |measure, pull| Row::new(measure, Role::Hold(pull), 0.0, Real::INFINITY);
    let spring = |hertz, damping_ratio| Spring {
        hertz,
        damping_ratio,
    };
    match kind {
        JointKind::Revolute(r) => {
            coordinate_rows(Measure::Angle, r.spring, r.motor, r.limit, rows);
            Some((Pull::Joint, Real::INFINITY))
        }
        JointKind::Prismatic(p) => {
            coordinate_rows(Measure::Along, p.spring, p.motor, p.limit, rows);
            rows.push(hold(Measure::Across, Pull::Joint));
            rows.push(hold(Measure::Angle, Pull::Joint));
            None
        }
        JointKind::Distance(d) => {
            // The spring's (or the rigid row's) target is the rest length; the limits are
            // lengths already.
            match d.spring.filter(|s| s.hertz > 0.0) {
                Some(_) => coordinate_rows(Measure::Length, d.spring, None, d.limit, rows),
                None => rows.push(hold(Measure::Length, Pull::Joint)),
            }
            rows.set_target(first, length);
            None
        }
        JointKind::Weld(w) => {
            let pull = |hertz, zeta| match hertz > 0.0 {
                true => Pull::Spring(spring(hertz, zeta)),
                false => Pull::Joint,
            };
            let angular = pull(w.angular_hertz, w.angular_damping_ratio);
            rows.push(hold(Measure::Angle, angular));
            Some((pull(w.linear_hertz, w.linear_damping_ratio), Real::INFINITY))
        }
        JointKind::Wheel(w) => {
            coordinate_rows(Measure::Along, w.spring, None, w.limit, rows);
            coordinate_rows(Measure::Angle, None, w.motor, None, rows);
            rows.push(hold(Measure::Across, Pull::Joint));
            None
        }
        JointKind::Motor(m) => {
            let mut angular = hold(Measure::Angle, Pull::Correct(m.correction_factor));
            angular.target = m.angular_offset;
            angular.max = m.max_torque;
            rows.push(angular);
            Some((Pull::Correct(m.correction_factor), m.max_force))
        }
        JointKind::Target(t) => Some((Pull::Spring(spring(t.hertz, t.damping_ratio)), t.max_force)),
    }
}

/// This step's joints: their constraints, and their rows side by side (a joint with none,
/// a free hinge, stays small).
#[derive(Clone, Debug, Default)]
pub(crate) struct JointSet {
    pub constraints: Vec<JointConstraint>,
    /// Each constraint's cold part, indexed alike.
    pub cold: Vec<JointCold>,
    /// Each constraint's place in the solve order of the constraint graph's colours
    /// ([`solve_rank`]), indexed alike; the constraints are pushed in this order.
    ranks: Vec<u8>,
    rows: Vec<Row>,
    /// Scratch for [`JointSet::build_shared`]: each joint's first row.
    row_starts: Vec<u32>,
}

/// What one joint's constraint is made from.
pub(crate) struct JointSource<'a> {
    /// The joint's slot in the World.
    pub slot: u32,
    /// Its bodies' solver indices (a fixed body for the world).
    pub ends: [u32; 2],
    /// Its colour in the constraint graph.
    pub colour: u8,
    pub kind: &'a JointKind,
    /// A distance joint's rest length (m; 0 for the other kinds).
    pub length: Real,
    /// How it is posed at the start of the step.
    pub frame: Frame,
    /// Last step's impulses.
    pub impulses: &'a JointImpulses,
    /// Last step's force on B (N).
    pub force: Vec2,
    /// Its rigid rows' stiffness (Hz) and damping ratio.
    pub hertz: Real,
    pub zeta: Real,
}

impl JointSource<'_> {
    /// The joint's constraint, with its point block (`point`, from [`parts`]) and its rows at
    /// `rows`, and its cold part.
    fn constraint(
        &self,
        point: Option<(Pull, Real)>,
        rows: (u32, u32),
    ) -> (JointConstraint, JointCold) {
        let [a, b] = self.ends;
        let constraint = JointConstraint {
            a,
            b,
            frame: self.frame,
            point: point.map(|_| PointBlock {
                soft: Softness::RIGID,
                always: false,
                max_impulse: Real::INFINITY,
                impulse: Vec2::from(self.impulses.point),
            }),
            rows,
        };
        let cold = JointCold {
            slot: self.slot,
            hertz: self.hertz,
            zeta: self.zeta,
            soft: Softness::RIGID,
            point,
            force: self.force,
            torque: 0.0,
        };
        (constraint, cold)
    }
}

impl JointSet {
    /// No joints.
    pub fn clear(&mut self) {
        self.constraints.clear();
        self.cold.clear();
        self.ranks.clear();
        self.rows.clear();
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.constraints.is_empty()
    }

    /// Add the constraint of the joint `source` describes. Joints are pushed in the order of
    /// their colours' [`solve_rank`].
    pub fn push(&mut self, source: JointSource) {
        let start = self.rows.len();
        let point = parts(source.kind, source.length, &mut self.rows);
        for (row, &impulse) in self.rows[start..].iter_mut().zip(&source.impulses.rows) {
            row.impulse = impulse;
        }
        let rows = (start as u32, self.rows.len() as u32);
        debug_assert!(self
            .ranks
            .last()
            .map_or(true, |&r| r <= solve_rank(source.colour)));
        self.ranks.push(solve_rank(source.colour));
        let (constraint, cold) = source.constraint(point, rows);
        self.constraints.push(constraint);
        self.cold.push(cold);
    }

    /// The constraints of `n` joints, the k-th (in solve order) described by `source(k)`,
    /// made on `region`'s workers: each joint's constraint and the count of its rows, then,
    /// once their places are known, the rows. (`source` is asked twice for a joint with rows.)
    pub fn build_shared<'s>(
        &mut self,
        n: usize,
        region: &Region,
        source: &(dyn Fn(usize) -> JointSource<'s> + Sync),
    ) {
        // (Only new room is filled: every joint is written below.)
        self.constraints.resize(n, JointConstraint::EMPTY);
        self.cold.resize(n, JointCold::EMPTY);
        self.ranks.resize(n, 0);
        let mut starts = std::mem::take(&mut self.row_starts);
        starts.resize(n, 0);
        let blocks = n.div_ceil(JOINTS_PER_BLOCK);
        {
            // SAFETY: each block writes its own joints.
            let (constraints, cold, ranks, counts) = unsafe {
                (
                    SharedSlice::new(&mut self.constraints),
                    SharedSlice::new(&mut self.cold),
                    SharedSlice::new(&mut self.ranks),
                    SharedSlice::new(&mut starts),
                )
            };
            region.for_blocks(blocks, &|b| {
                let k = block(b, JOINTS_PER_BLOCK, n);
                // SAFETY: as above.
                let out = unsafe {
                    (
                        constraints.range(k.clone()),
                        cold.range(k.clone()),
                        ranks.range(k.clone()),
                        counts.range(k.clone()),
                    )
                };
                for (m, (j, (c, (r, count)))) in k.zip(
                    out.0
                        .iter_mut()
                        .zip(out.1.iter_mut().zip(out.2.iter_mut().zip(out.3.iter_mut()))),
                ) {
                    let source = source(m);
                    let mut rows = RowCount(0);
                    let point = parts(source.kind, source.length, &mut rows);
                    *r = solve_rank(source.colour);
                    (*j, *c) = source.constraint(point, (0, 0));
                    *count = rows.0 as u32;
                }
            });
        }
        // Each joint's first row: the counts before it.
        let mut total = 0;
        for s in &mut starts {
            (*s, total) = (total, total + *s);
        }
        self.rows.resize(
            total as usize,
            Row::new(Measure::Angle, Role::Lower, 0.0, 0.0),
        );
        if total > 0 {
            let starts = &starts;
            // SAFETY: each block writes its own joints and their runs of rows.
            let (constraints, rows) = unsafe {
                (
                    SharedSlice::new(&mut self.constraints),
                    SharedSlice::new(&mut self.rows),
                )
            };
            region.for_blocks(blocks, &|b| {
                for m in block(b, JOINTS_PER_BLOCK, n) {
                    let end = starts.get(m + 1).copied().unwrap_or(total);
                    if end == starts[m] {
                        continue;
                    }
                    let source = source(m);
                    let range = starts[m] as usize..end as usize;
                    // SAFETY: as above.
                    let (j, run) = unsafe { (constraints.get(m), rows.range(range)) };
                    let mut run = RowRun { rows: run, len: 0 };
                    parts(source.kind, source.length, &mut run);
                    for (row, &impulse) in run.rows.iter_mut().zip(&source.impulses.rows) {
                        row.impulse = impulse;
                    }
                    j.expect("a joint").rows = (starts[m], end);
                }
            });
        }
        self.row_starts = starts;
    }

    /// The impulses joint `k` carries to the next step (per step).
    pub fn impulses(&self, k: usize) -> JointImpulses {
        let j = &self.constraints[k];
        let mut out = JointImpulses::default();
        if let Some(p) = &j.point {
            out.point = p.impulse.into();
        }
        for (o, r) in out.rows.iter_mut().zip(&self.rows[j.row_range()]) {
            *o = r.impulse;
        }
        out
    }
}

impl JointConstraint {
    /// A placeholder, overwritten before it is read.
    const EMPTY: JointConstraint = JointConstraint {
        a: 0,
        b: 0,
        frame: Frame {
            ra: Vec2::ZERO,
            rb: Vec2::ZERO,
            centres: Vec2::ZERO,
            angle: 0.0,
            axis: Vec2::ZERO,
        },
        point: None,
        rows: (0, 0),
    };

    /// Where its rows are in `JointSet::rows`.
    #[inline]
    fn row_range(&self) -> std::ops::Range<usize> {
        self.rows.0 as usize..self.rows.1 as usize
    }
}

/// The stiffest a joint is by default, as a fraction of the substep rate (Box2D's quarter:
/// a stiffer spring is not resolved by the substep).
pub(crate) const JOINT_CAP: Real = 0.25;

/// How a solve steps its joints.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointStep {
    /// Substep (s).
    pub h: Real,
    /// Substeps in the step.
    pub substeps: u32,
    /// The sequential solver's Baumgarte factor for the rigid rows (box2d-lite's 0.2: the
    /// fraction of the position error the velocity removes per step); 0: the soft step.
    pub baumgarte: Real,
    /// Whether the joints start from last step's impulses.
    pub warm_starting: bool,
    /// What the stiffness tier multiplies the joints' `constraint_hertz` by, as it does the
    /// contacts' (1 at the base tier and in the sequential solver).
    pub hertz_scale: Real,
    /// The stiffest a joint may be, as a fraction of the substep rate.
    pub cap: Real,
}

/// Prepare: springs and impulse caps for this solve; last step's impulses made per substep.
/// Spread over `region`'s workers, if given.
#[inline(never)]
pub(crate) fn prepare(
    set: &mut JointSet,
    selected: Selected,
    step: JointStep,
    region: Option<&Region>,
) {
    // Last step's impulses, per substep (none without warm starting).
    let scale = if step.warm_starting {
        1.0 / step.substeps as Real
    } else {
        0.0
    };
    for_each_joint(set, selected, region, &|j, c, rows| {
        prepare_joint(j, c, rows, (step, scale))
    });
}

/// Prepare one joint with its cold part and rows; its impulses scaled by `scale`.
#[inline]
fn prepare_joint(
    j: &mut JointConstraint,
    c: &mut JointCold,
    rows: &mut [Row],
    (step, scale): (JointStep, Real),
) {
    c.soft = if step.baumgarte > 0.0 {
        Softness {
            bias_rate: step.baumgarte / step.h,
            mass_scale: 1.0,
            impulse_scale: 0.0,
        }
    } else {
        Softness::new(
            (step.hertz_scale * c.hertz).min(step.cap / step.h),
            c.zeta,
            step.h,
        )
    };
    if let (Some(p), Some((pull, max))) = (&mut j.point, c.point) {
        (p.soft, p.always) = pull_softness(pull, c.soft, step.h);
        p.max_impulse = max * step.h;
        p.impulse *= scale;
    }
    let soft = c.soft;
    for row in rows {
        (row.soft, row.always) = match row.role {
            Role::Hold(pull) => pull_softness(pull, soft, step.h),
            _ => (soft, false),
        };
        row.max_impulse = row.max * step.h;
        row.impulse *= scale;
    }
}

/// The fewest joints whose constraints are made, prepared, stored and finished on the workers
/// (fewer take some tens of microseconds).
pub(crate) const SHARED_JOINTS_FROM: usize = 256;

/// Run `f` on every selected joint with its cold part and rows: on this thread, or spread
/// over `region`'s workers in blocks (each joint touches only its own parts).
#[inline(always)]
fn for_each_joint(
    set: &mut JointSet,
    selected: Selected,
    region: Option<&Region>,
    f: &(impl Fn(&mut JointConstraint, &mut JointCold, &mut [Row]) + Sync),
) {
    let n = selected.count(set.constraints.len());
    let JointSet {
        constraints,
        cold,
        rows,
        ..
    } = set;
    match region {
        None => selected.for_each_index(constraints.len(), |k| {
            let j = &mut constraints[k];
            f(j, &mut cold[k], &mut rows[j.row_range()])
        }),
        Some(region) => {
            // SAFETY: the selected joints are distinct, and each block reaches its own joints,
            // their cold parts and their rows.
            let (constraints, cold, rows) = unsafe {
                (
                    SharedSlice::new(constraints),
                    SharedSlice::new(cold),
                    SharedSlice::new(rows),
                )
            };
            region.for_blocks(n.div_ceil(JOINTS_PER_BLOCK), &|b| {
                for m in block(b, JOINTS_PER_BLOCK, n) {
                    let k = selected.at(m);
                    // SAFETY: as above.
                    let (j, c) = unsafe { (constraints.get(k), cold.get(k)) };
                    let (j, c) = (j.expect("a joint"), c.expect("its cold part"));
                    f(j, c, unsafe { rows.range(j.row_range()) });
                }
            });
        }
    }
}

/// The spring of a pull for substep `h`, and whether it acts in the relax pass too.
fn pull_softness(pull: Pull, joint: Softness, h: Real) -> (Softness, bool) {
    match pull {
        Pull::Joint => (joint, false),
        Pull::Spring(s) => (Softness::new(s.hertz, s.damping_ratio, h), true),
        Pull::Correct(beta) => (
            Softness {
                bias_rate: beta / h,
                mass_scale: 1.0,
                impulse_scale: 0.0,
            },
            false,
        ),
    }
}

/// Warm start: apply each joint's accumulated impulses (the sequential solver: all at once).
#[inline(never)]
pub(crate) fn warm_start(set: &JointSet, selected: Selected, bodies: &mut [SolverBody]) {
    let all = 0..selected.count(set.constraints.len());
    warm_start_span(set, selected, all, bodies);
}

/// Warm start the selected joints at positions `span` of the selection.
#[inline(never)]
fn warm_start_span(
    set: &JointSet,
    selected: Selected,
    span: std::ops::Range<usize>,
    bodies: &mut [SolverBody],
) {
    match selected {
        Selected::All => span.for_each(|k| warm_start_one(set, k, bodies)),
        Selected::Only(list) => {
            for &k in &list[span] {
                warm_start_one(set, k as usize, bodies);
            }
        }
    }
}

/// Warm start joint `k`.
#[inline(always)]
fn warm_start_one(set: &JointSet, k: usize, bodies: &mut [SolverBody]) {
    let j = &set.constraints[k];
    let (a, b) = two_mut(bodies, j.a, j.b);
    warm_start_joint(j, &set.rows[j.row_range()], (a, b));
}

/// Warm start joint `j`, with its `rows`, on its bodies `a` and `b`.
#[inline(always)]
fn warm_start_joint(j: &JointConstraint, rows: &[Row], (a, b): (&mut SolverBody, &mut SolverBody)) {
    // (Warm starting moves no body, so the pose is the same for every part.)
    if let Some(p) = &j.point {
        j.apply_point(a, b, &j.pose(a, b), p.impulse);
    }
    for row in rows {
        let lambda = row.sign() * row.impulse;
        if row.measure == Measure::Angle {
            // An angle row's Jacobian, [0, -1, 0, 1], turns the bodies only.
            a.w -= a.inv_inertia * lambda;
            b.w += b.inv_inertia * lambda;
        } else {
            let jac = jacobian(row.measure, &j.pose(a, b));
            j.apply_row(a, b, &jac, lambda);
        }
    }
}

/// One pass over the joints: `biased` (the soft bias) or a relax pass (rigid); `inv_h` is
/// 1 / substep (1/s). (The sequential solver: all at once.)
#[inline(never)]
pub(crate) fn solve(
    set: &mut JointSet,
    selected: Selected,
    bodies: &mut [SolverBody],
    biased: bool,
    inv_h: Real,
) {
    let all = 0..selected.count(set.constraints.len());
    solve_span(set, selected, all, bodies, (biased, inv_h));
}

/// Solve the selected joints at positions `span` of the selection (`pass`: biased, and
/// 1 / substep, as [`solve`]).
#[inline(never)]
fn solve_span(
    set: &mut JointSet,
    selected: Selected,
    span: std::ops::Range<usize>,
    bodies: &mut [SolverBody],
    pass: (bool, Real),
) {
    match selected {
        Selected::All => span.for_each(|k| solve_one(set, k, bodies, pass)),
        Selected::Only(list) => {
            for &k in &list[span] {
                solve_one(set, k as usize, bodies, pass);
            }
        }
    }
}

/// Solve joint `k`'s rows, then its point block (`biased`, `inv_h` as [`solve`]).
#[inline(always)]
fn solve_one(set: &mut JointSet, k: usize, bodies: &mut [SolverBody], pass: (bool, Real)) {
    let j = &mut set.constraints[k];
    let (a, b) = two_mut(bodies, j.a, j.b);
    let rows = &mut set.rows[j.row_range()];
    solve_joint(j, rows, (a, b), pass);
}

/// Solve joint `j`'s `rows`, then its point block, on its bodies `a` and `b`.
#[inline(always)]
fn solve_joint(
    j: &mut JointConstraint,
    rows: &mut [Row],
    (a, b): (&mut SolverBody, &mut SolverBody),
    pass: (bool, Real),
) {
    // An angle row's effective mass is the same at every pose: one division for all of them.
    let turn = a.inv_inertia + b.inv_inertia;
    let axial = if turn > 0.0 { 1.0 / turn } else { 0.0 };
    // (A solve pass moves no body: the joint angle is the same for every angle row.)
    let angle = j.frame.angle + b.dtheta - a.dtheta;
    for row in rows {
        if row.measure == Measure::Angle {
            solve_angle_row(row, axial, angle, (a, b), pass);
        } else {
            let pose = j.pose(a, b);
            solve_row(row, masses(a, b), (a, b), &pose, pass);
        }
    }
    if j.point.is_some() {
        let pose = j.pose(a, b);
        j.solve_point((a, b), &pose, pass.0);
    }
}

/// Where a constraint of `colour` comes in the soft step's solve order: the overflow first
/// (rank 0), then colour c (rank c + 1), Box2D v3's order.
#[inline]
pub(crate) fn solve_rank(colour: u8) -> u8 {
    if colour >= OVERFLOW {
        0
    } else {
        colour + 1
    }
}

/// What a [`JointPass`] does with each joint.
#[derive(Clone, Copy, Debug)]
pub(crate) enum JointWork {
    WarmStart,
    /// A solve pass: biased or not, and 1 / substep (1/s).
    Solve {
        biased: bool,
        inv_h: Real,
    },
}

/// One pass of the soft step over the selected joints, taken colour by colour: the contact
/// bundles call [`JointPass::run_until`] before each of their colours, so that each colour's
/// joints go just before its contacts and the overflow's before the overflow's (a joint to a
/// static body, in a top colour, then has the last word over the contacts of the colours
/// below, as in Box2D v3).
pub(crate) struct JointPass<'a> {
    set: &'a mut JointSet,
    selected: Selected<'a>,
    work: JointWork,
    /// How many of the selected joints are done.
    done: usize,
}

impl<'a> JointPass<'a> {
    /// A pass of `work` over `set`'s `selected` joints, none done yet.
    pub fn new(set: &'a mut JointSet, selected: Selected<'a>, work: JointWork) -> Self {
        JointPass {
            set,
            selected,
            work,
            done: 0,
        }
    }

    /// The selected joints not yet done whose solve rank is at most `rank`, now done: their
    /// positions in the selection.
    fn take_until(&mut self, rank: u8) -> std::ops::Range<usize> {
        let n = self.selected.count(self.set.constraints.len());
        let start = self.done;
        self.done = self.past(start..n, rank);
        start..self.done
    }

    /// The first position in `span` of the selection whose joint's solve rank is above
    /// `rank`, or the span's end. (The selection is in rank order: a binary search. Scanning
    /// took 2.9 % of a grid of 19,800 joints' step on two workers.)
    fn past(&self, span: std::ops::Range<usize>, rank: u8) -> usize {
        let ranks = &self.set.ranks;
        let beyond = match self.selected {
            Selected::All => ranks[span.clone()].partition_point(|&r| r <= rank),
            Selected::Only(list) => {
                list[span.clone()].partition_point(|&k| ranks[k as usize] <= rank)
            }
        };
        span.start + beyond
    }

    /// [`JointPass::run_until`], each colour's joints spread over `region`'s workers in
    /// blocks, one colour after another. A colour's joints share no dynamic body; a fixed body
    /// (the world, a kinematic body) is read from its row and written to a worker's own copy.
    pub fn run_until_shared(&mut self, region: &Region, bodies: &mut [SolverBody], rank: u8) {
        let span = self.take_until(rank);
        let mut start = span.start;
        while start < span.end {
            // The joints are in rank order: this colour's are a run.
            let colour = self.set.ranks[self.selected.at(start)];
            let end = self.past(start..span.end, colour);
            if end - start < JOINTS_PER_BLOCK {
                self.run_span(start..end, bodies);
            } else {
                self.run_colour_shared(region, start..end, bodies);
            }
            start = end;
        }
    }

    /// The joints at positions `span` of the selection, all of one colour, in blocks spread
    /// over `region`'s workers.
    fn run_colour_shared(
        &mut self,
        region: &Region,
        span: std::ops::Range<usize>,
        bodies: &mut [SolverBody],
    ) {
        let (selected, work, n) = (self.selected, self.work, span.len());
        // SAFETY: the joints of one colour share no dynamic body; each block reaches its own
        // joints and their rows; fixed bodies' rows are only read (below).
        let (bodies, joints, rows) = unsafe {
            (
                SharedRows::new(bodies),
                SharedSlice::new(&mut self.set.constraints),
                SharedSlice::new(&mut self.set.rows),
            )
        };
        region.for_blocks(n.div_ceil(JOINTS_PER_BLOCK), &|k| {
            for m in block(k, JOINTS_PER_BLOCK, n) {
                // SAFETY: as above.
                let j = unsafe { joints.get(selected.at(span.start + m)) }.expect("a joint");
                let jr = unsafe { rows.range(j.row_range()) };
                // A fixed body's row is read into a copy of this worker's own (many joints
                // of one colour may share it, and nothing they give it changes it).
                let (mut copy_a, mut copy_b);
                // SAFETY: as above.
                let (a, b) = unsafe {
                    let a = if bodies.inv_mass(j.a) == 0.0 {
                        copy_a = bodies.read(j.a);
                        &mut copy_a
                    } else {
                        bodies.body(j.a)
                    };
                    let b = if bodies.inv_mass(j.b) == 0.0 {
                        copy_b = bodies.read(j.b);
                        &mut copy_b
                    } else {
                        bodies.body(j.b)
                    };
                    (a, b)
                };
                match work {
                    JointWork::WarmStart => warm_start_joint(j, jr, (a, b)),
                    JointWork::Solve { biased, inv_h } => {
                        solve_joint(j, jr, (a, b), (biased, inv_h))
                    }
                }
            }
        });
    }

    /// Run the joints not yet done whose solve rank is at most `rank`.
    pub fn run_until(&mut self, bodies: &mut [SolverBody], rank: u8) {
        let span = self.take_until(rank);
        self.run_span(span, bodies);
    }

    /// Run the joints at positions `span` of the selection.
    fn run_span(&mut self, span: std::ops::Range<usize>, bodies: &mut [SolverBody]) {
        let (start, end) = (span.start, span.end);
        if end == start {
            return;
        }
        match self.work {
            JointWork::WarmStart => warm_start_span(self.set, self.selected, start..end, bodies),
            JointWork::Solve { biased, inv_h } => {
                solve_span(self.set, self.selected, start..end, bodies, (biased, inv_h))
            }
        }
    }
}

/// `x`, or zero where it is not finite or beyond [`BLOWN`]: a chain whose anchors cannot
/// meet (given in the wrong frames, 10 m apart on 0.25 m links) drove its impulses up
/// ten-thousandfold a step, to infinity and NaN within three steps; they start again from
/// zero instead, and the World stays finite.
#[inline]
fn finite_or_zero<T: FiniteOrZero>(x: T) -> T {
    x.finite_or_zero()
}

/// See [`finite_or_zero`].
trait FiniteOrZero {
    fn finite_or_zero(self) -> Self;
}

impl FiniteOrZero for Real {
    #[inline]
    fn finite_or_zero(self) -> Real {
        if self.abs() <= BLOWN {
            self
        } else {
            0.0
        }
    }
}

impl FiniteOrZero for Vec2 {
    #[inline]
    fn finite_or_zero(self) -> Vec2 {
        if self.x.abs() <= BLOWN && self.y.abs() <= BLOWN {
            self
        } else {
            Vec2::ZERO
        }
    }
}

/// The largest impulse (N s) or force (N) a joint keeps: far beyond any real load, and small
/// enough that its square, and a vector's length, stay finite in `f32`.
const BLOWN: Real = 1.0e18;

/// How many joints a worker takes at a time in the parallel step (and the fewest a span
/// must have to be spread).
const JOINTS_PER_BLOCK: usize = 32;

/// Store: the impulses back to per step, and each joint's force and torque on B (N, N m)
/// from its impulses over the substep. Spread over `region`'s workers, if given.
#[inline(never)]
pub(crate) fn store(
    set: &mut JointSet,
    selected: Selected,
    bodies: &[SolverBody],
    step: JointStep,
    region: Option<&Region>,
) {
    let (substeps, inv_h) = (step.substeps as Real, 1.0 / step.h);
    for_each_joint(set, selected, region, &|j, c, rows| {
        let pose = j.pose(&bodies[j.a as usize], &bodies[j.b as usize]);
        let (mut force, mut torque) = (Vec2::ZERO, 0.0);
        if let Some(p) = &mut j.point {
            p.impulse = finite_or_zero(p.impulse);
            force += p.impulse * inv_h;
            p.impulse *= substeps;
        }
        for row in rows {
            let jac = jacobian(row.measure, &pose);
            row.impulse = finite_or_zero(row.impulse);
            let impulse = row.sign() * row.impulse;
            force += jac.u * impulse * inv_h;
            if row.measure == Measure::Angle {
                torque += impulse * inv_h;
            }
            row.impulse *= substeps;
        }
        (c.force, c.torque) = (finite_or_zero(force), finite_or_zero(torque));
    });
}

impl Row {
    /// +1, or -1 for an upper limit (whose value is target - C).
    fn sign(&self) -> Real {
        if self.role == Role::Upper {
            -1.0
        } else {
            1.0
        }
    }
}

impl JointConstraint {
    /// Where the joint is now, from the bodies' motion since the start of the step.
    #[inline]
    fn pose(&self, a: &SolverBody, b: &SolverBody) -> Pose {
        let f = &self.frame;
        let ra = a.dq.rotate(f.ra);
        let rb = b.dq.rotate(f.rb);
        Pose {
            ra,
            rb,
            d: (b.dp - a.dp) + f.centres + rb - ra,
            angle: f.angle + b.dtheta - a.dtheta,
            axis: a.dq.rotate(f.axis),
        }
    }

    /// Solve the point block at `pose`. (Inlined into the pass: out of line it cost
    /// joint_grid, whose hinges are all point block, 5 % of its step.)
    #[inline(always)]
    fn solve_point(
        &mut self,
        (a, b): (&mut SolverBody, &mut SolverBody),
        pose: &Pose,
        biased: bool,
    ) {
        let [ma, ia, mb, ib] = masses(a, b);
        let Some(p) = &mut self.point else { return };
        let (ra, rb) = (pose.ra, pose.rb);
        let cdot = (b.v + cross_w(b.w, rb)) - (a.v + cross_w(a.w, ra));
        let s = if biased || p.always {
            p.soft
        } else {
            Softness::RIGID
        };
        let rhs = cdot + s.bias_rate * pose.d;
        let Some(solved) = block_solve([ma, ia, mb, ib], pose, rhs) else {
            return;
        };
        let old = p.impulse;
        let mut new = old - s.mass_scale * solved - s.impulse_scale * old;
        // (Squared: a rigid joint's cap is infinite, and the square root's latency held up
        // every joint of joint_grid.)
        if new.length_squared() > p.max_impulse * p.max_impulse {
            new *= p.max_impulse / new.length();
        }
        p.impulse = new;
        self.apply_point(a, b, pose, new - old);
    }

    /// Apply impulse `p` (N s) at the anchors: -p on A, +p on B.
    #[inline]
    fn apply_point(&self, a: &mut SolverBody, b: &mut SolverBody, pose: &Pose, p: Vec2) {
        let [ma, ia, mb, ib] = masses(a, b);
        a.v -= ma * p;
        a.w -= ia * cross(pose.ra, p);
        b.v += mb * p;
        b.w += ib * cross(pose.rb, p);
    }

    /// Apply impulse `lambda` along a row's Jacobian.
    #[inline]
    fn apply_row(&self, a: &mut SolverBody, b: &mut SolverBody, jac: &Jacobian, lambda: Real) {
        apply_row(masses(a, b), a, b, jac, lambda);
    }
}

/// 1 / the effective mass of a row with Jacobian `jac`, for inverse masses
/// `[mA, iA, mB, iB]`: J M^-1 J^T.
#[inline]
fn row_mass_inverse([ma, ia, mb, ib]: [Real; 4], jac: &Jacobian) -> Real {
    (ma + mb) * jac.u.length_squared() + ia * jac.ka * jac.ka + ib * jac.kb * jac.kb
}

/// K^-1 `rhs` for the point block at `pose` with inverse masses `[mA, iA, mB, iB]`
/// (K = J M^-1 J^T, 2x2, by Cramer's rule); None where K is singular.
#[inline]
fn block_solve([ma, ia, mb, ib]: [Real; 4], pose: &Pose, rhs: Vec2) -> Option<Vec2> {
    let (ra, rb) = (pose.ra, pose.rb);
    let k11 = ma + mb + ia * ra.y * ra.y + ib * rb.y * rb.y;
    let k12 = -ia * ra.x * ra.y - ib * rb.x * rb.y;
    let k22 = ma + mb + ia * ra.x * ra.x + ib * rb.x * rb.x;
    let det = k11 * k22 - k12 * k12;
    (det > 0.0).then(|| Vec2::new(k22 * rhs.x - k12 * rhs.y, k11 * rhs.y - k12 * rhs.x) / det)
}

/// Solve `row` of a joint with inverse masses `masses` at `pose`: `biased` pass or not,
/// `inv_h` 1 / substep.
fn solve_row(
    row: &mut Row,
    masses: [Real; 4],
    (a, b): (&mut SolverBody, &mut SolverBody),
    pose: &Pose,
    pass: (bool, Real),
) {
    let jac = jacobian(row.measure, pose);
    let sign = row.sign();
    let k = row_mass_inverse(masses, &jac);
    if k <= 0.0 {
        return;
    }
    let mass = 1.0 / k;
    let cdot = sign * (jac.u.dot(b.v - a.v) + jac.kb * b.w - jac.ka * a.w);
    let error = sign * (jac.value - row.target);
    let old = row.impulse;
    let new = row_impulse(row, mass, cdot, error, pass);
    row.impulse = new;
    apply_row(masses, a, b, &jac, sign * (new - old));
}

/// Solve an angle row (`axial`: 1 / (iA + iB), 0 if neither turns; `angle`: the joint angle
/// now, rad). Its Jacobian is [0, -1, 0, 1] at every pose, so it needs neither the pose nor
/// the bodies' linear velocities (as Box2D's axial rows). An upper limit's value is
/// target - angle: its signs are flipped by negation, not by a product on the chain of
/// velocity updates that every row of the joint waits on.
#[inline(always)]
fn solve_angle_row(
    row: &mut Row,
    axial: Real,
    angle: Real,
    (a, b): (&mut SolverBody, &mut SolverBody),
    pass: (bool, Real),
) {
    if axial == 0.0 {
        return;
    }
    let (relative, offset) = (b.w - a.w, angle - row.target);
    let upper = row.role == Role::Upper;
    let (cdot, error) = if upper {
        (-relative, -offset)
    } else {
        (relative, offset)
    };
    let old = row.impulse;
    let new = row_impulse(row, axial, cdot, error, pass);
    row.impulse = new;
    let lambda = if upper { old - new } else { new - old };
    a.w -= a.inv_inertia * lambda;
    b.w += b.inv_inertia * lambda;
}

/// A row's new accumulated impulse (N s, within its cap) for effective mass `mass` (kg or
/// kg m^2), velocity error `cdot` and position error `error` (both signed as the row's
/// value), in the `biased` pass or not, `inv_h` 1 / substep.
#[inline(always)]
fn row_impulse(
    row: &Row,
    mass: Real,
    cdot: Real,
    error: Real,
    (biased, inv_h): (bool, Real),
) -> Real {
    let old = row.impulse;
    let new = match row.role {
        Role::Motor(speed) => old - mass * (cdot - speed),
        Role::Hold(_) => {
            let s = if biased || row.always {
                row.soft
            } else {
                Softness::RIGID
            };
            old - mass * s.mass_scale * (cdot + s.bias_rate * error) - s.impulse_scale * old
        }
        Role::Lower | Role::Upper => {
            let (bias, s) = if error > 0.0 {
                (error * inv_h, Softness::RIGID)
            } else if biased {
                (row.soft.bias_rate * error, row.soft)
            } else {
                (0.0, Softness::RIGID)
            };
            let raw = old - mass * s.mass_scale * (cdot + bias) - s.impulse_scale * old;
            raw.max(0.0)
        }
    };
    // (Most rows have no cap: the clamp would lengthen the chain every row waits on.)
    if row.max_impulse == Real::INFINITY {
        new
    } else {
        new.clamp(-row.max_impulse, row.max_impulse)
    }
}

/// Apply impulse `lambda` along a row's Jacobian `jac` to bodies of inverse masses `masses`.
#[inline]
fn apply_row(
    [ma, ia, mb, ib]: [Real; 4],
    a: &mut SolverBody,
    b: &mut SolverBody,
    jac: &Jacobian,
    lambda: Real,
) {
    a.v -= ma * lambda * jac.u;
    a.w -= ia * lambda * jac.ka;
    b.v += mb * lambda * jac.u;
    b.w += ib * lambda * jac.kb;
}

/// Inverse masses and inertias of bodies `a` and `b`: `[mA, iA, mB, iB]`.
#[inline(always)]
fn masses(a: &SolverBody, b: &SolverBody) -> [Real; 4] {
    [a.inv_mass, a.inv_inertia, b.inv_mass, b.inv_inertia]
}

/// w x r.
#[inline]
fn cross_w(w: Real, r: Vec2) -> Vec2 {
    Vec2::new(-w * r.y, w * r.x)
}

/// A row's Jacobian and value at `pose`.
#[inline]
fn jacobian(measure: Measure, pose: &Pose) -> Jacobian {
    let along = |u: Vec2| Jacobian {
        u,
        ka: cross(pose.d + pose.ra, u),
        kb: cross(pose.rb, u),
        value: u.dot(pose.d),
    };
    match measure {
        Measure::Angle => Jacobian {
            u: Vec2::ZERO,
            ka: 1.0,
            kb: 1.0,
            value: pose.angle,
        },
        Measure::Along => along(pose.axis),
        Measure::Across => along(Vec2::new(-pose.axis.y, pose.axis.x)),
        Measure::Length => {
            let len = pose.d.length();
            // Anchors that meet have no direction: along the axis then (any will do).
            let u = if len > 1e-9 { pose.d / len } else { pose.axis };
            Jacobian {
                u,
                ka: cross(pose.ra, u),
                kb: cross(pose.rb, u),
                value: len,
            }
        }
    }
}

/// Mutable references to two distinct solver bodies, in either order.
#[inline]
fn two_mut(bodies: &mut [SolverBody], a: u32, b: u32) -> (&mut SolverBody, &mut SolverBody) {
    let (a, b) = (a as usize, b as usize);
    debug_assert!(a != b, "a joint joins two bodies");
    if a < b {
        let (lo, hi) = bodies.split_at_mut(b);
        (&mut lo[a], &mut hi[0])
    } else {
        let (lo, hi) = bodies.split_at_mut(a);
        (&mut hi[0], &mut lo[b])
    }
}
