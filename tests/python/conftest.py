import json, locale, os, subprocess
import pytest


@pytest.fixture(scope="session")
def exe():
    return os.environ["ZWIDTH_EXE"]


@pytest.fixture(scope="session")
def src():
    return os.environ["ZWIDTH_SOURCE_DIR"]


@pytest.fixture(scope="session")
def cli(exe):
    """Runs the zwidth CLI; returns the CompletedProcess (text)."""
    def run(*args, check=True):
        p = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"zwidth {' '.join(map(str, args))}: exit {p.returncode}: {p.stderr}")
        return p
    return run


@pytest.fixture(scope="session")
def log_h5(src):
    return os.path.join(src, "datasets/phantom/phantom_30s.h5")


@pytest.fixture(scope="session")
def log_csv(src):
    return os.path.join(src, "datasets/phantom/phantom_30s.csv")


@pytest.fixture(scope="session")
def table1_json(src):
    return os.path.join(src, "datasets/phantom/table1.json")


@pytest.fixture
def german():
    """Python's locale set to de_DE.UTF-8 for the test (decimal commas), then restored."""
    old = locale.setlocale(locale.LC_ALL)
    try:
        locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")
    except locale.Error:
        pytest.skip("no de_DE.UTF-8 locale (scripts/setup generates it)")
    yield
    locale.setlocale(locale.LC_ALL, old)


@pytest.fixture(scope="session")
def batch_logs(exe, src, tmp_path_factory):
    """zwidth.batch's units: `zwidth simulate` of Table I (4 s, seeds 1..5) and last a broken text log."""
    d = tmp_path_factory.mktemp("batch_units")
    logs = []
    for s in (1, 2, 3, 4, 5):
        p = str(d / f"u{s}.csv")
        subprocess.run([exe, "simulate", "--model", os.path.join(src, "datasets/phantom/table1.json"), "-o", p,
                        "--seconds", "4", "--seed", str(s)], check=True, capture_output=True)
        logs.append(p)
    bad = str(d / "bad.csv")
    with open(bad, "w") as f:
        f.write("t,torque,position\n0,1,2\n0.001,x,y\n")
    return logs + [bad]
