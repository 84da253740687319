//! The binary's DDS side: the endpoints and their QoS ([`dds`]), what the loop reads between
//! its steps ([`serve`]), what it publishes ([`publish`]), and the loop itself ([`run`]). The
//! logic they call is in the library, free of DDS.

pub mod dds;
pub mod publish;
pub mod run;
pub mod serve;
