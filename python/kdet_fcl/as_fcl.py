"""Run a program written for python-fcl, unmodified, with kdet_fcl.fcl in place of `fcl`.

    python3 -m kdet_fcl.as_fcl script.py [args...]
    python3 -m kdet_fcl.as_fcl -m package.module [args...]

Within the program, `import fcl` (and `from fcl import ...`) gets kdet_fcl.fcl: mesh pairs are
decided by kDet, the rest by FCL 0.7 as python-fcl does. In your own code, install() does the same
before the libraries that import fcl are imported.
"""
import os
import runpy
import sys

from . import fcl as _fcl


def install():
    """Make `import fcl` return kdet_fcl.fcl from now on (and fcl.fcl, fcl.collision_data)."""
    sys.modules["fcl"] = _fcl
    sys.modules["fcl.fcl"] = _fcl
    sys.modules["fcl.collision_data"] = _fcl


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    usage = "usage: python3 -m kdet_fcl.as_fcl script.py [args...] | -m module [args...]"
    if not argv or argv[0] in ("-h", "--help"):
        print(usage + "\n\n" + __doc__.strip().split("\n\n")[-1])
        return 0 if argv else 2
    install()
    if argv[0] == "-m":
        if len(argv) < 2:
            print(usage, file=sys.stderr)
            return 2
        sys.argv = argv[1:]
        runpy.run_module(argv[1], run_name="__main__", alter_sys=True)
    else:
        sys.argv = argv
        sys.path[0] = os.path.dirname(os.path.abspath(argv[0]))  # as `python3 script.py` has it
        runpy.run_path(argv[0], run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main())
