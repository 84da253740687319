//! Shared by the quick (`stress.rs`) and long (`stress_long.rs`) stress tests: a deterministic
//! generator and the random-run property check.
// Each test binary compiles this module and uses a part of it.
#![allow(dead_code)]

use std::time::{Duration, Instant};

use bistable_core::{
    ChatterRule, Event, GapAudit, Impact, Params, SimError, Simulator, Sinusoid, SolverOptions,
};

/// xorshift64*: a small deterministic generator, so that failures reproduce.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in `[0, 1)`.
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[a, b)`.
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// `|w⁺ + e·w⁻| / (|v⁻| + |v⁺| + |ż|)`: how far an impact is from the restitution law, relative
/// to the velocities involved (rounding is a few 1e-16).
pub fn impact_law_residual(i: &Impact, e: f64) -> f64 {
    let (wm, wp) = (i.v_before - i.zdot, i.v_after - i.zdot);
    let scale = i.v_before.abs() + i.v_after.abs() + i.zdot.abs();
    (wp + e * wm).abs() / scale.max(1e-300)
}

/// What a batch of random runs saw.
#[derive(Debug, Default)]
pub struct Summary {
    pub runs: u64,
    pub impacts: u64,
    pub sticks: u64,
    /// Runs stopped by the Zeno guard (a typed error, not a hang).
    pub zeno: u64,
    /// Most negative sampled gap (penetration), absolute.
    pub worst_gap: f64,
    /// Most negative sampled gap relative to the bound `1 + V/Ω + |x0|`.
    pub worst_gap_rel: f64,
    /// Largest `|w⁺ + e·w⁻| / (|v⁻| + |v⁺| + |ż|)` over all impacts.
    pub worst_law: f64,
    /// Most integration steps in one run.
    pub worst_steps: u64,
    /// Longest wall time of one run.
    pub worst_time: Duration,
}

impl Summary {
    /// Adds the counts of `other` and keeps the worse of each worst figure.
    pub fn merge(&mut self, other: &Summary) {
        self.runs += other.runs;
        self.impacts += other.impacts;
        self.sticks += other.sticks;
        self.zeno += other.zeno;
        self.worst_gap = self.worst_gap.min(other.worst_gap);
        self.worst_gap_rel = self.worst_gap_rel.min(other.worst_gap_rel);
        self.worst_law = self.worst_law.max(other.worst_law);
        self.worst_steps = self.worst_steps.max(other.worst_steps);
        self.worst_time = self.worst_time.max(other.worst_time);
    }
}

/// `runs` random cases over ζ ∈ [0, 0.5], e ∈ [0, 1] (every tenth e = 0), Ω ∈ [0.01, 50]
/// (log-uniform), V ∈ [0, 2], tol ∈ [1e-16, 1e-8] (log-uniform), random start on or above the
/// plate, each simulated for `duration` time units. Panics on the first violated property:
/// non-finite state, mass below the plate beyond 1e-12·(1 + V/Ω + |x0|), an impact that does
/// not satisfy the impact law or its energy change to rounding, more than 5000 steps per time
/// unit, or any error other than the Zeno guard. Case `k` uses `rules[k % rules.len()]`.
pub fn random_runs(seed: u64, runs: u64, duration: f64, rules: &[ChatterRule]) -> Summary {
    let mut rng = Rng(seed);
    let mut s = Summary::default();
    for case in 0..runs {
        let zeta = rng.range(0.0, 0.5);
        let e = if case % 10 == 0 {
            0.0
        } else {
            rng.range(0.0, 1.0)
        };
        let omega = 10f64.powf(rng.range(-2.0, 1.7)); // 0.01 … 50
        let v = rng.range(0.0, 2.0);
        let tol = 10f64.powf(rng.range(-16.0, -8.0));
        let plate = Sinusoid::new(omega, v).unwrap();
        let t0 = rng.range(0.0, 10.0);
        let z0 = v / omega * (omega * t0).sin();
        let x0 = z0 + rng.range(0.0, 1.0).powi(3);
        let v0 = rng.range(-1.0, 1.0);
        let params = Params::new(zeta, e).unwrap();
        let opts = SolverOptions::new(tol, rules[(case % rules.len() as u64) as usize])
            .unwrap()
            .with_max_chatter_impacts(10_000)
            .unwrap();
        let what =
            format!("seed {seed:#x} case {case}: ζ={zeta} e={e} Ω={omega} V={v} tol={tol} rule={:?} t0={t0} x0={x0} v0={v0}", opts.chatter());
        let mut sim = Simulator::with_state(params, plate.into(), opts, t0, x0, v0).unwrap();
        let mut audit = GapAudit::new(8);
        let start = Instant::now();
        match sim.advance_to(t0 + duration, &mut audit) {
            Ok(()) => {}
            Err(SimError::Zeno { .. }) => s.zeno += 1,
            Err(err) => panic!("{what}: {err}"),
        }
        s.worst_time = s.worst_time.max(start.elapsed());
        s.runs += 1;
        let st = sim.state();
        assert!(st.x.is_finite() && st.v.is_finite(), "{what}: {st:?}");
        let scale = 1.0 + v / omega + x0.abs();
        assert!(st.gap() >= -1e-12 * scale, "{what}: gap {}", st.gap());
        assert!(
            audit.worst.0 >= -1e-12 * scale,
            "{what}: sampled gap {:?}",
            audit.worst
        );
        s.worst_gap = s.worst_gap.min(audit.worst.0);
        s.worst_gap_rel = s.worst_gap_rel.min(audit.worst.0 / scale);
        let steps = sim.stats().steps;
        assert!(
            steps as f64 <= 5000.0 * duration,
            "{what}: {:?}",
            sim.stats()
        );
        s.worst_steps = s.worst_steps.max(steps);
        for ev in &audit.events {
            match ev {
                Event::Impact(i) => {
                    s.impacts += 1;
                    let law = impact_law_residual(i, e);
                    s.worst_law = s.worst_law.max(law);
                    let scale = i.v_before.abs() + i.v_after.abs() + i.zdot.abs();
                    assert!(
                        i.v_before - i.zdot <= 1e-15 * scale,
                        "{what}: approaching from below {i:?}"
                    );
                    assert!(law <= 4e-16, "{what}: impact law {law:e}");
                    let dk = 0.5 * (i.v_after.powi(2) - i.v_before.powi(2));
                    assert!((dk - i.delta_k).abs() <= 1e-15 * (1.0 + i.v_before.powi(2)));
                }
                Event::StickStart { .. } => s.sticks += 1,
                _ => {}
            }
        }
    }
    s
}
