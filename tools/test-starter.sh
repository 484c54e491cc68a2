#!/usr/bin/env bash
# The starter path on fires written by the reference OpenVDB library in each simulator's conventions
# (tests/starter/test_starter.py), against the release build: Debian's python3-openvdb (OpenVDB 10, with numpy) is
# installed when missing, and the test runs with Debian's Python, which that package serves. About a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
py=/usr/bin/python3
if ! "$py" -c 'import pyopenvdb' 2>/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q python3-openvdb > /dev/null 2>&1 || { apt-get update -q > /dev/null && apt-get install -y -q python3-openvdb > /dev/null; }
fi
[[ -f target/release/firemedium ]] || { echo "test-starter: target/release/firemedium is missing (cargo build --release)" >&2; exit 1; }
export FIREMEDIUM_COMMAND="$PWD/target/release/firemedium" FIREMEDIUM_REQUIRE_OPENVDB=1
(cd tests/starter && "$py" -m unittest -v test_starter 2>&1)
