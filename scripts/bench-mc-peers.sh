#!/usr/bin/env bash
# Marching cubes side by side with VTK (vtkFlyingEdges3D, vtkMarchingCubes)
# and scikit-image: makes the peers' Python environment if it is missing
# (target/peer-venv: vtk, scikit-image, numpy from the package registry),
# then runs `cargo bench --bench mc_peers`, which prints the table and
# writes target/mc_peers/report.json. Arguments go to the bench binary.
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${CHISEL_PEER_VENV:-target/peer-venv}"
if ! "$venv/bin/python" -c "import vtk, skimage, numpy" 2>/dev/null; then
    echo "bench-mc-peers: making $venv (vtk, scikit-image, numpy)" >&2
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --upgrade pip
    "$venv/bin/pip" install --quiet vtk scikit-image numpy
fi
export CHISEL_PEER_PYTHON="$(cd "$venv" && pwd)/bin/python"
exec cargo bench --bench mc_peers -- "$@"
