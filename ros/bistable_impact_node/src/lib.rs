//! ROS 2 node for the bistable impact oscillator, on `ros2-client` (RTPS/DDS, no ROS
//! installation needed): publishes the mass state, every impact event and `/clock`, takes
//! shaker commands, and serves its parameters. See `ros/README.md`.

pub mod args;
pub mod control;
pub mod inbox;
pub mod msg;
pub mod names;
pub mod params;
pub mod paramsrv;
pub mod sim;
