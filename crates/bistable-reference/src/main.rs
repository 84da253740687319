//! `bistable-reference`: print the high-precision reference events as CSV.
//!
//! ```text
//! bistable-reference --omega W --velocity V [--zeta 0.02] [--restitution 0.85] [--t-end T]
//!                    [--bits 128] [--chatter accumulation|paper] [--delta 1e-20] [--gap 1e-9]
//!                    [--max-events N] [--full-precision]
//! ```
//! Columns: `kind,index,t,phase,x,v_before,v_after,to_well` (`t` is the full-precision decimal
//! time with `--full-precision`).

use bistable_reference::{simulate, RefChatter, RefOptions, RefParams};
use std::process::ExitCode;

const USAGE: &str = "usage: bistable-reference --omega W --velocity V [--zeta 0.02] \
[--restitution 0.85] [--t-end T (default 100)] [--bits 128] [--chatter accumulation|paper] \
[--delta 1e-20] [--gap 1e-9] [--max-events N] [--full-precision]";

fn parse_f64(name: &str, value: Option<String>) -> Result<f64, String> {
    let v = value.ok_or_else(|| format!("{name} needs a value"))?;
    v.parse::<f64>()
        .map_err(|_| format!("{name}: not a number: {v:?}"))
}

fn parse_usize(name: &str, value: Option<String>) -> Result<usize, String> {
    let v = value.ok_or_else(|| format!("{name} needs a value"))?;
    v.parse::<usize>()
        .map_err(|_| format!("{name}: not a non-negative integer: {v:?}"))
}

struct Cli {
    params: RefParams,
    options: RefOptions,
    full_precision: bool,
}

fn parse_args(args: impl Iterator<Item = String>) -> Result<Option<Cli>, String> {
    let mut omega = None;
    let mut velocity = None;
    let mut params = RefParams::default();
    let mut options = RefOptions::default();
    let mut chatter = "accumulation".to_string();
    let mut delta = 1e-20;
    let mut gap = 1e-9;
    let mut full_precision = false;
    let mut args = args.peekable();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "-h" | "--help" => return Ok(None),
            "--omega" => omega = Some(parse_f64(&arg, args.next())?),
            "--velocity" => velocity = Some(parse_f64(&arg, args.next())?),
            "--zeta" => params.zeta = parse_f64(&arg, args.next())?,
            "--restitution" => params.restitution = parse_f64(&arg, args.next())?,
            "--t-end" => options.t_end = parse_f64(&arg, args.next())?,
            "--bits" => options.bits = parse_usize(&arg, args.next())?,
            "--max-events" => options.max_events = parse_usize(&arg, args.next())?,
            "--delta" => delta = parse_f64(&arg, args.next())?,
            "--gap" => gap = parse_f64(&arg, args.next())?,
            "--chatter" => {
                chatter = args
                    .next()
                    .ok_or_else(|| "--chatter needs a value".to_string())?
            }
            "--full-precision" => full_precision = true,
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    params.omega = omega.ok_or("--omega is required")?;
    params.velocity = velocity.ok_or("--velocity is required")?;
    options.chatter = match chatter.as_str() {
        "accumulation" => RefChatter::Accumulation { delta },
        "paper" | "fixed-gap" => RefChatter::FixedGap { gap },
        other => {
            return Err(format!(
                "--chatter must be accumulation or paper, got {other:?}"
            ))
        }
    };
    Ok(Some(Cli {
        params,
        options,
        full_precision,
    }))
}

fn main() -> ExitCode {
    let cli = match parse_args(std::env::args().skip(1)) {
        Ok(Some(cli)) => cli,
        Ok(None) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(msg) => {
            eprintln!("error: {msg}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let events = match simulate(&cli.params, &cli.options) {
        Ok(ev) => ev,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    let mut out = String::from("kind,index,t,phase,x,v_before,v_after,to_well\n");
    for e in &events {
        let t = if cli.full_precision {
            e.t_str.clone()
        } else {
            format!("{:?}", e.t)
        };
        out.push_str(&format!(
            "{},{},{},{:?},{:?},{:?},{:?},{}\n",
            e.kind.name(),
            e.index,
            t,
            e.phase,
            e.x,
            e.v_before,
            e.v_after,
            e.to_well
        ));
    }
    print!("{out}");
    ExitCode::SUCCESS
}
