//! Soft constraints: a constraint as a damped spring tuned in hertz and damping ratio, so its
//! stiffness does not depend on the step or the iteration count (Catto, "Solver2D").

use crate::physics::math::{Real, PI};

/// Soft constraint coefficients for a spring of `hertz` with damping ratio `zeta`, stepped at h.
///
/// With omega = 2 pi f: bias_rate = omega / (2 zeta + h omega), and the impulse is
/// -m_eff mass_scale (vn + bias_rate s) - impulse_scale P_accumulated, where
/// mass_scale = h omega (2 zeta + h omega) / (1 + h omega (2 zeta + h omega)) and
/// impulse_scale = 1 / (1 + h omega (2 zeta + h omega)) (Catto, "Solver2D", soft step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Softness {
    pub bias_rate: Real,
    pub mass_scale: Real,
    pub impulse_scale: Real,
}

impl Softness {
    /// A rigid constraint: full correction, no compliance.
    pub const RIGID: Softness = Softness {
        bias_rate: 0.0,
        mass_scale: 1.0,
        impulse_scale: 0.0,
    };

    /// Coefficients for stiffness `hertz` (Hz), damping ratio `zeta`, substep `h` (s).
    pub fn new(hertz: Real, zeta: Real, h: Real) -> Softness {
        if hertz == 0.0 {
            return Softness::RIGID;
        }
        let omega = 2.0 * PI * hertz;
        let a1 = 2.0 * zeta + h * omega;
        let a2 = h * omega * a1;
        let a3 = 1.0 / (1.0 + a2);
        Softness {
            bias_rate: omega / a1,
            mass_scale: a2 * a3,
            impulse_scale: a3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softness_matches_the_spring_damper_closed_form() {
        // f = 30 Hz, zeta = 10, h = 1/240 s
        let h: Real = 1.0 / 240.0;
        let s = Softness::new(30.0, 10.0, h);
        let omega = 2.0 * PI * 30.0;
        let a1 = 2.0 * 10.0 + h * omega;
        assert!((s.bias_rate - omega / a1).abs() < 1e-4);
        let a2 = h * omega * a1;
        assert!((s.mass_scale - a2 / (1.0 + a2)).abs() < 1e-6);
        assert!((s.impulse_scale - 1.0 / (1.0 + a2)).abs() < 1e-6);
        // a rigid limit: infinitely stiff springs have mass_scale -> 1, impulse_scale -> 0
        let rigid = Softness::new(1e9, 1.0, h);
        assert!(rigid.mass_scale > 0.999 && rigid.impulse_scale < 1e-3);
    }
}
