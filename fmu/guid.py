#!/usr/bin/env python3
"""Derives the FMU's guid from modelDescription.xml and writes it into the file.

The guid is the first 16 bytes of SHA-256 over the file's bytes with the value of the first
`guid="..."` attribute emptied, formatted as {8-4-4-4-12} hex. fmu/build.rs computes the same
value, compiles it in, and refuses to build while the file holds another one.

    python3 fmu/guid.py            # rewrite modelDescription.xml if its guid is stale
    python3 fmu/guid.py --check    # exit 1 if it is stale
"""
import hashlib
import pathlib
import sys

KEY = b'guid="'


def derive(data: bytes) -> tuple[str, int, int]:
    """Returns (guid, start, end) where data[start:end] is the current attribute value."""
    start = data.index(KEY) + len(KEY)
    end = data.index(b'"', start)
    h = hashlib.sha256(data[:start] + data[end:]).hexdigest()[:32]
    guid = "{%s-%s-%s-%s-%s}" % (h[:8], h[8:12], h[12:16], h[16:20], h[20:])
    return guid, start, end


def main() -> int:
    path = pathlib.Path(__file__).resolve().parent.parent / "modelDescription.xml"
    data = path.read_bytes()
    guid, start, end = derive(data)
    current = data[start:end].decode()
    if current == guid:
        print(f"guid {guid} is up to date")
        return 0
    if "--check" in sys.argv[1:]:
        print(f"stale guid {current}, expected {guid}: run `make fmu-guid`", file=sys.stderr)
        return 1
    path.write_bytes(data[:start] + guid.encode() + data[end:])
    print(f"guid {current} -> {guid}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
