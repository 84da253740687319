"""The node's message types for the Eclipse Cyclone DDS Python binding: plain DDS types with the
ROS 2 type names (`<pkg>::msg::dds_::<Type>_`), XCDR1 as rmw uses."""
from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int32, uint8, uint32, uint64


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class MassState(IdlStruct, typename="bistable_impact_msgs::msg::dds_::MassState_"):
    header: Header
    t: float64
    x: float64
    v: float64
    z: float64
    zdot: float64
    kinetic_energy: float64
    potential_energy: float64
    well: uint8
    in_contact: bool
    impact_count: uint64
    shaker_mode: uint8
    shaker_omega: float64
    shaker_velocity: float64


@dataclass
class ImpactEvent(IdlStruct, typename="bistable_impact_msgs::msg::dds_::ImpactEvent_"):
    header: Header
    index: uint64
    t: float64
    phase: float64
    x: float64
    v_before: float64
    v_after: float64
    zdot: float64
    delta_k: float64
    ended_in_sticking: bool


@dataclass
class ShakerCommand(IdlStruct, typename="bistable_impact_msgs::msg::dds_::ShakerCommand_"):
    header: Header
    mode: uint8
    omega: float64
    velocity: float64
    z: float64
    zdot: float64


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time
