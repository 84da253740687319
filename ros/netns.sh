#!/bin/sh
# Runs a command in a new network namespace (user namespace, no root needed) whose only
# interface is loopback with multicast, so DDS discovery and traffic never leave the machine
# and separate tests never see each other.
exec unshare -rn sh -c 'ip link set lo up && ip link set lo multicast on &&
  ip route add 224.0.0.0/4 dev lo && exec "$@"' netns "$@"
