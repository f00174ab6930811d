//! The exact reference of IFToMM A02, the N-four-bar (cases/iftomm/): a scene equal to
//! [`lash_model::iftomm::n_four_bar`]'s (its formulation and the augmented Lagrangian's
//! settings aside, which `--formulation` may change) is compared against its
//! one-degree-of-freedom reduction J θ̈ = −g K cos θ ([`lash_model::iftomm::OneDof::solve`],
//! DOP853 at rtol 1e-13) mapped to every body, instead of a run of the whole mechanism: dop853
//! at rtol 1e-12 on N = 40 (81 bodies) over the published 20 s does not end within a study's
//! budget (BENCHMARKS.md), and the reduction is exact.
//!
//! ```text
//! every crank turns by θ, every coupler translates (the parallelograms, cases/iftomm/README.md):
//! crank i    centre (i + ½ cos θ, ½ sin θ),  angle θ,  velocity (−½ θ̇ sin θ, ½ θ̇ cos θ),  θ̇
//! coupler i  centre (i + ½ + cos θ, sin θ),  angle 0,  velocity (−θ̇ sin θ, θ̇ cos θ),     0
//! states     at each time: (x, y, φ) of every integrated body, then (ẋ, ẏ, φ̇), in the
//!            order of the run's extra states (Mechanism::integrated_bodies)
//! ```

use lash_model::iftomm::n_four_bar;
use lash_model::{Mechanism, Scene};

use crate::error::Error;
use crate::report::metrics::Sample;

/// An exact reference on a grid: its samples and the states of the integrated bodies.
pub(crate) type Exact = (Vec<Sample>, Vec<f64>);

/// The reference on `times` of a scene that is A02: its samples (time and a zero constraint
/// violation; no slider, no clearance joint) and the states of its integrated bodies; None
/// for any other scene, or one that does not start at t = 0.
pub(crate) fn a02_reference(scene: &Scene, t0: f64, times: &[f64]) -> Result<Option<Exact>, Error> {
    let nb = scene.bodies.len();
    if t0 != 0.0 || nb < 3 || nb.is_multiple_of(2) {
        return Ok(None);
    }
    let n = (nb - 1) / 2;
    let Some(t_end) = scene.t_end else {
        return Ok(None);
    };
    let (generated, dof) = n_four_bar(n, t_end);
    let mut s = scene.clone();
    s.formulation = generated.formulation;
    s.augmented_lagrangian = generated.augmented_lagrangian;
    if s != generated {
        return Ok(None);
    }
    let mech = Mechanism::from_scene(scene)
        .map_err(|e| Error::Internal(format!("A02's reference: {e}")))?;
    let bodies = mech.integrated_bodies();
    let solution = dof.solve(times);
    let mut states = Vec::with_capacity(6 * bodies.len() * times.len());
    let mut samples = Vec::with_capacity(times.len());
    for (&t, &[th, w]) in times.iter().zip(&solution) {
        let (sn, cs) = th.sin_cos();
        let (mut q, mut v) = (Vec::new(), Vec::new());
        for name in &bodies {
            let body = |p: &str| name.strip_prefix(p).and_then(|i| i.parse::<usize>().ok());
            if let Some(i) = body("crank") {
                q.extend([i as f64 + 0.5 * cs, 0.5 * sn, th]);
                v.extend([-0.5 * w * sn, 0.5 * w * cs, w]);
            } else if let Some(i) = body("coupler") {
                q.extend([i as f64 + 0.5 + cs, sn, 0.0]);
                v.extend([-w * sn, w * cs, 0.0]);
            } else {
                return Err(Error::Internal(format!("A02's reference: body {name}")));
            }
        }
        states.extend(q);
        states.extend(v);
        samples.push(Sample {
            t,
            ..Default::default()
        });
    }
    Ok(Some((samples, states)))
}

#[cfg(test)]
mod tests {
    //! A02's reference is the scene's own motion: its start is the assembled initial state, a
    //! run converges to it, and any other scene has none.
    use super::*;
    use crate::compare::reference::{compare_one, Reference};
    use crate::run::prepare::Prepared;
    use lash_solver::Method;

    fn a02(n: usize) -> Prepared {
        let path = format!(
            "{}/../../cases/iftomm/a02_n{n}.json",
            env!("CARGO_MANIFEST_DIR")
        );
        Prepared::load_spec(&path, None).unwrap()
    }

    #[test]
    fn the_reference_starts_at_the_assembled_state_of_n40() {
        // At t = 0 the reduction is θ = π/2, θ̇ = −1: the mapping must give the scene's
        // assembled (q, q̇) of all 81 bodies (the initial state is already consistent, so the
        // projection leaves it to rounding).
        let p = a02(40);
        let scene = p.scene().unwrap();
        let (samples, states) = a02_reference(scene, 0.0, &[0.0]).unwrap().unwrap();
        assert_eq!(samples.len(), 1);
        let y0 = Mechanism::from_scene(scene).unwrap().initial_state();
        assert_eq!(states.len(), y0.len());
        let worst = states
            .iter()
            .zip(&y0)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 1e-12, "{worst:e}");
    }

    #[test]
    fn a_run_of_n40_converges_to_the_reference() {
        // N = 40 over its first 0.5 s (crank 0 from vertical towards the first horizontal
        // position at 0.7 s): dop853 at rtol 1e-6 and 1e-10. The full run's B0 stays within
        // 8e-8 m of the reduction over 20 s at rtol 1e-10 (cases/iftomm/README.md), so the
        // relative state error must fall with rtol and be below 1e-7 at 1e-10; a wrong map
        // (a coupler turned, a crank off its pin) would leave an error of order 1e-2 or more.
        let p = a02(40);
        let r = Reference::compute(&p, Some(0.5)).unwrap();
        assert!(r.run.is_none() && r.exact.is_some(), "{}", r.how);
        assert!(r.how.contains("A02"), "{}", r.how);
        let err = |rtol| {
            let (c, _) = compare_one(&p, &r, Method::Dop853, Some(rtol), None, None).unwrap();
            c.error.unwrap()
        };
        let (loose, tight) = (err(1e-6), err(1e-10));
        assert!(tight < 1e-7 && tight < loose / 100.0, "{loose:e} {tight:e}");
    }

    #[test]
    fn any_other_scene_has_no_exact_reference() {
        // One rod 1 % heavier: no longer the benchmark, so no reduction applies.
        let p = a02(2);
        let mut scene = p.scene().unwrap().clone();
        assert!(a02_reference(&scene, 0.0, &[0.0]).unwrap().is_some());
        scene.bodies[1].mass *= 1.01;
        assert!(a02_reference(&scene, 0.0, &[0.0]).unwrap().is_none());
        // A start other than t = 0 neither.
        assert!(a02_reference(p.scene().unwrap(), 0.1, &[0.1])
            .unwrap()
            .is_none());
    }
}
