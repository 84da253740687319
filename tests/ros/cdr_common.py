"""Shared by the CDR golden-file test and its generator: message classes, building a message
from the golden file's field values, and the positions of CDR alignment padding (Fast DDS
leaves padding bytes uninitialised, so only the other bytes are comparable)."""
import pathlib

from bistable_impact_msgs.msg import ImpactEvent, MassState, ShakerCommand
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock

ROOT = pathlib.Path(__file__).resolve().parents[2]
GOLDEN = ROOT / "ros/bistable_impact_node/tests/data/cdr_golden.json"
TYPES = {"MassState": MassState, "ImpactEvent": ImpactEvent, "ShakerCommand": ShakerCommand, "Clock": Clock}
SIZES = {"boolean": 1, "octet": 1, "uint8": 1, "int8": 1, "int16": 2, "uint16": 2, "int32": 4,
         "uint32": 4, "float": 4, "int64": 8, "uint64": 8, "double": 8}


def assign(msg, fields):
    """Sets the (nested) fields of a rosidl message from a dict."""
    for name, value in fields.items():
        if isinstance(value, dict):
            assign(getattr(msg, name), value)
        else:
            setattr(msg, name, type(getattr(msg, name))(value))
    return msg


def build(case):
    """The message of a golden case and its bytes serialised by rclpy."""
    msg = assign(TYPES[case["type"]](), case["fields"])
    return msg, serialize_message(msg)


def fields_of(msg, like):
    """The fields of `msg` named in `like` (nested), as a dict."""
    return {k: fields_of(getattr(msg, k), v) if isinstance(v, dict) else getattr(msg, k) for k, v in like.items()}


def padding(msg):
    """Byte positions (in the serialised message, 4-byte encapsulation header included) that
    are CDR alignment padding, from the message's field types (plain CDR, XCDR1)."""
    pads = []
    offset = 0

    def walk(m):
        nonlocal offset
        for name, kind in m.get_fields_and_field_types().items():
            value = getattr(m, name)
            if kind == "string":
                size, extra = 4, len(value.encode()) + 1
            elif kind in SIZES:
                size, extra = SIZES[kind], 0
            else:
                walk(value)
                continue
            while offset % size:
                pads.append(offset + 4)
                offset += 1
            offset += size + extra

    walk(msg)
    return pads
