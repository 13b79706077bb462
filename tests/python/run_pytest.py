#!/usr/bin/env python3
"""ctest entry for the Python tests: python3 run_pytest.py BUILD_DIR ZWIDTH_EXE SOURCE_DIR [pytest args].

Exits 77 (ctest's skip code) when pytest or NumPy is not installed or the module was not built.
"""
import os, sys


def main():
    build, exe, src = sys.argv[1:4]
    try:
        import pytest, numpy  # noqa: F401
    except ImportError as e:
        print(f"skipped: {e} (apt-get install python3-pytest python3-numpy)")
        sys.exit(77)
    pkg = os.path.join(build, "python")
    if not os.path.isfile(os.path.join(pkg, "zwidth", "__init__.py")):
        print(f"skipped: the Python module was not built in {pkg} (needs python3-dev and pybind11-dev)")
        sys.exit(77)
    sys.dont_write_bytecode = True  # nothing written into the source tree
    os.environ["ZWIDTH_EXE"] = exe
    os.environ["ZWIDTH_SOURCE_DIR"] = src
    sys.path.insert(0, pkg)
    here = os.path.dirname(os.path.abspath(__file__))
    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", "--rootdir", here, here] + sys.argv[4:]))


# Guarded: a multiprocessing "spawn" child imports this script again (as __mp_main__) and
# must not start pytest once more.
if __name__ == "__main__":
    main()
