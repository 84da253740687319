//! A plate rebuilt from samples of its position and velocity `(z, ż)` taken at known instants
//! (a co-simulation host's communication points), for the step that follows the newest sample.
//!
//! The piece over `[t_k, t_k + h]` is the Hermite polynomial through the newest `m` samples —
//! `m ≤ `[`MAX_NODES`], degree `2m − 1 ≤ 5` — extrapolated over the step, plus a cubic blend that
//! starts it exactly at the plate's current position and velocity and vanishes (with its slope)
//! at the step's end. For a smooth plate sampled every `h` the quintic (`m = 3`) is off by
//! `≈ h⁶ |z⁽⁶⁾| / 20` in position, `O(h⁵)` in velocity and `O(h⁴)` in acceleration, and the
//! mismatch the blend removes is of the same size, so the plate's acceleration (which decides
//! sticking and release through the contact force) converges too.
//!
//! The order is chosen by how well each order would have predicted the newest sample from the
//! ones before it, its miss `|p_m(t_k) − z_k| + h_k |p_m'(t_k) − ż_k|`, over the orders that can
//! be checked that way (`m + 1` usable samples): starting from `m = 1`, a higher order is taken
//! when its miss is at least 8 times smaller than the best lower order's. A smooth plate sampled
//! finely enough (`hΩ` below about 0.5) gets the quintic, whose miss is some hundred times
//! smaller than the cubic's; samples with noise keep a low order, because the higher orders
//! amplify noise (about 2, 15 and 67 times in position for `m = 1, 2, 3`, and 1, 37 and 205 times
//! per `h` in velocity) and so miss by more, and the factor 8 keeps a lucky small miss from
//! picking them.
//!
//! Rules for samples that do not come from a smooth motion (all of them keep the plate continuous
//! in position and velocity, and the core detects every contact with the moving plate, so the
//! plate never passes through the mass):
//! - Two consecutive samples are *joined* when the position change agrees with the trapezoidal
//!   integral of the velocities: `|Δz − h(ż₀ + ż₁)/2| ≤ ¼ h (|ż₀ + ż₁|/2 + |Δż|)` plus a few
//!   ulps of `z` (a smooth motion misses by `h³|z‴|/12`). A sample not joined to its predecessor
//!   (a step in `z`, noise larger than the motion over one step) starts a new history: the
//!   piece is then `z_k + ż_k s`, and the blend carries the plate to it within the step.
//! - An older sample is used only while its spacing to the next one is within `[h/4, 4h]` of
//!   the coming step `h`, so that nearly coincident instants (a 1e-9 s step before a 0.01 s
//!   one) cannot amplify rounding into the higher coefficients.
//! - When the blend does not fit into doubles (a step shorter than about `1e-100` time units),
//!   only the start position and velocity are imposed and the mismatch is left to the next step.

use crate::params::ParamError;
use crate::shaker::{PolyPiece, MAX_POLY_DEGREE};
use crate::time::Instant;

/// Most samples one piece is built from (degree `2·3 − 1 = 5 = MAX_POLY_DEGREE`).
pub const MAX_NODES: usize = MAX_POLY_DEGREE.div_ceil(2);

/// How many times smaller its miss of the newest sample must be for an order to be preferred
/// to the best lower one (see the module documentation).
const GAIN: f64 = 8.0;

/// Samples kept: one more than [`MAX_NODES`], to check the highest order on the newest sample.
pub const MAX_SAMPLES: usize = MAX_NODES + 1;

/// Plate position and velocity at an instant (nondimensional).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Instant of the sample.
    pub t: Instant,
    /// Plate position.
    pub z: f64,
    /// Plate velocity.
    pub zdot: f64,
}

/// The newest samples of a sampled plate, oldest first; `joined[i]` tells whether sample `i`
/// continues sample `i − 1` smoothly (see the module documentation). Invariants: the first `n`
/// slots hold the samples, strictly increasing in time, and `joined[0]` is `false`.
#[derive(Debug, Clone, Copy, Default)]
pub struct SampleHistory {
    samples: [Sample; MAX_SAMPLES],
    joined: [bool; MAX_SAMPLES],
    n: usize,
}

impl PartialEq for SampleHistory {
    /// The same stored samples and flags (the unused slots do not count).
    fn eq(&self, other: &Self) -> bool {
        self.entries().eq(other.entries())
    }
}

/// Why a sample was refused.
fn refuse(name: &'static str, value: f64, rule: &'static str) -> ParamError {
    ParamError { name, value, rule }
}

impl SampleHistory {
    /// An empty history.
    pub fn new() -> Self {
        Self::default()
    }

    /// A history from saved entries `(sample, joined)`, oldest first; `None` unless the
    /// entries are at most [`MAX_SAMPLES`], finite, strictly increasing in time, and the oldest
    /// is not marked joined.
    pub fn from_entries(entries: &[(Sample, bool)]) -> Option<Self> {
        if entries.len() > MAX_SAMPLES {
            return None;
        }
        let finite = entries
            .iter()
            .all(|(s, _)| s.z.is_finite() && s.zdot.is_finite());
        let increasing = entries.windows(2).all(|w| w[1].0.t > w[0].0.t);
        if !finite || !increasing || entries.first().is_some_and(|e| e.1) {
            return None;
        }
        let mut h = Self::new();
        for (i, &(s, joined)) in entries.iter().enumerate() {
            (h.samples[i], h.joined[i]) = (s, joined);
        }
        h.n = entries.len();
        Some(h)
    }

    /// The stored samples with their `joined` flags, oldest first.
    pub fn entries(&self) -> impl Iterator<Item = (Sample, bool)> + '_ {
        self.samples[..self.n]
            .iter()
            .copied()
            .zip(self.joined[..self.n].iter().copied())
    }

    /// The newest sample.
    pub fn newest(&self) -> Option<Sample> {
        self.n.checked_sub(1).map(|i| self.samples[i])
    }

    /// Adds a sample after the newest one (the oldest beyond [`MAX_SAMPLES`] is dropped). A
    /// sample at the instant of the newest one replaces it: the host's latest values for that
    /// instant (a step that made no progress, e.g. an FMI 3.0 early return at its start).
    #[inline(always)]
    pub fn push(&mut self, s: Sample) -> Result<(), ParamError> {
        let p = self.prepare(s)?;
        self.commit(p);
        Ok(())
    }

    /// `s` checked as [`SampleHistory::push`] checks it, ready to be added by
    /// [`SampleHistory::commit`]; the history is not changed.
    #[inline(always)]
    pub(crate) fn prepare(&self, s: Sample) -> Result<Prepared, ParamError> {
        if !s.z.is_finite() {
            return Err(refuse("plate_sample_z", s.z, "must be finite"));
        }
        if !s.zdot.is_finite() {
            return Err(refuse("plate_sample_zdot", s.zdot, "must be finite"));
        }
        let n = self.n;
        let replaces = n > 0 && self.samples[n - 1].t == s.t;
        let kept = n - usize::from(replaces);
        let joined = match kept.checked_sub(1).map(|i| self.samples[i]) {
            Some(prev) => {
                let h = s.t.since(prev.t);
                if h.is_nan() || h <= 0.0 {
                    return Err(refuse(
                        "plate_sample_time",
                        s.t.to_f64(),
                        "must be after the previous sample",
                    ));
                }
                joins(&prev, &s, h)
            }
            None => false,
        };
        Ok(Prepared {
            sample: s,
            joined,
            replaces,
        })
    }

    /// Adds a sample that [`SampleHistory::prepare`] checked against this history as it is.
    #[inline(always)]
    pub(crate) fn commit(&mut self, p: Prepared) {
        if p.replaces {
            self.n -= 1;
        }
        if self.n == MAX_SAMPLES {
            // From a copy: a move within the array would be a call to `memmove`.
            let (samples, joined) = (self.samples, self.joined);
            self.samples[..MAX_SAMPLES - 1].copy_from_slice(&samples[1..]);
            self.joined[..MAX_SAMPLES - 1].copy_from_slice(&joined[1..]);
            self.n -= 1;
        }
        (self.samples[self.n], self.joined[self.n]) = (p.sample, p.joined);
        self.n += 1;
        // The oldest kept sample starts the history.
        self.joined[0] = false;
    }

    /// The stored samples as a piece reads them (`None` for an empty history).
    #[inline(always)]
    fn window(&self) -> Option<Window<'_>> {
        let n = self.n.checked_sub(1)?;
        Some(self.window_of(self.samples[n], self.joined[n], n))
    }

    /// The samples as a piece reads them once `p` is added ([`SampleHistory::commit`]).
    #[inline(always)]
    fn window_after(&self, p: &Prepared) -> Window<'_> {
        self.window_of(p.sample, p.joined, self.n - usize::from(p.replaces))
    }

    /// `newest` (continuing its predecessor: `joined`) after the first `kept` stored samples.
    #[inline(always)]
    fn window_of(&self, newest: Sample, joined: bool, kept: usize) -> Window<'_> {
        Window {
            newest,
            joined,
            samples: &self.samples,
            flags: &self.joined,
            kept,
            len: 1 + kept.min(MAX_SAMPLES - 1),
        }
    }

    /// [`Window::usable`] for a piece ending at `end`.
    #[cfg(test)]
    fn usable_at(&self, end: Instant) -> usize {
        self.window()
            .map_or(0, |w| w.usable(end.since(w.newest.t)).0)
    }

    /// How many of the newest samples a piece ending at `end` is built from (see the module
    /// documentation for the choice).
    #[cfg(test)]
    fn nodes(&self, end: Instant) -> usize {
        self.window().map_or(0, |w| {
            w.order(w.usable(end.since(w.newest.t)), &PieceMemo::default())
        })
    }

    /// The plate over `[newest sample, end]`, starting at the plate's current position and
    /// velocity `now = (z, ż)` at the newest sample's instant.
    pub fn piece(&self, end: Instant, now: (f64, f64)) -> Result<PolyPiece, ParamError> {
        self.piece_with(end, now, &mut PieceMemo::default())
    }

    /// [`SampleHistory::piece`] (the same piece), keeping in `memo` the table of the nodes it
    /// is built from: the next piece checks its orders on them.
    pub fn piece_with(
        &self,
        end: Instant,
        now: (f64, f64),
        memo: &mut PieceMemo,
    ) -> Result<PolyPiece, ParamError> {
        let Some(w) = self.window() else {
            return Err(refuse(
                "plate_samples",
                0.0,
                "at least one sample is needed",
            ));
        };
        w.piece(end, now, memo)
    }

    /// The piece [`SampleHistory::piece_with`] gives once `p` is added, with the history left
    /// as it is.
    #[inline(always)]
    pub(crate) fn piece_after(
        &self,
        p: &Prepared,
        end: Instant,
        now: (f64, f64),
        memo: &mut PieceMemo,
    ) -> Result<PolyPiece, ParamError> {
        self.window_after(p).piece(end, now, memo)
    }
}

/// A sample checked against a history by [`SampleHistory::prepare`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Prepared {
    sample: Sample,
    /// It continues the newest kept sample smoothly.
    joined: bool,
    /// It is at the newest sample's instant and replaces it.
    replaces: bool,
}

/// The newest samples of a history as a piece reads them, newest first (node `i`, `i < len ≤
/// MAX_SAMPLES`): `newest`, then the stored samples before slot `kept`, newest first. `joined`
/// and `flags` tell whether each continues the one before it (the oldest one's flag is not
/// read).
#[derive(Clone, Copy)]
struct Window<'a> {
    newest: Sample,
    joined: bool,
    samples: &'a [Sample; MAX_SAMPLES],
    flags: &'a [bool; MAX_SAMPLES],
    kept: usize,
    len: usize,
}

impl Window<'_> {
    /// The slot of node `i ≥ 1` (wrapped into the array: slots of nodes past `len` are read
    /// without a bounds check, and not used).
    #[inline(always)]
    fn slot(&self, i: usize) -> usize {
        self.kept.wrapping_sub(i) % MAX_SAMPLES
    }

    /// Node `i`, newest first, and whether it continues node `i + 1`.
    #[inline(always)]
    fn entry(&self, i: usize) -> (Sample, bool) {
        if i == 0 {
            (self.newest, self.joined)
        } else {
            let k = self.slot(i);
            (self.samples[k], self.flags[k])
        }
    }

    /// Node `i`, newest first.
    #[inline(always)]
    fn node(&self, i: usize) -> Sample {
        self.entry(i).0
    }

    /// How many of the newest samples a piece of length `h` after the newest one may be built
    /// from: the newest one, then older ones while they are joined and spaced within
    /// `[h/4, 4h]`; with the spacing of the two newest (NaN for one sample).
    #[inline(always)]
    fn usable(&self, h: f64) -> (usize, f64) {
        let (mut k, mut newest_spacing) = (1, f64::NAN);
        for i in 1..self.len {
            let (newer, joined) = self.entry(i - 1);
            let spacing = newer.t.since(self.node(i).t);
            if i == 1 {
                newest_spacing = spacing;
            }
            if !(joined && spacing >= 0.25 * h && spacing <= 4.0 * h) {
                break;
            }
            k += 1;
        }
        (k, newest_spacing)
    }

    /// How many of the `usable` newest samples a piece is built from, with the table of the
    /// older samples from `memo` when it holds it (see the module documentation for the
    /// choice); `s` is the spacing of the two newest ([`Window::usable`]).
    #[inline(always)]
    fn order(&self, (usable, s): (usize, f64), memo: &PieceMemo) -> usize {
        let checkable = usable.saturating_sub(1).min(MAX_NODES);
        let mut best = (f64::INFINITY, 1);
        if checkable > 0 {
            // The older samples' table (the table of the first nodes is a part of the table of
            // more), from the last piece when it was built on them.
            let older = |i: usize| self.node(i + 1);
            let fresh;
            let table = match memo.table_of(checkable, older) {
                Some(t) => t,
                None => {
                    fresh = Table::of_nodes(checkable, older);
                    &fresh
                }
            };
            let newest = self.newest;
            let predicted = table.predictions(s, checkable);
            for (m, &(z, zd)) in (1..=checkable).zip(&predicted) {
                let miss = (z - newest.z).abs() + s * (zd - newest.zdot).abs();
                if m == 1 || miss <= best.0 / GAIN {
                    best = (miss, m);
                }
            }
        }
        usable.min(best.1)
    }

    /// The plate over `[newest sample, end]`, starting at the plate's current position and
    /// velocity `now = (z, ż)` at the newest sample's instant, keeping in `memo` the table of
    /// the nodes it is built from.
    #[inline(always)]
    fn piece(
        &self,
        end: Instant,
        now: (f64, f64),
        memo: &mut PieceMemo,
    ) -> Result<PolyPiece, ParamError> {
        let newest = self.newest;
        let start = newest.t;
        let h = end.since(start);
        if h.is_nan() || h <= 0.0 {
            return Err(refuse(
                "plate_piece_length",
                h,
                "end must be after the newest sample",
            ));
        }
        // The table of every usable node (at most MAX_NODES) holds the table of the nodes the
        // order picks as its start, so it does not wait for the order's choice.
        let usable = self.usable(h);
        let count = usable.0.min(MAX_NODES);
        let node = |i: usize| self.node(i);
        let table = Table::of_nodes(count, node);
        let m = self.order(usable, memo);
        let mut c = table.monomials(2 * m);
        memo.keep(count, node, table);
        let (z_now, zd_now) = now;
        // The interpolant starts at the newest sample (`c0`, `c1` are its `z`, `ż`): the
        // blend does not wait for the table either.
        let (d0, d1) = (z_now - newest.z, zd_now - newest.zdot);
        debug_assert!(
            c[0].to_bits() == newest.z.to_bits() && c[1].to_bits() == newest.zdot.to_bits()
        );
        // δ0 (1 − 3σ² + 2σ³) + δ1 h (σ − 2σ² + σ³), σ = s/h, in powers of s.
        let r = 1.0 / h;
        let r2 = r * r;
        let c2 = c[2] - 3.0 * d0 * r2 - 2.0 * d1 * r;
        let c3 = c[3] + 2.0 * d0 * (r2 * r) + d1 * r2;
        if c2.is_finite() && c3.is_finite() {
            (c[2], c[3]) = (c2, c3);
        }
        // Exactly where the plate is (`c0 + δ0` may round away from it).
        (c[0], c[1]) = (z_now, zd_now);
        // `h > 0` is checked above; `new` tells which coefficient is not finite.
        PolyPiece::of_finite(start, end, c).map_or_else(|| PolyPiece::new(start, end, &c), Ok)
    }
}

/// Whether `b` continues `a` smoothly, `h = b.t − a.t > 0` (see the module documentation).
fn joins(a: &Sample, b: &Sample, h: f64) -> bool {
    let sum = a.zdot + b.zdot;
    let defect = (b.z - a.z - 0.5 * h * sum).abs();
    let scale = h * (0.5 * sum.abs() + (b.zdot - a.zdot).abs());
    let ulps = 16.0 * f64::EPSILON * a.z.abs().max(b.z.abs());
    defect <= 0.25 * scale + ulps
}

/// Monomial coefficients in `s = τ − t_0` (the first node's instant) of the Hermite polynomial
/// through `(z, ż)` at each node (degree `2·nodes − 1`), by divided differences on doubled
/// nodes.
#[cfg(test)]
fn hermite(nodes: &[Sample]) -> [f64; MAX_POLY_DEGREE + 1] {
    Table::of(nodes).monomials(2 * nodes.len())
}

/// The table of divided differences of the nodes of the last piece built
/// ([`SampleHistory::piece_with`]): the next piece checks its orders on the same samples, with
/// the same numbers. Derived data, not part of a history's state (an empty memo gives the same
/// pieces).
#[derive(Clone, Copy, Default)]
pub struct PieceMemo {
    /// The last piece's nodes, newest first: the first `n` entries.
    nodes: [Sample; MAX_NODES],
    n: usize,
    table: Table,
}

impl PieceMemo {
    /// The table of the `k` nodes `node(0)`, … (newest first) if it is a part of the one
    /// kept: the newest of the kept nodes, the same samples bit for bit (the table of the
    /// newest `m` nodes is the start of the table of more).
    #[inline(always)]
    fn table_of(&self, k: usize, node: impl Fn(usize) -> Sample) -> Option<&Table> {
        let bits = |s: &Sample| {
            let (hi, lo) = s.t.parts();
            [hi, lo, s.z, s.zdot].map(f64::to_bits)
        };
        // The bits of every kept node against the node asked (the nodes past `k` read too,
        // without a branch, and their differences masked out).
        let mut differ = 0;
        for (i, kept) in self.nodes.iter().enumerate() {
            let (a, b) = (bits(kept), bits(&node(i)));
            let d = (a[0] ^ b[0]) | (a[1] ^ b[1]) | (a[2] ^ b[2]) | (a[3] ^ b[3]);
            differ |= if i < k { d } else { 0 };
        }
        (self.n >= k && differ == 0).then_some(&self.table)
    }

    /// Keeps `table` of the `k` nodes `node(0)`, … (newest first, `k ≤ MAX_NODES`).
    #[inline(always)]
    fn keep(&mut self, k: usize, node: impl Fn(usize) -> Sample, table: Table) {
        for (i, slot) in self.nodes.iter_mut().enumerate().take(k) {
            *slot = node(i);
        }
        self.n = k;
        self.table = table;
    }
}

/// Divided differences on doubled nodes, in `s = τ − t_0` (the first node's instant): `at` the
/// node instants (`at[0] = 0`), each doubled in the table (`x_i = at[i / 2]`), and
/// `q[i] = f[x_0, …, x_i]`.
#[derive(Clone, Copy, Default)]
struct Table {
    at: [f64; MAX_NODES],
    q: [f64; MAX_POLY_DEGREE + 1],
}

impl Table {
    /// The table of `nodes`, given oldest first ([`Table::of_nodes`] of the newest).
    #[cfg(test)]
    fn of(nodes: &[Sample]) -> Self {
        let k = nodes.len().min(MAX_NODES);
        Self::of_nodes(k, |i| nodes[nodes.len() - 1 - i])
    }

    /// The table of the `k` nodes `node(0)`, `node(1)`, … (newest first, `1 ≤ k ≤ MAX_NODES`).
    /// Its first `2m` entries are the table of the newest `m` nodes, the same numbers: entry
    /// `i` is computed from entries `≤ i` alone.
    #[inline(always)]
    fn of_nodes(k: usize, node: impl Fn(usize) -> Sample) -> Self {
        // Compiled for each number of nodes, so that the loops are unrolled.
        match k {
            1 => Self::of_n::<2>(node),
            2 => Self::of_n::<4>(node),
            _ => Self::of_n::<6>(node),
        }
    }

    /// [`Table::of_nodes`] for `N / 2` nodes.
    #[inline(always)]
    fn of_n<const N: usize>(node: impl Fn(usize) -> Sample) -> Self {
        let n = N;
        let origin = node(0).t;
        let mut q = [0.0; MAX_POLY_DEGREE + 1];
        let mut at = [0.0; MAX_NODES];
        for i in 0..N / 2 {
            let s = node(i);
            // The origin's own offset is zero exactly (`since` of equal instants).
            at[i] = if i == 0 { 0.0 } else { s.t.since(origin) };
            (q[2 * i], q[2 * i + 1]) = (s.z, s.z);
        }
        // The reciprocals of the node spacings, `inv[a][b] = 1/(at[a] − at[b])` for `b < a`:
        // the only divisors of the table, so three divisions (independent of each other) make
        // all of it.
        let mut inv = [[0.0; MAX_NODES]; MAX_NODES];
        for a in 1..N / 2 {
            for b in 0..a {
                inv[a][b] = 1.0 / (at[a] - at[b]);
            }
        }
        // In place: after column j, q[i] (i ≥ j) holds f[x_{i−j}, …, x_i]; on a doubled node
        // the first divided difference is the sample's velocity.
        for j in 1..n {
            for i in (j..n).rev() {
                q[i] = if j == 1 && i % 2 == 1 {
                    node(i / 2).zdot
                } else {
                    (q[i] - q[i - 1]) * inv[i / 2][(i - j) / 2]
                };
            }
        }
        Self { at, q }
    }

    /// Value and derivative at `s` of the interpolants through the first `m = 1 … orders`
    /// nodes (entry `m − 1`): the partial sums of one Newton series, `Σ_{i<2m} q_i ω_i(s)`
    /// with `ω_i = Π_{k<i} (s − x_k)`.
    fn predictions(&self, s: f64, orders: usize) -> [(f64, f64); MAX_NODES] {
        let mut out = [(0.0, 0.0); MAX_NODES];
        let (mut w, mut dw) = (1.0, 0.0);
        let (mut z, mut zd) = (0.0, 0.0);
        for (m, o) in out.iter_mut().enumerate().take(orders) {
            for i in 2 * m..2 * m + 2 {
                z += self.q[i] * w;
                zd += self.q[i] * dw;
                let u = s - self.at[i / 2];
                dw = dw * u + w;
                w *= u;
            }
            *o = (z, zd);
        }
        out
    }

    /// Monomial coefficients of the interpolant through the first `n` (even) entries.
    fn monomials(&self, n: usize) -> [f64; MAX_POLY_DEGREE + 1] {
        // Compiled for each `n`, so that the loops are unrolled and `c` stays in registers.
        match n {
            2 => self.monomials_n::<2>(),
            4 => self.monomials_n::<4>(),
            _ => self.monomials_n::<6>(),
        }
    }

    /// [`Table::monomials`] for `n = N`.
    #[inline(always)]
    fn monomials_n<const N: usize>(&self) -> [f64; MAX_POLY_DEGREE + 1] {
        let n = N;
        let (at, q) = (&self.at, &self.q);
        // Newton form to monomials: p = q_{n−1}; p ← p·(s − x_j) + q_j for j = n−2 … 0; the
        // last two passes (x_1 = x_0 = 0) only shift.
        let mut c = [0.0; MAX_POLY_DEGREE + 1];
        c[0] = q[n - 1];
        for j in (0..n - 1).rev() {
            for k in (1..n).rev() {
                c[k] = if j < 2 {
                    c[k - 1]
                } else {
                    c[k - 1] - at[j / 2] * c[k]
                };
            }
            c[0] = if j < 2 { q[j] } else { q[j] - at[j / 2] * c[0] };
        }
        c
    }
}

/// Why [`taylor_piece`] refused a piece.
#[derive(Debug, Clone, PartialEq)]
pub enum TaylorPieceError {
    /// The piece does not end after its start (or its length is NaN).
    Empty,
    /// The coefficient of this order is not finite.
    NotFinite(usize),
    /// [`PolyPiece::new`] refused the piece.
    Piece(ParamError),
}

/// The plate over `[start, end]` (τ) from its Taylor coefficients `c` at `start` (nondimensional
/// `z_k`), plus a blend `δ(1 − 3σ² + 2σ³)`, `σ = (τ − start)/(end − start)`, that removes the
/// difference `δ = z_now − c0` between where the plate is and where the coefficients put it. The
/// plate position stays continuous (the simulator refuses jumps) and reaches the Taylor
/// polynomial by the end of the piece; `δ` is zero for inputs that extrapolate exactly. A piece
/// too short for the blend (its coefficients `∝ δ/len³` overflow) carries `δ` over to the next
/// one. `z_now = None`: the plate starts at `c0` (initialization).
pub fn taylor_piece(
    start: Instant,
    end: f64,
    mut c: [f64; MAX_POLY_DEGREE + 1],
    z_now: Option<f64>,
) -> Result<PolyPiece, TaylorPieceError> {
    let len = Instant::new(end).since(start);
    if len.is_nan() || len <= 0.0 {
        return Err(TaylorPieceError::Empty);
    }
    let delta = z_now.map_or(0.0, |z| z - c[0]);
    if let Some(z) = z_now.filter(|_| delta != 0.0) {
        // Exactly where the plate is (`c0 + δ` may round away from it when the coefficients are
        // far from the plate, and the simulator refuses a plate that jumps).
        c[0] = z;
        let (c2, c3) = (
            c[2] - 3.0 * delta / (len * len),
            c[3] + 2.0 * delta / (len * len * len),
        );
        // A piece too short to blend the difference out within doubles (e.g. 1e-200) leaves
        // it to the next one: the plate stays continuous and follows the given derivatives.
        if c2.is_finite() && c3.is_finite() {
            (c[2], c[3]) = (c2, c3);
        }
    }
    if let Some(k) = c.iter().position(|v| !v.is_finite()) {
        return Err(TaylorPieceError::NotFinite(k));
    }
    PolyPiece::new(start, Instant::new(end), &c).map_err(TaylorPieceError::Piece)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shaker::PlateMotion;

    fn sine(t: f64) -> Sample {
        Sample {
            t: Instant::new(t),
            z: 0.04 * (1.75 * t).sin(),
            zdot: 0.07 * (1.75 * t).cos(),
        }
    }

    /// Uniform numbers in `[0, 1)` from a xorshift generator seeded with `seed`.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Value and slope at `s` of `Σ c_k s^k` (Horner).
    fn value_and_slope(c: &[f64], s: f64) -> (f64, f64) {
        let (mut p, mut d) = (0.0, 0.0);
        for &ck in c.iter().rev() {
            d = d * s + p;
            p = p * s + ck;
        }
        (p, d)
    }

    #[test]
    fn a_sample_at_the_newest_instant_replaces_it_and_an_earlier_one_is_refused() {
        let mut hist = SampleHistory::new();
        for k in 0..3 {
            hist.push(sine(0.1 * f64::from(k))).unwrap();
        }
        let same = Sample {
            z: 0.5,
            ..sine(0.2)
        };
        hist.push(same).unwrap();
        let kept: Vec<(Sample, bool)> = hist.entries().collect();
        assert_eq!(kept.len(), 3);
        assert_eq!(kept[2].0, same);
        // Replaced as if pushed after the second sample: a jump of the position starts anew.
        assert!(kept[1].1 && !kept[2].1);
        assert!(hist.push(sine(0.15)).is_err());
        assert_eq!(hist.entries().count(), 3);
    }

    #[test]
    fn hermite_reproduces_a_quintic() {
        let p = |t: f64| {
            0.3 - 0.2 * t + 0.5 * t * t + 0.1 * t.powi(3) - 0.05 * t.powi(4) + 0.02 * t.powi(5)
        };
        let dp = |t: f64| -0.2 + t + 0.3 * t * t - 0.2 * t.powi(3) + 0.1 * t.powi(4);
        let nodes: Vec<Sample> = [1.0, 1.5, 2.0]
            .iter()
            .map(|&t| Sample {
                t: Instant::new(t),
                z: p(t),
                zdot: dp(t),
            })
            .collect();
        let c = hermite(&nodes);
        // Taylor coefficients of p at t = 2.
        let mut out = [0.0; 6];
        PlateMotion::from(
            PolyPiece::new(
                Instant::new(0.0),
                Instant::new(9.0),
                &[0.3, -0.2, 0.5, 0.1, -0.05, 0.02],
            )
            .unwrap(),
        )
        .series(Instant::new(2.0), &mut out);
        for k in 0..6 {
            assert!(
                (c[k] - out[k]).abs() < 1e-12 * out[k].abs().max(1.0),
                "{k}: {} vs {}",
                c[k],
                out[k]
            );
        }
    }

    #[test]
    fn extrapolation_error_is_sixth_order() {
        let err = |h: f64| {
            let mut hist = SampleHistory::new();
            for k in 0..4 {
                hist.push(sine(1.0 + k as f64 * h)).unwrap();
            }
            let end = Instant::new(1.0 + 4.0 * h);
            assert_eq!(hist.nodes(end), MAX_NODES);
            let s = sine(1.0 + 3.0 * h);
            let p = PlateMotion::from(hist.piece(end, (s.z, s.zdot)).unwrap());
            (p.motion(end).0 - sine(1.0 + 4.0 * h).z).abs()
        };
        let (e1, e2) = (err(0.1), err(0.05));
        let order = (e1 / e2).log2();
        assert!(
            (5.5..6.6).contains(&order),
            "order {order} ({e1:e}, {e2:e})"
        );
        // Bound of the module docs: h⁶ |z⁽⁶⁾| / 20 with |z⁽⁶⁾| ≤ 0.07·1.75⁵.
        assert!(e2 <= 0.05f64.powi(6) * 0.07 * 1.75f64.powi(5) / 20.0);
    }

    #[test]
    fn piece_starts_at_the_plate_and_ends_on_the_extrapolation() {
        let mut hist = SampleHistory::new();
        for k in 0..3 {
            hist.push(sine(k as f64 * 0.1)).unwrap();
        }
        let now = (0.0101, 0.05);
        let end = Instant::new(0.3);
        let piece = hist.piece(end, now).unwrap();
        let p = PlateMotion::from(piece);
        let (z0, zd0, _) = p.motion(Instant::new(0.2));
        assert_eq!((z0, zd0), now);
        let bare = PlateMotion::from(hist.piece(end, (sine(0.2).z, sine(0.2).zdot)).unwrap());
        let (a, b) = (p.motion(end), bare.motion(end));
        assert!(
            (a.0 - b.0).abs() < 1e-15 && (a.1 - b.1).abs() < 1e-14,
            "{a:?} {b:?}"
        );
    }

    #[test]
    fn a_jump_starts_a_new_history_and_close_samples_are_skipped() {
        let mut hist = SampleHistory::new();
        for k in 0..3 {
            hist.push(sine(k as f64 * 0.1)).unwrap();
        }
        assert_eq!(hist.nodes(Instant::new(0.3)), 2);
        let mut jump = sine(0.3);
        jump.z += 0.5;
        hist.push(jump).unwrap();
        assert_eq!(hist.usable_at(Instant::new(0.4)), 1);
        // Spacing 0.1 is outside [h/4, 4h] for h = 1e-3 and for h = 1.
        let mut h2 = SampleHistory::new();
        h2.push(sine(0.0)).unwrap();
        h2.push(sine(0.1)).unwrap();
        assert_eq!(h2.usable_at(Instant::new(0.101)), 1);
        assert_eq!(h2.usable_at(Instant::new(1.1)), 1);
        assert_eq!(h2.usable_at(Instant::new(0.2)), 2);
        assert!(h2.push(sine(0.05)).is_err());
        let mut nan = sine(0.3);
        nan.zdot = f64::NAN;
        assert!(h2.push(nan).is_err());
    }

    #[test]
    fn the_table_by_reciprocals_is_the_table_by_divisions_to_rounding() {
        // The reference: divided differences with one division per entry, nodes newest first
        // (as the table was computed before its divisors became three reciprocals). Random
        // samples, spacings within the [h/4, 4h] a piece accepts, and the interpolant of each
        // order compared over the coming step in position and velocity, against what one
        // rounding of the samples themselves (each z, ż moved by one ulp) does to it.
        fn by_divisions(nodes: &[Sample]) -> [f64; MAX_POLY_DEGREE + 1] {
            let newest_first: Vec<Sample> = nodes.iter().rev().copied().collect();
            let n = 2 * nodes.len();
            let (mut x, mut q) = ([0.0; 6], [0.0; 6]);
            for (i, s) in newest_first.iter().enumerate() {
                let xi = s.t.since(newest_first[0].t);
                (x[2 * i], x[2 * i + 1]) = (xi, xi);
                (q[2 * i], q[2 * i + 1]) = (s.z, s.z);
            }
            for j in 1..n {
                for i in (j..n).rev() {
                    q[i] = if j == 1 && i % 2 == 1 {
                        newest_first[i / 2].zdot
                    } else {
                        (q[i] - q[i - 1]) / (x[i] - x[i - j])
                    };
                }
            }
            let mut c = [0.0; 6];
            c[0] = q[n - 1];
            for j in (0..n - 1).rev() {
                for k in (1..n).rev() {
                    c[k] = c[k - 1] - x[j] * c[k];
                }
                c[0] = q[j] - x[j] * c[0];
            }
            c
        }
        let mut rnd = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut worst, mut data) = (0.0_f64, 0.0_f64);
        for _ in 0..5000 {
            let h = 10f64.powf(-3.0 + 3.0 * rnd());
            let mut t = 1000.0 * rnd();
            let mut nodes = [sine(0.0); MAX_NODES];
            for n in nodes.iter_mut() {
                *n = sine(t);
                t += h * 4f64.powf(2.0 * rnd() - 1.0);
            }
            for m in 1..=MAX_NODES {
                let newest = &nodes[MAX_NODES - m..];
                let (a, b) = (hermite(newest), by_divisions(newest));
                let mut nudged = newest.to_vec();
                for n in nudged.iter_mut() {
                    n.z = f64::from_bits(n.z.to_bits() + 1);
                    n.zdot = f64::from_bits(n.zdot.to_bits() + 1);
                }
                let c = by_divisions(&nudged);
                for s in [0.5 * h, h] {
                    let (za, da) = value_and_slope(&a, s);
                    let (zb, db) = value_and_slope(&b, s);
                    let (zc, dc) = value_and_slope(&c, s);
                    // In units of the plate's amplitude (0.04) and velocity amplitude (0.07).
                    worst = worst
                        .max((za - zb).abs() / 0.04)
                        .max((da - db).abs() / 0.07);
                    data = data.max((zc - zb).abs() / 0.04).max((dc - db).abs() / 0.07);
                }
            }
        }
        // Measured: 4.8e-13 against 1.3e-11.
        assert!(
            worst <= 0.1 * data && worst <= 1e-12,
            "largest difference {worst:e}, from one ulp of the samples {data:e}"
        );
    }

    #[test]
    fn one_table_gives_each_order_the_bits_of_its_own() {
        // The table of the newest m nodes is the start of the table of all of them, bit for
        // bit (what lets the orders and the memo share one table), and so are the
        // interpolants built from it.
        let mut uni = uniform(0x2545_f491_4f6c_dd1d);
        let mut rnd = || uni() - 0.5;
        for _ in 0..2000 {
            let t0 = 100.0 * rnd();
            let mut nodes = [sine(0.0); MAX_NODES];
            for (k, n) in nodes.iter_mut().enumerate() {
                *n = Sample {
                    t: Instant::new(t0 + (k as f64) * (0.01 + 0.001 * rnd())),
                    z: rnd(),
                    zdot: rnd(),
                };
            }
            let all = Table::of(&nodes);
            for m in 1..=MAX_NODES {
                let part = Table::of(&nodes[MAX_NODES - m..]);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&all.q[..2 * m]), bits(&part.q[..2 * m]), "m = {m}");
                assert_eq!(bits(&all.at[..m]), bits(&part.at[..m]), "m = {m}");
                let (a, b) = (all.monomials(2 * m), part.monomials(2 * m));
                assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "m = {m}");
            }
        }
    }

    #[test]
    fn the_orders_predictions_are_the_interpolants_of_the_older_samples() {
        // The Newton partial sums `order` compares against each order's interpolant in
        // monomials, evaluated at the newest sample: equal to rounding.
        let mut hist = SampleHistory::new();
        for k in 0..4 {
            hist.push(sine(0.3 + 0.01 * k as f64 + 1e-4 * (k * k) as f64))
                .unwrap();
        }
        assert_eq!(hist.usable_at(Instant::new(0.35)), 4);
        let all: Vec<Sample> = hist.entries().map(|e| e.0).collect();
        let (newest, older) = (all[3], &all[..3]);
        let s = newest.t.since(older[2].t);
        let predicted = Table::of(older).predictions(s, MAX_NODES);
        for m in 1..=MAX_NODES {
            let (z, zd) = predicted[m - 1];
            let (p, d) = value_and_slope(&hermite(&older[3 - m..]), s);
            assert!(
                (z - p).abs() <= 1e-15 && (zd - d).abs() <= 1e-13,
                "m = {m}: {z} {p} {zd} {d}"
            );
        }
    }

    #[test]
    fn a_piece_after_a_prepared_sample_is_the_piece_after_the_push() {
        // Uneven spacings, samples at the newest instant again, jumps, samples before the
        // newest and non-finite ones, with a memo on each side.
        let mut next = uniform(11);
        let (mut hist, mut memo_a, mut memo_b) = (
            SampleHistory::new(),
            PieceMemo::default(),
            PieceMemo::default(),
        );
        let (mut t, mut prepared_ok) = (0.0, 0);
        for _ in 0..2_000 {
            let r = next();
            let at = match r {
                r if r < 0.1 => t,
                r if r < 0.15 => t - 0.005,
                _ => t + 0.01 * (0.5 + next()),
            };
            let mut s = sine(at);
            if r > 0.95 {
                s.z += 0.01;
            }
            if r > 0.99 {
                s.zdot = f64::NAN;
            }
            let end = Instant::new(at + 0.01 * (0.3 + next()));
            let now = (s.z + 1e-6 * (next() - 0.5), s.zdot + 1e-6 * (next() - 0.5));
            let mut pushed = hist;
            match (hist.prepare(s), pushed.push(s)) {
                (Ok(p), Ok(())) => {
                    let a = hist.piece_after(&p, end, now, &mut memo_a).unwrap();
                    let b = pushed.piece_with(end, now, &mut memo_b).unwrap();
                    let bits = |c: &[f64]| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!((a.start(), a.end()), (b.start(), b.end()));
                    assert_eq!(bits(&a.coeffs()), bits(&b.coeffs()));
                    hist.commit(p);
                    assert_eq!(hist, pushed);
                    t = at;
                    prepared_ok += 1;
                }
                (Err(e), Err(f)) => {
                    assert_eq!((e.name, e.rule), (f.name, f.rule));
                    assert_eq!(e.value.to_bits(), f.value.to_bits());
                }
                (a, b) => panic!("prepare {a:?}, push {b:?}"),
            }
        }
        assert!(prepared_ok > 1_500, "{prepared_ok}");
    }

    #[test]
    fn pieces_with_a_memo_are_the_pieces_without() {
        let (mut hist, mut memo) = (SampleHistory::new(), PieceMemo::default());
        for k in 0..400 {
            // Smooth, then a jump, then noise, with a few uneven spacings.
            let t = k as f64 * 0.01 + if k % 37 == 0 { 0.004 } else { 0.0 };
            let mut s = sine(t);
            if k >= 150 {
                s.z += 0.3;
            }
            if k >= 250 {
                s.z += 1e-5 * ((k * 7919) % 13) as f64;
            }
            hist.push(s).unwrap();
            let end = Instant::new(t + 0.01);
            let now = (s.z + 1e-9, s.zdot);
            let a = hist.piece(end, now).unwrap();
            let b = hist.piece_with(end, now, &mut memo).unwrap();
            assert_eq!(
                a.coeffs().map(f64::to_bits),
                b.coeffs().map(f64::to_bits),
                "k = {k}"
            );
        }
    }

    #[test]
    fn noisy_samples_get_a_lower_order() {
        // Noise of 1e-4 of the amplitude at 100 samples per time unit: the linear prediction
        // misses the newest sample least, so the piece is built from it alone.
        let mut hist = SampleHistory::new();
        let noise = [3e-6, -4e-6, 4e-6, -3e-6];
        for (k, n) in noise.iter().enumerate() {
            let mut s = sine(k as f64 * 0.01);
            s.z += n;
            hist.push(s).unwrap();
        }
        assert_eq!(hist.usable_at(Instant::new(0.04)), 4);
        assert_eq!(hist.nodes(Instant::new(0.04)), 1);
    }

    #[test]
    fn saved_entries_round_trip_and_bad_ones_are_refused() {
        let mut hist = SampleHistory::new();
        for k in 0..5 {
            hist.push(sine(k as f64 * 0.1)).unwrap();
        }
        let e: Vec<_> = hist.entries().collect();
        assert_eq!(e.len(), MAX_SAMPLES);
        assert!(!e[0].1 && e[1].1 && e[2].1 && e[3].1);
        assert_eq!(SampleHistory::from_entries(&e), Some(hist));
        let mut swapped = e.clone();
        swapped.swap(1, 2);
        assert_eq!(SampleHistory::from_entries(&swapped), None);
        assert_eq!(SampleHistory::from_entries(&e[1..]), None); // oldest marked joined
    }

    #[test]
    fn taylor_piece_blends_from_the_plate_onto_the_coefficients() {
        let start = Instant::new(1.0);
        let c = [0.1, 0.2, -0.4, 0.0, 0.0, 0.0];
        let p = crate::PlateMotion::from(taylor_piece(start, 1.5, c, Some(0.25)).unwrap());
        assert_eq!(p.motion(start).0, 0.25);
        let s = 0.5;
        let (z1, _, _) = p.motion(Instant::new(1.5));
        assert!((z1 - (0.1 + 0.2 * s - 0.4 * s * s)).abs() < 1e-14, "{z1}");
        let first = crate::PlateMotion::from(taylor_piece(start, 1.5, c, None).unwrap());
        assert_eq!(first.motion(start).0, 0.1);
        assert_eq!(
            taylor_piece(start, 0.5, c, None),
            Err(TaylorPieceError::Empty)
        );
        let mut bad = c;
        bad[4] = f64::INFINITY;
        assert_eq!(
            taylor_piece(start, 1.5, bad, None),
            Err(TaylorPieceError::NotFinite(4))
        );
    }
}
