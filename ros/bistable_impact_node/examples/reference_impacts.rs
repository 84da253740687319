//! Reference impact list straight from `bistable-core` (no node code), for the interop tests:
//! `reference_impacts OMEGA V T_END [T_SWITCH OMEGA2 V2]` (or `OMEGA V T_END X0 V0`, from the
//! mass state `(X0, V0)` at time 0, as the node's `bistable/reset_state` does) prints
//! `index,t,phase,x,v_before,v_after,zdot,delta_k,ended_in_sticking` (nondimensional, ζ = 0.02,
//! e = 0.85, the paper's initial condition), switching the shaker at `T_SWITCH` if given, as
//! the node does: a `SetpointRamp` of `RAMP_CYCLES` periods about the initial centre (impacts
//! on the ramp get the ramp's phase).

use bistable_core::{Event, Params, SetpointRamp, Simulator, Sinusoid, SolverOptions};
use bistable_impact_node::sim::RAMP_CYCLES;

fn main() -> Result<(), String> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse::<f64>().map_err(|e| format!("'{a}': {e}")))
        .collect::<Result<_, _>>()?;
    let (omega, v, t_end, switch, (x0, v0)) = match args[..] {
        [omega, v, t_end] => (omega, v, t_end, None, (0.0, 0.0)),
        [omega, v, t_end, x0, v0] => (omega, v, t_end, None, (x0, v0)),
        [omega, v, t_end, ts, o2, v2] => (omega, v, t_end, Some((ts, o2, v2)), (0.0, 0.0)),
        _ => {
            return Err(
                "usage: reference_impacts OMEGA V T_END [T_SWITCH OMEGA2 V2 | X0 V0]".into(),
            )
        }
    };
    let plate = Sinusoid::new(omega, v).map_err(|e| e.to_string())?;
    let mut sim = Simulator::with_state(
        Params::paper(),
        plate.into(),
        SolverOptions::default(),
        0.0,
        x0,
        v0,
    )
    .map_err(|e| e.to_string())?;
    let mut events = Vec::new();
    if let Some((ts, o2, v2)) = switch {
        events.extend(sim.events_until(ts).map_err(|e| e.to_string())?);
        let ramp =
            SetpointRamp::start(&mut sim, 0.0, o2, v2, RAMP_CYCLES).map_err(|e| e.to_string())?;
        events.extend(ramp.events_through(&mut sim).map_err(|e| e.to_string())?);
    }
    events.extend(sim.events_until(t_end).map_err(|e| e.to_string())?);
    println!("index,t,phase,x,v_before,v_after,zdot,delta_k,ended_in_sticking");
    for (k, e) in events.iter().enumerate() {
        if let Event::Impact(i) = e {
            let sticks = events[k + 1..].iter().find_map(|n| match n {
                Event::StickStart { impacts, .. } => Some(*impacts == i.index + 1),
                Event::Impact(_) => Some(false),
                _ => None,
            });
            println!(
                "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{}",
                i.index,
                i.t,
                i.phase.unwrap_or(f64::NAN),
                i.x,
                i.v_before,
                i.v_after,
                i.zdot,
                i.delta_k,
                u8::from(sticks == Some(true))
            );
        }
    }
    Ok(())
}
