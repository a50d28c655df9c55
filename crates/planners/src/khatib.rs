//! The classic potential field: O. Khatib, "Real-time obstacle avoidance
//! for manipulators and mobile robots", IJRR 5(1), 1986, as Ko & Choi
//! ("A New Approach to Moving Obstacle Avoidance Problem of a Mobile Robot")
//! use it in their case 7: the
//! `vdf` planner with alpha = beta -> infinity, i.e. with the outward speed
//! ignored and the virtual distance equal to the real gap d (eq 1):
//!
//! ```text
//! U_o = eta/2 (1/d - 1/eps_d)^2, d <= eps_d; 0 beyond     (Ko & Choi 7, vd = d)
//! U_g = zeta/2 ||P - P_g||^2                               (8)
//! ```
//!
//! Everything else is `vdf`'s: the gradient (9), the driving force under
//! the acceleration and velocity limits with the carried-over inertial term
//! (10)-(21), the goal test (22); see [`crate::vdf`] for the readings.
//! Khatib's own paper drives a manipulator by operational-space control;
//! here the force goes through Ko & Choi's point-mass driving law so that
//! `khatib` and `vdf` differ only by the outward speed, as case 7 compares.
//! The per-body diagnostic is `d_<id>`, the real gap.
//!
//! Parameters (defaults: Ko & Choi cases 4-7, in cm): `eta` (10^4), `zeta`
//! (2), `eps_d` (40, the field's range, Khatib's rho_0).

use crate::vdf::Vdf;
use crate::{ParamError, ParamReader, Params};

/// Builds Khatib's field from `eta`, `zeta`, `eps_d`.
pub fn khatib_from_params(params: &Params) -> Result<Vdf, ParamError> {
    let mut r = ParamReader::new("khatib", params);
    let eta = r.non_negative("eta", 1e4)?;
    let zeta = r.non_negative("zeta", 2.0)?;
    let eps_d = r.positive("eps_d", 40.0)?;
    r.finish()?;
    Ok(Vdf::khatib(eta, zeta, eps_d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ParamValue;

    #[test]
    fn reads_its_three_parameters_and_refuses_vdf_ones() {
        let mut p = Params::new();
        p.insert("eps_d".into(), ParamValue::Number(30.0));
        let k = khatib_from_params(&p).unwrap();
        assert_eq!((k.eta, k.zeta, k.eps_vd), (1e4, 2.0, 30.0));
        assert!(!k.use_outward_speed);
        p.insert("alpha".into(), ParamValue::Number(5.0));
        assert!(khatib_from_params(&p).is_err());
    }
}
