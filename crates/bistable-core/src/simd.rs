//! Which instruction set the runtime dispatch points use, and the switch that forces one.
//!
//! Four places pick their code from the CPU at run time: the batch kernel over 8 lanes
//! (AVX-512) and over 4 lanes (AVX2) in [`crate::batch`], [`crate::Simulator::flights_at`]
//! (AVX-512) and the phase reduction of [`crate::Instant::angle`] (FMA). Every path computes the
//! same bits (the lane operations are the scalar IEEE operations, [`crate::lanes`]; the FMA only
//! computes a product's exact error sooner), so the choice changes the speed only. The
//! environment variable `BISTABLE_SIMD`, read once per process at the first dispatch, chooses
//! the path, so that one machine can run every path its CPU has:
//!
//! | `BISTABLE_SIMD` | path |
//! |---|---|
//! | unset, empty or `auto` | the widest the CPU has: AVX-512, else AVX2, else portable |
//! | `avx512` | AVX-512 (and AVX2 and FMA); refused on a CPU without AVX-512F |
//! | `avx2` | AVX2 and FMA, never AVX-512: the path of a CPU with AVX2 but no AVX-512; refused on a CPU without AVX2 |
//! | `portable` | nothing beyond the build's baseline (no AVX, no FMA): the path of a CPU with neither |
//!
//! Any other value, or a path the CPU lacks, is refused: [`check`] tells why (the command-line
//! program and the ROS node exit with code 2 and that message, the Python package raises
//! `ImportError`, the FMU's instantiate functions log it and return NULL), and a program that
//! does not check panics with the same message at the first dispatch.

use std::fmt;
use std::sync::OnceLock;

/// The environment variable that forces a path.
pub const ENV: &str = "BISTABLE_SIMD";

/// An instruction set the dispatch points can use, narrowest first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdPath {
    /// The build's baseline instructions only (SSE2 on x86-64), no FMA.
    Portable,
    /// AVX2 registers for 4 lanes and FMA where the CPU has it; 8 lanes and
    /// [`crate::Simulator::flights_at`] portable.
    Avx2,
    /// AVX-512 registers for 8 lanes and [`crate::Simulator::flights_at`], AVX2 for 4 lanes,
    /// FMA.
    Avx512,
}

impl SimdPath {
    /// The value of `BISTABLE_SIMD` that forces this path: `portable`, `avx2` or `avx512`.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Portable => "portable",
            SimdPath::Avx2 => "avx2",
            SimdPath::Avx512 => "avx512",
        }
    }

    /// The widest path this CPU has.
    pub fn detected() -> SimdPath {
        Cpu::detect().widest()
    }
}

impl fmt::Display for SimdPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why `BISTABLE_SIMD` is refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SimdError {
    /// Not one of `auto`, `portable`, `avx2`, `avx512` (the value as given).
    Unknown(String),
    /// The CPU lacks the instructions of the path asked for (`asked`); `widest` is the widest
    /// path it has.
    Unsupported {
        /// The path asked for.
        asked: SimdPath,
        /// The CPU's widest path.
        widest: SimdPath,
    },
}

impl fmt::Display for SimdError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimdError::Unknown(v) => write!(
                f,
                "{ENV}={v:?} is not a SIMD path: use auto, portable, avx2 or avx512"
            ),
            SimdError::Unsupported { asked, widest } => write!(
                f,
                "{ENV}={asked}: this CPU lacks {} (its widest path is {widest})",
                match asked {
                    SimdPath::Avx512 => "AVX-512F",
                    _ => "AVX2",
                }
            ),
        }
    }
}

impl std::error::Error for SimdError {}

/// What the CPU has, of what the dispatch points use.
#[derive(Debug, Clone, Copy)]
struct Cpu {
    avx512f: bool,
    avx2: bool,
    fma: bool,
}

impl Cpu {
    #[cfg(target_arch = "x86_64")]
    fn detect() -> Cpu {
        Cpu {
            avx512f: std::arch::is_x86_feature_detected!("avx512f"),
            avx2: std::arch::is_x86_feature_detected!("avx2"),
            fma: std::arch::is_x86_feature_detected!("fma"),
        }
    }

    #[cfg(not(target_arch = "x86_64"))]
    fn detect() -> Cpu {
        Cpu {
            avx512f: false,
            avx2: false,
            fma: false,
        }
    }

    /// The widest path with these features.
    fn widest(self) -> SimdPath {
        if self.avx512f {
            SimdPath::Avx512
        } else if self.avx2 {
            SimdPath::Avx2
        } else {
            SimdPath::Portable
        }
    }
}

/// The path `value` of `BISTABLE_SIMD` asks for on a CPU with `cpu`, and the features the
/// dispatch points may use on it.
fn resolve(value: Option<&str>, cpu: Cpu) -> Result<(SimdPath, Cpu), SimdError> {
    let widest = cpu.widest();
    let path = match value.unwrap_or("") {
        "" | "auto" => widest,
        "portable" => SimdPath::Portable,
        "avx2" => SimdPath::Avx2,
        "avx512" => SimdPath::Avx512,
        other => return Err(SimdError::Unknown(other.to_string())),
    };
    if path > widest {
        return Err(SimdError::Unsupported {
            asked: path,
            widest,
        });
    }
    let allowed = Cpu {
        avx512f: cpu.avx512f && path >= SimdPath::Avx512,
        avx2: cpu.avx2 && path >= SimdPath::Avx2,
        fma: cpu.fma && path >= SimdPath::Avx2,
    };
    Ok((path, allowed))
}

/// The path and features in use, from `BISTABLE_SIMD` and the CPU, decided once.
#[inline]
fn state() -> &'static Result<(SimdPath, Cpu), SimdError> {
    static STATE: OnceLock<Result<(SimdPath, Cpu), SimdError>> = OnceLock::new();
    STATE.get_or_init(|| {
        let value = std::env::var_os(ENV).map(|v| v.to_string_lossy().into_owned());
        resolve(value.as_deref(), Cpu::detect())
    })
}

/// The path in use (`BISTABLE_SIMD` and the CPU, see the module documentation), or why
/// `BISTABLE_SIMD` is refused. Front ends call it before any work to report a bad value.
pub fn check() -> Result<SimdPath, SimdError> {
    state().as_ref().map(|s| s.0).map_err(Clone::clone)
}

/// The path in use. Panics with [`check`]'s message when `BISTABLE_SIMD` is refused.
pub fn path() -> SimdPath {
    features().0
}

/// [`path`] and the features the dispatch points may use.
#[inline]
fn features() -> (SimdPath, Cpu) {
    match state() {
        Ok(s) => *s,
        Err(e) => panic!("{e}"),
    }
}

/// Whether the dispatch points may use AVX-512F registers.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx512f() -> bool {
    features().1.avx512f
}

/// Whether the dispatch points may use AVX2 registers.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2() -> bool {
    features().1.avx2
}

/// Whether the dispatch points may use FMA instructions.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn fma() -> bool {
    features().1.fma
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Cpu = Cpu {
        avx512f: true,
        avx2: true,
        fma: true,
    };
    const AVX2: Cpu = Cpu {
        avx512f: false,
        avx2: true,
        fma: true,
    };
    const NONE: Cpu = Cpu {
        avx512f: false,
        avx2: false,
        fma: false,
    };

    fn used(value: Option<&str>, cpu: Cpu) -> (SimdPath, [bool; 3]) {
        let (p, c) = resolve(value, cpu).unwrap();
        (p, [c.avx512f, c.avx2, c.fma])
    }

    #[test]
    fn each_value_selects_its_features() {
        use SimdPath::*;
        assert_eq!(used(None, ALL), (Avx512, [true, true, true]));
        assert_eq!(used(Some(""), AVX2), (Avx2, [false, true, true]));
        assert_eq!(used(Some("auto"), NONE), (Portable, [false; 3]));
        assert_eq!(used(Some("avx512"), ALL), (Avx512, [true, true, true]));
        assert_eq!(used(Some("avx2"), ALL), (Avx2, [false, true, true]));
        assert_eq!(used(Some("portable"), ALL), (Portable, [false; 3]));
        assert_eq!(used(Some("portable"), NONE), (Portable, [false; 3]));
    }

    #[test]
    fn unknown_values_and_missing_instructions_are_refused() {
        let err = |v, cpu| resolve(Some(v), cpu).unwrap_err();
        use SimdPath::*;
        let unsupported = |asked, widest| SimdError::Unsupported { asked, widest };
        assert_eq!(err("avx512", AVX2), unsupported(Avx512, Avx2));
        assert_eq!(err("avx512", NONE), unsupported(Avx512, Portable));
        assert_eq!(err("avx2", NONE), unsupported(Avx2, Portable));
        assert_eq!(err("AVX2", ALL), SimdError::Unknown("AVX2".into()));
        let msg = err("sse", ALL).to_string();
        assert!(
            msg.contains("BISTABLE_SIMD=\"sse\"") && msg.contains("portable"),
            "{msg}"
        );
        let msg = err("avx512", AVX2).to_string();
        assert!(
            msg.contains("lacks AVX-512F (its widest path is avx2)"),
            "{msg}"
        );
    }
}
