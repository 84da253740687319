//! The small numerical kernels the locators and continuations share: vectors and dense linear
//! solves of a few unknowns, the pseudo-arclength Newton corrector, and the bracketing root
//! finders (bisection and the Illinois variant of regula falsi).
//!
//! The finders work on brackets of any kind of point `P`: a parameter along a curve (`f64`),
//! a time, or a solved orbit whose trials between the ends are found by a corrector. The
//! caller says how long a bracket is and how to find the point a given fraction of the way
//! from one end to the other; the finders decide where to look and when to stop.

/// Euclidean inner product.
pub(crate) fn dot<const N: usize>(a: [f64; N], b: [f64; N]) -> f64 {
    (0..N).map(|k| a[k] * b[k]).sum()
}

/// Euclidean norm.
pub(crate) fn norm<const N: usize>(a: [f64; N]) -> f64 {
    dot(a, a).sqrt()
}

/// `b − a`.
pub(crate) fn sub<const N: usize>(b: [f64; N], a: [f64; N]) -> [f64; N] {
    std::array::from_fn(|k| b[k] - a[k])
}

/// Solves the `N×N` system `a·x = b` by Gaussian elimination with partial pivoting; `None`
/// when a pivot is 0 or not finite, or the solution is not finite.
pub(crate) fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let piv = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col] == 0.0 || !a[piv][col].is_finite() {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let pivot_row = a[col];
        for row in col + 1..N {
            let f = a[row][col] / pivot_row[col];
            for (k, entry) in a[row].iter_mut().enumerate().skip(col) {
                *entry -= f * pivot_row[k];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Most Newton iterations of [`correct`].
const NEWTON_ITERATIONS: u32 = 12;

/// The linearisation of `N − 1` equations in `N` unknowns at a point: their Jacobian and
/// residuals in the first `N − 1` rows (the last row is left for the arclength condition).
pub(crate) type Linearised<const N: usize> = ([[f64; N]; N], [f64; N]);

/// Newton's method on `N − 1` equations in `N` unknowns with the pseudo-arclength condition
/// `t·(u − pred) = 0` (the solution lies in the hyperplane through the prediction `pred`
/// normal to `t`), from `pred`.
///
/// `eval(u)` evaluates the equations at `u`: what the caller keeps of the evaluation, and
/// `None` once the residual is small enough, else the [`Linearised`] system (`None` for the
/// whole when the evaluation fails). A step that leaves the unknowns' domain (`inside`) or
/// is not finite fails. Returns the converged point, its evaluation and the iterations used.
pub(crate) fn correct<const N: usize, V>(
    pred: [f64; N],
    t: [f64; N],
    mut eval: impl FnMut([f64; N]) -> Option<(V, Option<Linearised<N>>)>,
    inside: impl Fn(&[f64; N]) -> bool,
) -> Option<([f64; N], V, u32)> {
    let mut u = pred;
    for it in 0..NEWTON_ITERATIONS {
        let (v, lin) = eval(u)?;
        let Some((mut jac, residual)) = lin else {
            return Some((u, v, it));
        };
        jac[N - 1] = t;
        let mut rhs = residual.map(|r| -r);
        rhs[N - 1] = -dot(t, sub(u, pred));
        let d = solve(jac, rhs)?;
        for k in 0..N {
            u[k] += d[k];
        }
        if !inside(&u) || u.iter().any(|c| !c.is_finite()) {
            return None;
        }
    }
    None
}

/// What a bisection finds at a bracket's midpoint.
pub(crate) enum Mid<P> {
    /// The midpoint, on the side of the low end: it becomes the low end.
    Lo(P),
    /// The midpoint, on the side of the high end: it becomes the high end.
    Hi(P),
    /// Neither can be told (a trial failed): the bisection stops.
    Stop,
}

/// Bisection of the bracket `(lo, hi)` until `len(lo, hi) <= tol`, `max_steps` midpoints
/// or a [`Mid::Stop`]; `mid(lo, hi)` finds the midpoint and its side. Returns the final
/// bracket.
pub(crate) fn bisect<P>(
    (mut lo, mut hi): (P, P),
    tol: f64,
    max_steps: usize,
    len: impl Fn(&P, &P) -> f64,
    mut mid: impl FnMut(&P, &P) -> Mid<P>,
) -> (P, P) {
    for _ in 0..max_steps {
        if len(&lo, &hi) <= tol {
            break;
        }
        match mid(&lo, &hi) {
            Mid::Lo(p) => lo = p,
            Mid::Hi(p) => hi = p,
            Mid::Stop => break,
        }
    }
    (lo, hi)
}

/// The root of a test function between the ends `lo` and `hi` (points with the function's
/// values, of opposite signs) by the Illinois variant of regula falsi, until
/// `len(lo, hi) <= tol` or `max_steps` trials. `trial(lo, hi, f)` finds the point a fraction
/// `f ∈ (0, 1)` of the way from `lo` to `hi` and the function's value there (`None`: the
/// search fails). An end kept for a second trial in a row has its value halved.
///
/// Returns the last trial (the end with the smaller `|value|` if there was none) and the
/// final bracket's length (0 at an exact root); `None` when a trial fails or its value is not
/// finite.
pub(crate) fn illinois<P: Copy>(
    (mut lo, mut f_lo): (P, f64),
    (mut hi, mut f_hi): (P, f64),
    tol: f64,
    max_steps: usize,
    len: impl Fn(&P, &P) -> f64,
    mut trial: impl FnMut(&P, &P, f64) -> Option<(P, f64)>,
) -> Option<(P, f64)> {
    let mut best = if f_lo.abs() <= f_hi.abs() { lo } else { hi };
    // Which end the last trial replaced (−1: lo, 1: hi, 0: none yet).
    let mut replaced = 0;
    for _ in 0..max_steps {
        if len(&lo, &hi) <= tol {
            break;
        }
        let mut g = f_lo / (f_lo - f_hi);
        if !(g.is_finite() && g > 0.0 && g < 1.0) {
            g = 0.5;
        }
        let (p, fp) = trial(&lo, &hi, g)?;
        if !fp.is_finite() {
            return None;
        }
        best = p;
        if fp == 0.0 {
            return Some((p, 0.0));
        }
        if (fp < 0.0) == (f_lo < 0.0) {
            (lo, f_lo) = (p, fp);
            if replaced == -1 {
                f_hi *= 0.5;
            }
            replaced = -1;
        } else {
            (hi, f_hi) = (p, fp);
            if replaced == 1 {
                f_lo *= 0.5;
            }
            replaced = 1;
        }
    }
    Some((best, len(&lo, &hi)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_solves() {
        let x = solve(
            [[0.0, 2.0, 1.0], [1.0, 0.0, 0.0], [3.0, 1.0, 4.0]],
            [5.0, 1.0, 16.0],
        )
        .unwrap();
        // x = (1, 1, 3).
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
        assert!((x[2] - 3.0).abs() < 1e-14);
        assert!(solve(
            [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]],
            [1.0; 3]
        )
        .is_none());
        let a = [
            [2.0, 0.0, 0.0, 1.0],
            [0.0, 3.0, 0.0, 0.0],
            [1.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 4.0],
        ];
        let x = solve(a, [3.0, 3.0, 2.0, 4.0]).unwrap();
        for (got, want) in x.iter().zip([1.0, 1.0, 1.0, 1.0]) {
            assert!((got - want).abs() < 1e-15, "{x:?}");
        }
    }

    #[test]
    fn newton_stays_on_the_arclength_hyperplane() {
        // The unit circle x² + y² = 1 from the prediction (1, 0.6) with t = (0, 1): the point
        // on the line y = 0.6, (0.8, 0.6).
        let circle = |u: [f64; 2]| {
            let r = u[0] * u[0] + u[1] * u[1] - 1.0;
            let lin = (r.abs() > 1e-14).then_some(([[2.0 * u[0], 2.0 * u[1]], [0.0; 2]], [r, 0.0]));
            Some((r, lin))
        };
        let (u, r, it) = correct([1.0, 0.6], [0.0, 1.0], circle, |_| true).unwrap();
        assert!((u[0] - 0.8).abs() < 1e-14 && u[1] == 0.6, "{u:?}");
        assert!(r.abs() <= 1e-14 && it > 0);
        // The first step goes to x = 0.82: outside a domain x > 0.9.
        assert!(correct([1.0, 0.6], [0.0, 1.0], circle, |u| u[0] > 0.9).is_none());
    }

    #[test]
    fn bisection_and_illinois_find_roots_to_the_bracket() {
        let side = |&lo: &f64, &hi: &f64| {
            let m = 0.5 * (lo + hi);
            if m * m < 2.0 {
                Mid::Lo(m)
            } else {
                Mid::Hi(m)
            }
        };
        let (lo, hi) = bisect((0.0, 3.0), 1e-10, 100, |a, b| b - a, side);
        assert!(hi - lo <= 1e-10 && lo < 2.0_f64.sqrt() && hi > 2.0_f64.sqrt());
        let (lo, hi) = bisect((0.0, 3.0), 1e-10, 3, |a, b| b - a, side);
        assert_eq!((lo, hi), (1.125, 1.5));
        let f = |s: f64| s * s - 2.0;
        let (s, err) = illinois(
            (0.0, f(0.0)),
            (3.0, f(3.0)),
            1e-10,
            100,
            |a: &f64, b: &f64| (b - a).abs(),
            |&a, &b, g| {
                let s = a + g * (b - a);
                Some((s, f(s)))
            },
        )
        .unwrap();
        assert!(err <= 1e-10, "{err}");
        assert!((s - 2.0_f64.sqrt()).abs() <= 1e-10, "{s}");
        assert!(illinois(
            (0.0, -1.0),
            (1.0, 1.0),
            1e-10,
            100,
            |a, b| b - a,
            |_, _, _| Some((0.5, f64::NAN))
        )
        .is_none());
    }
}
