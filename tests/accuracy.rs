//! CI-sized accuracy checks: every closed-form case at dt = 1/60 with both solvers' defaults
//! (`Settings::sequential()`: 10 iterations; `Settings::soft_step()`: 4 substeps), plus the two
//! scenes without a closed form against their reference runs. The full sweep over dt,
//! iterations and substeps is `tiltbox report`.
//!
//! Each tolerance says where it comes from. h is the integration step: dt for the sequential
//! solver, dt / substeps for the soft step (`accuracy::integration_step`).
#![cfg(feature = "measure")]

use tiltbox::measure::accuracy::reference::{self, ReferenceCase};
use tiltbox::measure::accuracy::{closed_form, integration_step, Measurement};
use tiltbox::physics::{Real, Settings};

const DT: Real = 1.0 / 60.0;

fn solvers() -> [Settings; 2] {
    [Settings::sequential(), Settings::soft_step()]
}

fn show(s: &Settings, m: &Measurement) -> String {
    format!(
        "{} {}: error {} {} ({}), diverged {}, details {:?}",
        tiltbox::measure::accuracy::config_label(s),
        m.case,
        m.error,
        m.unit,
        m.error_meaning,
        m.diverged,
        m.details
    )
}

fn run(case: fn(&Settings, Real) -> Measurement, s: &Settings, dt: Real) -> Measurement {
    let m = case(s, dt);
    println!("{}", show(s, &m));
    assert!(!m.diverged, "{}", show(s, &m));
    m
}

/// Run `case` at [`DT`] with each solver's defaults, and `check` what it measured.
fn each_solver(case: fn(&Settings, Real) -> Measurement, check: impl Fn(&Settings, &Measurement)) {
    for s in solvers() {
        check(&s, &run(case, &s, DT));
    }
}

/// The headline error is below `bound` (in the case's unit).
fn assert_error_below(s: &Settings, m: &Measurement, bound: f64) {
    assert!(m.error < bound, "{}", show(s, m));
}

/// Semi-implicit Euler under a constant acceleration a is ahead by a t h / 2 at time t: at
/// t = 1 s the error is below twice that, a h (a from the case's `expected a`).
fn assert_first_order_under_constant_acceleration(s: &Settings, m: &Measurement) {
    let a = m.detail("expected a (m/s^2)").unwrap();
    assert_error_below(s, m, a * 1.0 * integration_step(s, DT));
}

#[test]
fn free_fall_matches_semi_implicit_euler_exactly_and_converges_first_order() {
    each_solver(closed_form::free_fall, |s, m| {
        // Semi-implicit Euler's exact discrete answer; what is left is f32 rounding: the spacing
        // of f32 at y = 100 m is 7.6e-6 m, accumulated over at most 240 position updates.
        let discrete = m.detail("error vs discrete exact form (m)").unwrap();
        assert!(discrete < 1e-3, "{}", show(s, m));
        // Against the continuous answer the error is g t h / 2 (first order in h).
        let predicted = 0.5 * 9.81 * 1.0 * integration_step(s, DT);
        assert!((m.error - predicted).abs() < 1e-3, "{}", show(s, m));
        // Halving dt halves the error (first order), to within rounding.
        let half = run(closed_form::free_fall, s, DT / 2.0);
        let ratio = half.error / m.error;
        assert!(
            (ratio - 0.5).abs() < 0.05,
            "ratio {ratio}: {}",
            show(s, &half)
        );
    });
}

#[test]
fn slide_to_a_stop_covers_v0_squared_over_2_mu_g() {
    each_solver(closed_form::slide_to_stop, |s, m| {
        // Semi-implicit Euler overshoots or undershoots a constant deceleration by about
        // v0 h / 2; allow twice that (v0 = 5 m/s).
        assert_error_below(s, m, 5.0 * integration_step(s, DT));
        // The stop is detected on the step grid: within two steps of v0 / (mu g).
        let t = m.detail("stop time (s)").unwrap();
        let t_expected = m.detail("expected stop time (s)").unwrap();
        assert!((t - t_expected).abs() < 2.0 * DT as f64, "{}", show(s, m));
    });
}

#[test]
fn slope_below_the_friction_angle_sticks() {
    // Static friction holds exactly in the continuous model; allow 1 mm over 2 s
    // (a fifth of the soft step's 5 mm slop), i.e. no visible creep.
    each_solver(closed_form::slope_stick, |s, m| {
        assert_error_below(s, m, 1e-3)
    });
}

#[test]
fn slope_above_the_friction_angle_slides_at_g_sin_minus_mu_cos() {
    // a = 3.2 m/s^2.
    each_solver(
        closed_form::slope_slide,
        assert_first_order_under_constant_acceleration,
    );
}

#[test]
fn disc_rolls_without_slipping_at_two_thirds_g_sin_theta() {
    each_solver(closed_form::disc_rolls, |s, m| {
        // As for the sliding box (a = 3.27 m/s^2).
        assert_first_order_under_constant_acceleration(s, m);
        // Rolling: the contact point is at rest. Friction is solved against the velocity the
        // integrator produced, so the residue is bounded by one integration step's worth of
        // gravity, g h (0.16 m/s for the sequential solver, 0.041 m/s for the soft step;
        // measured: 0 and 0.037 m/s), against a speed of 3.3 m/s.
        let slip = m.detail("slip speed v + omega r (m/s)").unwrap();
        assert!(
            slip.abs() < 9.81 * integration_step(s, DT),
            "{}",
            show(s, m)
        );
    });
}

#[test]
fn disc_below_the_rolling_friction_bound_slides_and_spins_up() {
    each_solver(closed_form::disc_slides, |s, m| {
        assert_first_order_under_constant_acceleration(s, m);
        // Spin from kinetic friction: omega = alpha t, first order in h like the position
        // (alpha = 3.4 rad/s^2); allow alpha * 2h on top of 1 %.
        let h = integration_step(s, DT);
        let w = m.detail("spin |omega| at 1 s (rad/s)").unwrap();
        let w_expected = m.detail("expected spin alpha t (rad/s)").unwrap();
        assert!(
            (w - w_expected).abs() < 0.01 * w_expected + w_expected * 2.0 * h,
            "{}",
            show(s, m)
        );
        // And it does slip: the contact point moves at (a - alpha r) t = 2.3 m/s.
        let slip = m.detail("slip speed v + omega r (m/s)").unwrap();
        assert!(slip > 1.0, "{}", show(s, m));
    });
}

#[test]
fn bounce_rebounds_to_e_squared_of_the_drop_height() {
    // Rapier's restitution test accepts +-0.05 on the rebound height ratio.
    each_solver(closed_form::bounce, |s, m| assert_error_below(s, m, 0.05));
}

#[test]
fn head_on_conserves_momentum_and_obeys_the_restitution_law() {
    each_solver(closed_form::head_on, |s, m| {
        // Both are exact for one contact solved with restitution; what is left is f32
        // rounding of speeds of a few m/s (spacing ~5e-7).
        assert_error_below(s, m, 1e-3);
        let p = m.detail("momentum error (kg m/s)").unwrap();
        assert!(p < 1e-3, "{}", show(s, m));
    });
}

#[test]
fn constant_torque_spins_up_at_tau_over_i() {
    // Semi-implicit Euler integrates a constant angular acceleration exactly in omega;
    // only f32 rounding (omega ~ 2 rad/s, spacing 2.4e-7, <= 240 additions) remains.
    each_solver(closed_form::spin, |s, m| assert_error_below(s, m, 1e-4));
}

#[test]
fn resting_stack_of_10_neither_sinks_nor_drifts() {
    each_solver(closed_form::resting_stack, |s, m| {
        let slop = s.linear_slop as f64;
        // Box2D's allowance for a resting contact is the slop; for the whole 10-box stack we
        // allow twice that, beyond which the overlap is visible.
        let sink = m.detail("top sinking (m)").unwrap();
        assert!(sink.abs() < 2.0 * slop, "{}", show(s, m));
        // An aligned stack has no sideways force at all: any drift is a solver artefact.
        let drift = m.detail("largest top drift during run (m)").unwrap();
        assert!(drift < 1e-3, "{}", show(s, m));
    });
}

fn reference_check(case: ReferenceCase, s: &Settings) -> Measurement {
    let baseline = reference::reference_run(case, s);
    let m = reference::compare(&reference::run(case, s, DT), &baseline);
    println!("{}", show(s, &m));
    assert!(!m.diverged, "{}", show(s, &m));
    assert!(!baseline.diverged, "reference diverged: {baseline:?}");
    // Contacts are found up to the speculative distance (4 x slop) ahead; an overlap deeper
    // than that means a contact was resolved late.
    let slop = s.linear_slop as f64;
    let pen = m.detail("largest penetration (m)").unwrap();
    assert!(pen < 4.0 * slop, "{}", show(s, &m));
    // Contacts only remove energy (restitution <= 1): a gain of more than 1 % is the solver
    // adding energy.
    let drift = m.detail("energy drift (relative)").unwrap();
    assert!(drift < 0.01, "{}", show(s, &m));
    m
}

#[test]
fn falling_bricks_stays_bounded_against_its_reference() {
    for s in solvers() {
        let m = reference_check(ReferenceCase::FallingBricks, &s);
        // Chaotic after the first collisions, so no convergence order; the bricks must still
        // end up in the same region as the reference run (1 m RMS in a 10 m box).
        assert!(m.error < 1.0, "{}", show(&s, &m));
    }
}

#[test]
fn pyramid_of_20_settles_like_its_reference() {
    for s in solvers() {
        let m = reference_check(ReferenceCase::Pyramid20, &s);
        // The pyramid only settles: positions should agree with the fine reference to within
        // the overlap two resting contacts may have (2 x slop).
        assert!(m.error < 2.0 * s.linear_slop as f64, "{}", show(&s, &m));
    }
}
