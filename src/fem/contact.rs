//! Rigid flat platen with kinematic (velocity-constraint) contact.
//!
//! The top platen sits at `z_p(t) = z₀ − u(t)` (a bottom platen, plane-strain runs only, at
//! `z₀ + u(t)`); u follows a smooth cubic ramp of the velocity,
//! `u̇ = V (3τ² − 2τ³)`, τ = t/t_r < 1, then the constant speed V. After each velocity update, a
//! surface node whose predicted position would pass the platen gets the normal velocity that puts
//! it exactly on the platen at the end of the step; the normal impulse `m Δv_z` is the platen
//! reaction. A node moving away is released without any force (no adhesion). Coulomb friction:
//! the tangential velocity is removed up to the impulse `μ |m Δv_z|` (stick), otherwise reduced
//! by it (slip).
//!
//! Why kinematic rather than penalty: a rigid flat platen makes the constraint exact and
//! parameter-free; a penalty stiffness would add a tuning constant, a compliance that shifts
//! the force–displacement curve, and a tighter stable time step.

/// The moving platen.
#[derive(Debug, Clone, Copy)]
pub struct Platen {
    /// Initial height (m).
    pub z0: f64,
    /// Speed after the ramp (m/s).
    pub speed: f64,
    /// Ramp duration (s).
    pub ramp: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
    /// Whether the platen acts.
    pub active: bool,
    /// −1 for the top platen (moves down, keeps nodes below it), +1 for a bottom platen.
    pub sign: f64,
}

impl Platen {
    /// A top platen touching height `z0` from above.
    pub fn new(z0: f64, speed: f64, ramp: f64, friction: f64) -> Self {
        Platen { z0, speed, ramp, friction, active: true, sign: -1.0 }
    }

    /// A bottom platen touching height `z0` from below and moving up.
    pub fn bottom(z0: f64, speed: f64, ramp: f64, friction: f64) -> Self {
        Platen { sign: 1.0, ..Platen::new(z0, speed, ramp, friction) }
    }

    /// Platen displacement u(t) (m, downward).
    pub fn displacement(&self, t: f64) -> f64 {
        if t <= 0.0 {
            return 0.0;
        }
        if t < self.ramp {
            let tau = t / self.ramp;
            self.speed * self.ramp * (tau.powi(3) - 0.5 * tau.powi(4))
        } else {
            self.speed * (0.5 * self.ramp + (t - self.ramp))
        }
    }

    /// Platen speed u̇(t) (m/s).
    pub fn velocity(&self, t: f64) -> f64 {
        if t <= 0.0 {
            0.0
        } else if t < self.ramp {
            let tau = t / self.ramp;
            self.speed * tau * tau * (3.0 - 2.0 * tau)
        } else {
            self.speed
        }
    }

    /// Applies the constraint at the end of a step to `t_new`; returns the normal impulse on
    /// the particle per radian (N s, positive = compression).
    #[allow(clippy::too_many_arguments)]
    pub fn constrain(&self, t_new: f64, dt: f64, surface: &[u32], x: &[[f64; 2]], v: &mut [[f64; 2]], mass: &[f64], fix_r: &[bool]) -> f64 {
        let zp = self.z0 + self.sign * self.displacement(t_new);
        let mut impulse = 0.0;
        for &i in surface {
            let i = i as usize;
            let z_pred = x[i][1] + dt * v[i][1];
            if self.sign * (z_pred - zp) < 0.0 {
                let vz = (zp - x[i][1]) / dt;
                let dvz = (v[i][1] - vz).abs();
                v[i][1] = vz;
                let jn = mass[i] * dvz;
                impulse += jn;
                if self.friction > 0.0 && !fix_r[i] {
                    let jt = mass[i] * v[i][0].abs();
                    let limit = self.friction * jn;
                    if jt <= limit {
                        v[i][0] = 0.0;
                    } else {
                        v[i][0] -= v[i][0].signum() * limit / mass[i];
                    }
                }
            }
        }
        impulse
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_smooth_and_integrates() {
        let p = Platen::new(0.0, 2.0, 1e-3, 0.0);
        // u' = v at several times (central difference).
        for &t in &[2e-4, 5e-4, 9.9e-4, 1.5e-3] {
            let h = 1e-8;
            let fd = (p.displacement(t + h) - p.displacement(t - h)) / (2.0 * h);
            assert!((fd - p.velocity(t)).abs() < 1e-6, "t {t}: {fd} vs {}", p.velocity(t));
        }
        assert!((p.velocity(1e-3) - 2.0).abs() < 1e-12);
        assert!((p.displacement(1e-3) - 1e-3).abs() < 1e-15);
    }
}
