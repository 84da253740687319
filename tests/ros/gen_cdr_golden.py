"""Fills in the "cdr" bytes of ros/bistable_impact_node/tests/data/cdr_golden.json with
rclpy's serialisation of the given field values, padding set to zero as the Rust side writes
it (run when a message changes; the tests check that Rust and rclpy agree with the file)."""
import json
import sys

from cdr_common import GOLDEN, build, padding

cases = json.loads(GOLDEN.read_text())
for case in cases:
    msg, data = build(case)
    data = bytearray(data)
    for p in padding(msg):
        data[p] = 0
    case["cdr"] = data.hex()
GOLDEN.write_text(json.dumps(cases, indent=2) + "\n")
print(f"wrote {len(cases)} cases to {GOLDEN}", file=sys.stderr)
