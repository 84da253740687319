//! `bistable spectrum`: the amplitude spectrum of the steady-state displacement, to tell
//! periodic responses (lines at multiples of Ω/p) from chaotic ones (a broadband floor).

use std::path::PathBuf;

use clap::Args;
use plotters::prelude::*;
use serde::Serialize;

use bistable_analysis::spectrum::{flatness, Spectrum, SpectrumOptions};
use bistable_analysis::Model;

use crate::common::CommonArgs;
use crate::error::CliError;
use crate::output::{print_json, print_text, CsvFile, Field};
use crate::plot::{self, header, Area, DrawResult, Mark};

/// Long description shown by `bistable spectrum --help`.
pub const LONG_ABOUT: &str = "\
Amplitude spectrum of the steady-state displacement x(τ) at (Ω, V): the response
starts from the paper's initial condition, skips --transient shaker periods,
then x is sampled --samples times per shaker period (uniformly, from the dense
output) over --record shaker periods. The mean is removed, a Hann window
applied and the FFT taken (rustfft); the amplitude of bin k is 2|X_k|/Σw (the
amplitude of a sinusoid at that frequency). Frequencies are in units of the
shaker frequency Ω, with resolution 1/--record.

A periodic response of period p has lines only at multiples of Ω/p; a chaotic
one has a broadband floor. The summary gives the period found on the
stroboscopic section (null: none up to 16) and the spectral flatness (geometric
over arithmetic mean of the power up to --max-freq): near 0 for line spectra,
orders of magnitude larger for broadband ones.";

/// Shown after the options by `bistable spectrum --help`.
pub const AFTER_HELP: &str = "\
CSV (--out): freq_over_omega,amplitude, one row per FFT bin up to the Nyquist
frequency (--samples/2 in units of Ω).

Examples:
  bistable spectrum --omega 2.45 --velocity 0.07 --plot out/spectrum_chaos.png
  bistable spectrum --omega 2.2 --velocity 0.07 --plot out/spectrum_p2.png --out out/p2.csv";

/// Options of `bistable spectrum`.
#[derive(Debug, Clone, Args)]
pub struct SpectrumArgs {
    #[command(flatten)]
    pub common: CommonArgs,

    /// Shaker periods skipped as transient.
    #[arg(long, value_name = "N", default_value_t = 500)]
    pub transient: u32,

    /// Shaker periods sampled (>= 8; the frequency resolution is Ω/N).
    #[arg(long, value_name = "N", default_value_t = 1024)]
    pub record: u32,

    /// Samples per shaker period (>= 4; the Nyquist frequency is N/2 in units of Ω).
    #[arg(long, value_name = "N", default_value_t = 64)]
    pub samples: u32,

    /// Highest frequency plotted and used for the flatness, in units of Ω.
    #[arg(long, value_name = "F", default_value_t = 5.0)]
    pub max_freq: f64,

    /// Draw the spectrum to FILE.png.
    #[arg(long, value_name = "FILE.png", help_heading = "Output")]
    pub plot: Option<PathBuf>,

    /// Write the spectrum to FILE.csv.
    #[arg(long, value_name = "FILE.csv", help_heading = "Output")]
    pub out: Option<PathBuf>,
}

#[derive(Debug, Serialize)]
struct Summary {
    omega: f64,
    velocity: f64,
    transient: u32,
    record: u32,
    samples_per_period: u32,
    /// Period on the stroboscopic section (shaker periods); null when none up to 16.
    period: Option<usize>,
    /// Geometric over arithmetic mean of the power in (0, max_freq].
    spectral_flatness: f64,
    /// Frequency (units of Ω) and amplitude of the largest peak.
    peak_freq_over_omega: f64,
    peak_amplitude: f64,
    files: Vec<PathBuf>,
}

/// Runs `bistable spectrum`.
pub fn run(args: &SpectrumArgs) -> Result<(), CliError> {
    let model = args.common.model()?;
    let record = CliError::count("--record", args.record, 8)?;
    let samples = CliError::count("--samples", args.samples, 4)?;
    if u64::from(args.record) * u64::from(args.samples) > 1 << 26 {
        return Err(CliError::invalid_text(
            "--record",
            args.record,
            "--record × --samples must be at most 2^26",
        ));
    }
    let nyquist = 0.5 * f64::from(args.samples);
    if !(args.max_freq.is_finite() && args.max_freq > 0.0) {
        return Err(CliError::invalid(
            "--max-freq",
            args.max_freq,
            "must be > 0",
        ));
    }
    let max_f = args.max_freq.min(nyquist);

    let Spectrum {
        bins: spec,
        period,
        peak,
    } = Spectrum::compute(
        &model,
        SpectrumOptions {
            transient: args.transient,
            record,
            samples,
        },
    )?;
    let flat = flatness(&spec, max_f);

    let mut files = Vec::new();
    if let Some(path) = &args.out {
        let mut csv = CsvFile::create(path, "freq_over_omega,amplitude")?;
        for &(f, a) in &spec {
            csv.row(&[Field::F(f), Field::F(a)])?;
        }
        files.push(csv.finish()?);
    }
    if let Some(path) = &args.plot {
        plot::png(path, (1400, 850), |root| {
            draw(root, &model, args, &spec, max_f, period, flat)
        })?;
        files.push(path.clone());
    }
    let summary = Summary {
        omega: model.omega(),
        velocity: model.velocity(),
        transient: args.transient,
        record: args.record,
        samples_per_period: args.samples,
        period,
        spectral_flatness: flat,
        peak_freq_over_omega: peak.0,
        peak_amplitude: peak.1,
        files,
    };
    if args.common.json() {
        print_json(&summary)
    } else {
        let mut text = format!(
            "spectrum of x at Ω = {}, V = {}: {}; spectral flatness {:.3e} (0 … 1); largest \
             peak {:.4e} at {:.4}·Ω\n",
            summary.omega,
            summary.velocity,
            match period {
                Some(p) => format!("period {p}"),
                None => "no period <= 16 (aperiodic)".to_string(),
            },
            flat,
            peak.1,
            peak.0
        );
        for f in &summary.files {
            text.push_str(&format!("wrote {}\n", f.display()));
        }
        print_text(&text)
    }
}

const LINE: RGBColor = RGBColor(31, 87, 165);
const HARMONIC: RGBColor = RGBColor(200, 120, 40);

fn draw(
    root: &Area<'_>,
    model: &Model,
    args: &SpectrumArgs,
    spec: &[(f64, f64)],
    max_f: f64,
    period: Option<usize>,
    flat: f64,
) -> DrawResult {
    let pts: Vec<(f64, f64)> = spec
        .iter()
        .filter(|s| s.0 <= max_f)
        .map(|&(f, a)| (f, a.max(1e-300).log10()))
        .collect();
    let peak = pts.iter().skip(1).map(|p| p.1).fold(f64::MIN, f64::max);
    let floor = (peak - 12.0).max(pts.iter().skip(1).map(|p| p.1).fold(f64::MAX, f64::min));
    let response = match period {
        Some(p) => format!("period {p} (lines at multiples of Ω/{p})"),
        None => "aperiodic: no period up to 16".to_string(),
    };
    let area = header(
        root,
        &format!("Amplitude spectrum of x(τ) — {}", plot::label(model)),
        &format!(
            "{response}; {} shaker periods after {} of transient, {} samples per period, Hann \
             window; spectral flatness {flat:.2e}",
            args.record, args.transient, args.samples
        ),
        &[
            (Mark::Line(LINE, 2), "amplitude of x".to_string()),
            (
                Mark::Dashed(HARMONIC),
                "multiples of the shaker frequency Ω".to_string(),
            ),
        ],
    )?;
    let mut chart = plot::chart(
        &area,
        (0.0, max_f),
        (floor - 0.3, peak + 0.5),
        "frequency ω/Ω (units of the shaker frequency)",
        "log₁₀ amplitude (units of Δx)",
        None,
    )?;
    for k in 1..=(max_f.floor() as u32) {
        plot::vline(&mut chart, f64::from(k), HARMONIC)?;
    }
    let clipped: Vec<(f64, f64)> = pts.iter().map(|&(f, a)| (f, a.max(floor - 0.3))).collect();
    plot::thick_line(&mut chart, &clipped, LINE, 1)?;
    Ok(())
}
