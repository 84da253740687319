//! Where to start shooting: initial guesses for periodic orbits taken from simulated
//! attractors.

/// A grid point, a period and a guess `(x, x')` at plate phase 0 to shoot from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// Index of the grid point.
    pub point: usize,
    /// Period in shaker periods.
    pub period: u32,
    /// Initial guess `(x, x')`.
    pub guess: (f64, f64),
}

/// Seeds from a simulated attractor's section points `sections` (most recent last) whose
/// period is `attractor` (`None`: aperiodic): the attractor itself for its own period, and
/// for each smaller period `q` in `periods` that divides it, the mean of the section points
/// `q` apart (where the orbit that lost stability by period doubling lies); for an aperiodic
/// attractor, the mean of all points for period 1.
pub fn seeds_from(
    point: usize,
    sections: &[(f64, f64)],
    attractor: Option<usize>,
    periods: &[u32],
) -> Vec<Seed> {
    let Some(&last) = sections.last() else {
        return Vec::new();
    };
    let mean = |pts: &mut dyn Iterator<Item = (f64, f64)>| {
        let (mut sx, mut sv, mut n) = (0.0, 0.0, 0.0);
        for (x, v) in pts {
            sx += x;
            sv += v;
            n += 1.0;
        }
        (sx / n, sv / n)
    };
    let mut out = Vec::new();
    for &q in periods {
        let qu = q as usize;
        let guess = match attractor {
            Some(p) if p == qu => last,
            Some(p) if p > qu && p.is_multiple_of(qu) && sections.len() >= p => {
                mean(&mut sections[sections.len() - p..].iter().step_by(qu).copied())
            }
            None if q == 1 => mean(&mut sections.iter().copied()),
            _ => continue,
        };
        out.push(Seed {
            point,
            period: q,
            guess,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_of_periodic_and_aperiodic_attractors() {
        let p2: Vec<(f64, f64)> = (0..8)
            .map(|i| if i % 2 == 0 { (0.1, 0.2) } else { (0.3, -0.2) })
            .collect();
        let s = seeds_from(3, &p2, Some(2), &[1, 2, 4]);
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].point, s[0].period), (3, 1));
        assert!((s[0].guess.0 - 0.2).abs() < 1e-15 && s[0].guess.1.abs() < 1e-15);
        assert_eq!(s[1].guess, (0.3, -0.2)); // the most recent point
        assert_eq!(seeds_from(0, &p2, None, &[1, 2]).len(), 1);
        assert!(seeds_from(0, &[], Some(1), &[1]).is_empty());
    }
}
