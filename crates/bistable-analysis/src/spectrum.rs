//! The amplitude spectrum of the steady-state displacement, to tell periodic responses (lines at
//! multiples of Ω/p) from chaotic ones (a broadband floor).

use std::num::NonZeroU32;

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

use bistable_core::{Event, SimError};

use crate::cycles::settled;
use crate::period::{detect_period, MAX_PERIOD, PERIOD_TOL};
use crate::Model;

/// What to sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SpectrumOptions {
    /// Shaker periods skipped as transient.
    pub transient: u32,
    /// Shaker periods sampled (the frequency resolution is Ω/record).
    pub record: NonZeroU32,
    /// Samples per shaker period (the Nyquist frequency is samples/2 in units of Ω).
    pub samples: NonZeroU32,
}

/// The spectrum of the steady state at one point.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// `(frequency / Ω, amplitude)` for the FFT bins `0..=N/2` (amplitude in units of `Δx`).
    pub bins: Vec<(f64, f64)>,
    /// Period on the stroboscopic section (shaker periods); `None` when none up to 16.
    pub period: Option<usize>,
    /// `(frequency / Ω, amplitude)` of the largest bin above 0 (`(0, 0)` if there is none).
    pub peak: (f64, f64),
}

impl Spectrum {
    /// Runs the paper's initial condition at `model`, skips the transient, samples `x`
    /// uniformly (from the dense output) and takes the spectrum.
    pub fn compute(model: &Model, o: SpectrumOptions) -> Result<Self, SimError> {
        let (record, samples) = (o.record.get(), o.samples.get());
        let plate = model.shaker;
        let first = u64::from(o.transient);
        let mut sim = settled(model, o.transient)?;
        let h = plate.period() / f64::from(samples);
        let mut x = Vec::with_capacity(record as usize * samples as usize);
        let mut sections = Vec::with_capacity(record as usize + 1);
        let st = sim.state();
        sections.push((st.x, st.v));
        for c in 0..u64::from(record) {
            let start = plate.section(first + c);
            for j in 0..samples {
                if j > 0 {
                    sim.advance_instant(start + f64::from(j) * h, &mut |_: &Event| {})?;
                }
                x.push(sim.state().x);
            }
            sim.advance_instant(plate.section(first + c + 1), &mut |_: &Event| {})?;
            let st = sim.state();
            sections.push((st.x, st.v));
        }
        let bins = amplitude_spectrum(&x, record);
        let peak = bins
            .iter()
            .skip(1)
            .copied()
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        Ok(Self {
            bins,
            period: detect_period(&sections, MAX_PERIOD, PERIOD_TOL),
            peak,
        })
    }
}

/// The amplitude spectrum of `x` sampled uniformly over `record` shaker periods: mean removed,
/// Hann window, FFT; `(frequency / Ω, 2|X_k|/Σw)` (the amplitude of a sinusoid at that
/// frequency) for bins `0..=N/2`.
pub fn amplitude_spectrum(x: &[f64], record: u32) -> Vec<(f64, f64)> {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n as f64;
    let w: Vec<f64> = (0..n)
        .map(|k| 0.5 - 0.5 * (std::f64::consts::TAU * k as f64 / n as f64).cos())
        .collect();
    let wsum: f64 = w.iter().sum();
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .zip(&w)
        .map(|(&v, &wk)| Complex::new((v - mean) * wk, 0.0))
        .collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    buf[..=n / 2]
        .iter()
        .enumerate()
        .map(|(k, c)| (k as f64 / f64::from(record), 2.0 * c.norm() / wsum))
        .collect()
}

/// Spectral flatness: geometric over arithmetic mean of the power of the bins with
/// `0 < f <= max_f` (0 if there are none); near 0 for line spectra, near 1 for white noise.
pub fn flatness(spec: &[(f64, f64)], max_f: f64) -> f64 {
    let power: Vec<f64> = spec
        .iter()
        .filter(|s| s.0 > 0.0 && s.0 <= max_f)
        .map(|s| (s.1 * s.1).max(1e-300))
        .collect();
    if power.is_empty() {
        return 0.0;
    }
    let n = power.len() as f64;
    let geo = (power.iter().map(|p| p.ln()).sum::<f64>() / n).exp();
    geo / (power.iter().sum::<f64>() / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sinusoid_has_one_line_of_its_amplitude() {
        // 0.3·sin at 2Ω plus 0.1·cos at 0.5Ω, 64 samples per shaker period, 256 periods.
        let (rec, spp) = (256u32, 64u32);
        let x: Vec<f64> = (0..rec * spp)
            .map(|k| {
                let t = f64::from(k) / f64::from(spp); // in shaker periods
                0.3 * (std::f64::consts::TAU * 2.0 * t).sin()
                    + 0.1 * (std::f64::consts::TAU * 0.5 * t).cos()
                    + 7.0
            })
            .collect();
        let s = amplitude_spectrum(&x, rec);
        let at = |f: f64| s[(f * f64::from(rec)).round() as usize];
        assert!((at(2.0).1 - 0.3).abs() < 1e-9, "{:?}", at(2.0));
        assert!((at(0.5).1 - 0.1).abs() < 1e-9);
        assert!(s[0].1 < 1e-9, "mean removed");
        assert!(at(3.0).1 < 1e-12);
        // A line spectrum is far from flat; white-ish noise is not.
        assert!(flatness(&s, 5.0) < 1e-6);
        let mut seed = 12345u64;
        let noise: Vec<f64> = (0..4096)
            .map(|_| {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        assert!(flatness(&amplitude_spectrum(&noise, 64), 5.0) > 0.1);
    }
}
