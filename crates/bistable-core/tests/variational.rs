//! The variational matrix through flights and impacts: against central finite differences of
//! the flow, and against the determinant identity det Φ = e^(2·impacts)·exp(−2ζτ).
#![allow(clippy::needless_range_loop)] // 2×2 matrix loops read best with indices

use bistable_core::{Event, Params, Simulator, Sinusoid, SolverOptions};

/// The paper's model shaken at `(Ω, V)`, with the mass at `(x0, v0)` at τ = 0.
fn start(omega: f64, v: f64, x0: f64, v0: f64) -> Simulator {
    let plate = Sinusoid::new(omega, v).unwrap();
    Simulator::with_state(
        Params::paper(),
        plate.into(),
        SolverOptions::default(),
        0.0,
        x0,
        v0,
    )
    .unwrap()
}

fn flow(omega: f64, v: f64, x0: f64, v0: f64, t: f64) -> (f64, f64, u64) {
    let mut sim = start(omega, v, x0, v0);
    sim.advance_to(t, &mut |_: &Event| {}).unwrap();
    let s = sim.state();
    (s.x, s.v, sim.stats().impacts)
}

#[test]
fn variational_matrix_matches_finite_differences() {
    for (omega, v, x0, v0, periods) in [
        (1.75, 0.07, 0.05, 0.02, 3.0),
        (2.5, 0.07, 0.03, -0.01, 4.0),
        (0.85, 0.11, 0.02, 0.05, 2.0),
    ] {
        let t = periods * std::f64::consts::TAU / omega;
        let mut sim = start(omega, v, x0, v0);
        sim.enable_variational();
        sim.advance_to(t, &mut |_: &Event| {}).unwrap();
        let phi = sim.variational().unwrap();
        let impacts = sim.stats().impacts;
        // Central differences at h and h/2, Richardson-extrapolated (error O(h⁴)).
        let central = |h: f64| {
            let mut fd = [[0.0; 2]; 2];
            for j in 0..2 {
                let d = if j == 0 { (h, 0.0) } else { (0.0, h) };
                let p = flow(omega, v, x0 + d.0, v0 + d.1, t);
                let m = flow(omega, v, x0 - d.0, v0 - d.1, t);
                assert_eq!(p.2, impacts, "perturbation changed the impact count");
                fd[0][j] = (p.0 - m.0) / (2.0 * h);
                fd[1][j] = (p.1 - m.1) / (2.0 * h);
            }
            fd
        };
        let (f1, f2) = (central(2e-5), central(1e-5));
        let mut fd = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                fd[i][j] = (4.0 * f2[i][j] - f1[i][j]) / 3.0;
            }
        }
        let scale = fd.iter().flatten().fold(0.0_f64, |a, b| a.max(b.abs()));
        let err = (0..2)
            .flat_map(|i| (0..2).map(move |j| (i, j)))
            .map(|(i, j)| (phi[i][j] - fd[i][j]).abs())
            .fold(0.0, f64::max)
            / scale;
        let det = phi[0][0] * phi[1][1] - phi[0][1] * phi[1][0];
        let expected = 0.85_f64.powi(2 * impacts as i32) * (-2.0 * 0.02 * t).exp();
        println!(
            "Ω={omega} V={v}: {impacts} impacts, |Φ − FD|/|Φ| = {err:.1e}, det Φ = {det:.6e} (identity {expected:.6e})"
        );
        assert!(impacts >= 2);
        assert!(err < 1e-7, "{err}");
        assert!(
            ((det - expected) / expected).abs() < 1e-10,
            "{det} vs {expected}"
        );
    }
}
