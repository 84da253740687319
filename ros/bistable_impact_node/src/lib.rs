//! ROS 2 node for the bistable impact oscillator, on `ros2-client` (RTPS/DDS, no ROS
//! installation needed): publishes the mass state, every impact event and `/clock`, takes
//! shaker commands, and serves its parameters. See `ros/README.md`. The modules here are free
//! of DDS (unit-tested); the binary's `node` modules wire them to DDS and run the loop.

pub mod args;
pub mod control;
pub mod diagnostics;
pub mod inbox;
pub mod logging;
pub mod msg;
pub mod names;
pub mod pacer;
pub mod params;
pub mod paramset;
pub mod paramsrv;
pub mod sim;
pub mod startgate;
pub mod state;
