//! The binary's DDS side: the endpoints and their QoS ([`dds`]), what the loop reads between
//! its steps ([`serve`]), what it publishes ([`publish`]), the loop itself ([`run`]) and the DDS
//! layer's own warnings in the node's log ([`ddslog`]). The
//! logic they call is in the library, free of DDS.

pub mod dds;
pub mod ddslog;
pub mod publish;
pub mod run;
pub mod serve;
