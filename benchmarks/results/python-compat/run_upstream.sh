#!/usr/bin/env bash
# python-fcl's own tests and example, and trimesh's collision tests, unmodified, on kdet_fcl.fcl
# (`python3 -m kdet_fcl.as_fcl` makes their `import fcl` kdet_fcl.fcl). Neither project is a Debian
# package: pass checkouts of them (e.g. git clones of BerkeleyAutomation/python-fcl and
# mikedh/trimesh). trimesh's tests need python3-pytest, python3-scipy and python3-networkx.
#
#   PYFCL_DIR=... TRIMESH_DIR=... [BUILD=build] benchmarks/results/python-compat/run_upstream.sh
set -u
root=$(cd "$(dirname "$0")/../../.." && pwd)
build=${BUILD:-$root/build}
: "${PYFCL_DIR:?a python-fcl checkout}" "${TRIMESH_DIR:?a trimesh checkout}"
py=${PYTHON:-/usr/bin/python3}
export PYTHONPATH="$build/python:$TRIMESH_DIR" PYTHONDONTWRITEBYTECODE=1
status=0
echo "== python-fcl $(git -C "$PYFCL_DIR" rev-parse --short HEAD 2>/dev/null): tests/test_fcl.py, tests/test_precision.py"
(cd "$PYFCL_DIR/tests" && "$py" -m kdet_fcl.as_fcl -m unittest -v test_fcl test_precision) 2>&1 || status=1
echo "== python-fcl: examples/example.py"
(cd "$PYFCL_DIR/examples" && "$py" -m kdet_fcl.as_fcl example.py) > /tmp/kdet-pyfcl-example.log 2>&1 || status=1
tail -n 3 /tmp/kdet-pyfcl-example.log; echo "($(wc -l < /tmp/kdet-pyfcl-example.log) lines)"
echo "== trimesh $(git -C "$TRIMESH_DIR" rev-parse --short HEAD 2>/dev/null): tests/test_collision.py"
(cd "$TRIMESH_DIR/tests" && "$py" -m kdet_fcl.as_fcl -m pytest -v -p no:cacheprovider test_collision.py) 2>&1 || status=1
echo "== the fcl module they ran on"
"$py" -c "import kdet_fcl.as_fcl as a; a.install(); import fcl; print(fcl.__name__, fcl.__file__)"
exit $status
