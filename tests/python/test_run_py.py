"""zwidth.run: the CLI's `zwidth run` from Python (report::RunToFolder, the one pipeline), and the
defaults of Python's estimate()/fit() being the CLI's (fit::UserFitOptions, the window rule).

The reference is the CLI itself, run on the same log: every file of its run folder must equal
Python's byte for byte once the provenance's command and date are blanked."""
import json
import os
import re
import subprocess
import warnings

import numpy as np
import pytest

import zwidth


def _blank_provenance(name, data):
    text = data.decode("utf-8")
    if name.endswith(".json"):
        text = re.sub(r'"command": "[^"\n]*"', '"command": ""', text)
        text = re.sub(r'"utc_date": "[^"\n]*"', '"utc_date": ""', text)
    if name.endswith(".html"):
        text = re.sub(r"report written [0-9T:Z-]+; command: <code>.*?</code>", "report written; command:", text)
    return text


def _files(folder):
    out = {}
    for root, _, names in os.walk(folder):
        for n in names:
            p = os.path.join(root, n)
            with open(p, "rb") as f:
                out[os.path.relpath(p, folder)] = f.read()
    return out


@pytest.fixture(scope="module")
def short_log(tmp_path_factory):
    # Synthetic: Table I simulated for 12 s at 1 kHz (white-noise torque, seed 3).
    d = tmp_path_factory.mktemp("runlog")
    path = str(d / "log.csv")
    zwidth.simulate(zwidth.Model.table1(), seconds=12, seed=3).save(path)
    return path


def test_python_run_writes_the_cli_folder_byte_for_byte(short_log, cli, tmp_path):
    args = dict(reference="table1", delays=[2, 5], b_points=200, figures=False)
    cli("run", short_log, "-o", tmp_path / "cli", "--reference", "table1", "--delays", "2,5", "--b-points", "200",
        "--no-figures")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the samples past the last segment
        r = zwidth.run(short_log, tmp_path / "py", **args)
    assert r["quality"] in ("good", "poor") and r["out_dir"] == str(tmp_path / "py")
    a, b = _files(tmp_path / "cli"), _files(tmp_path / "py")
    assert sorted(a) == sorted(b)
    assert {"summary.json", "model.json", "report.html", "frf.csv", "boundary.csv"} <= set(a)
    for name in a:
        assert _blank_provenance(name, a[name]) == _blank_provenance(name, b[name]), name
    # The provenance says who asked: the Python call, not a command line.
    assert json.loads(b["summary.json"])["provenance"]["command"].startswith("zwidth.run(")


def test_python_run_with_a_filter_hand_and_figure_files_matches_the_cli(short_log, cli, tmp_path):
    # The loop is resolved at the log's period by the same rule; figures/ data files as well.
    cli("run", short_log, "-o", tmp_path / "cli", "--velocity-filter-hz", "40", "--hand", "0.001,0.002,0.5",
        "--delays", "3", "--b-points", "100", "--modes", "2")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        zwidth.run([short_log], str(tmp_path / "py"), velocity_filter_hz=40.0, hand=(0.001, 0.002, 0.5),
                   delays=[3], b_points=100, modes=2)
    a, b = _files(tmp_path / "cli"), _files(tmp_path / "py")
    assert sorted(a) == sorted(b)
    for name in a:
        if name.endswith((".json", ".html", ".csv", ".dat", ".gp")):
            assert _blank_provenance(name, a[name]) == _blank_provenance(name, b[name]), name


def test_python_run_fits_friction_as_the_cli_run_byte_for_byte(cli, table1_json, tmp_path):
    # Synthetic: Table I simulated by the CLI for 20 s with Coulomb friction 0.004 N m (seed 7). The
    # friction fit (analysis::FrictionInputFor) is the same rule from both front ends.
    log = str(tmp_path / "friction.csv")
    cli("simulate", "--model", table1_json, "--seconds", "20", "--coulomb", "0.004", "--seed", "7", "-o", log)
    cli("run", log, "-o", tmp_path / "cli", "--delays", "2", "--b-points", "40", "--no-figures")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        zwidth.run(log, tmp_path / "py", delays=[2], b_points=40, figures=False)
    a, b = _files(tmp_path / "cli"), _files(tmp_path / "py")
    assert sorted(a) == sorted(b)
    for name in a:
        assert _blank_provenance(name, a[name]) == _blank_provenance(name, b[name]), name
    model = json.loads(b["model.json"])
    assert model["friction"]["coulomb_pos"] > 0.001 and model["fit"]["friction"]["status"] == "fitted"
    assert json.loads(b["summary.json"])["boundary"][0]["friction"]["at_zero_B"]["amplitude"] > 0
    # friction='none': only detected; a bad word is refused by keyword before anything is written.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        zwidth.run(log, tmp_path / "none", delays=[2], b_points=40, figures=False, friction="none")
    assert "friction" not in json.loads((tmp_path / "none" / "model.json").read_text())
    with pytest.raises(zwidth.InputError, match=r"^friction 'viscous': expected none, auto or coulomb"):
        zwidth.run(log, tmp_path / "bad", friction="viscous")
    assert not os.path.exists(tmp_path / "bad")


def test_python_runs_on_threads_with_friction_write_the_serial_folders(cli, table1_json, tmp_path):
    # zwidth.run releases the GIL: two friction fits (FFTs planned under zwidth::FftwPlannerMutex)
    # and a Welch estimate side by side give the bytes of the runs made one after the other.
    # Synthetic: Table I with Coulomb friction 0.004 N m (seeds 7, 8), 12 s each, made by the CLI.
    import concurrent.futures
    logs = []
    for seed in (7, 8):
        logs.append(str(tmp_path / f"f{seed}.csv"))
        cli("simulate", "--model", table1_json, "--seconds", "12", "--coulomb", "0.004", "--seed", seed, "-o", logs[-1])
    kw = dict(delays=[2], b_points=30, figures=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for i, log in enumerate(logs):
            zwidth.run(log, tmp_path / f"serial{i}", **kw)
        with concurrent.futures.ThreadPoolExecutor(2) as pool:
            list(pool.map(lambda i: zwidth.run(logs[i], tmp_path / f"threaded{i}", **kw), range(2)))
    def content(name, data):  # the provenance aside: its inputs are the process's (both logs, on threads)
        if name.endswith(".json"):
            j = json.loads(data)
            j.pop("provenance", None)
            return j
        text = data.decode("utf-8")
        return text[:text.find("<p class='provenance'>")] if name.endswith(".html") else text
    for i in range(2):
        a, b = _files(tmp_path / f"serial{i}"), _files(tmp_path / f"threaded{i}")
        assert sorted(a) == sorted(b)
        assert json.loads(a["model.json"])["fit"]["friction"]["status"] == "fitted"
        for name in a:
            assert content(name, a[name]) == content(name, b[name]), name


def test_python_run_prints_nothing_on_stdout(short_log, tmp_path, src):
    code = ("import warnings, zwidth\nwarnings.simplefilter('ignore')\n"
            f"zwidth.run({short_log!r}, {str(tmp_path / 'o')!r}, figures=False, delays=[2], b_points=50)\n")
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(zwidth.__file__)))
    p = subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout == "" and p.stderr == ""
    assert os.path.isfile(tmp_path / "o" / "summary.json")


def _siblings(folder):
    parent = os.path.dirname(str(folder))
    return sorted(os.listdir(parent))


def test_python_run_refuses_what_the_cli_refuses_and_leaves_nothing(short_log, cli, tmp_path):
    out = tmp_path / "taken"
    out.mkdir()
    (out / "mine.txt").write_text("keep me")
    before = _siblings(out)
    with pytest.raises(zwidth.InputError, match=r"not empty.*force"):
        zwidth.run(short_log, out, figures=False)
    assert (out / "mine.txt").read_text() == "keep me" and os.listdir(out) == ["mine.txt"]
    p = cli("run", short_log, "-o", out, "--no-figures", check=False)
    assert p.returncode == 2 and "--force" in p.stderr
    # Bad values named by keyword, before anything is read or written.
    for kw, pattern in [(dict(delays=[-1]), "delays"), (dict(report_filter_hz=float("nan")), "report_filter_hz"),
                        (dict(b_points=1), "b_points"), (dict(b_step=float("inf")), "b_step"),
                        (dict(units="metric"), "units"), (dict(velocity_filter_hz=float("nan")), "velocity_filter_hz"),
                        (dict(window="blackman"), "window"), (dict(modes="many"), "modes"),
                        (dict(reference=str(tmp_path / "none.json")), "cannot open model file")]:
        target = tmp_path / ("new_" + next(iter(kw)))
        with pytest.raises(zwidth.InputError, match=pattern):
            zwidth.run(short_log, target, figures=False, **kw)
        assert not os.path.exists(target)
    with pytest.raises(TypeError, match="unexpected"):
        zwidth.run(short_log, tmp_path / "x", no_such_option=1)
    with pytest.raises(zwidth.InputError, match="parent|exist"):
        zwidth.run(short_log, tmp_path / "no" / "such" / "dir", figures=False)
    assert _siblings(out) == before  # no temporary folder left beside


def test_python_run_force_replaces_zwidths_files_and_keeps_others(short_log, tmp_path):
    out = tmp_path / "again"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        zwidth.run(short_log, out, figures=False, delays=[2], b_points=50)
        (out / "notes.txt").write_text("mine")
        zwidth.run(short_log, out, figures=False, delays=[4], b_points=50, force=True)
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "summary.json").read_text())["boundary"][0]["delay_samples"] == 4


def test_default_python_fit_is_the_default_cli_fit_at_5khz(tmp_path, cli):
    # Synthetic: Table I simulated for 20 s at 5 kHz (seed 4) with a 2-sample input delay: the
    # CLI's window rule gives 16384 samples there (not 4096) and its delay default is 'auto'.
    m = zwidth.Model.table1()
    path = str(tmp_path / "fast.csv")
    zwidth.simulate(m, seconds=20, sample_rate_hz=5000, delay_samples=2, seed=4).save(path)
    cli("fit", path, "-o", tmp_path / "cli.json")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        res = zwidth.fit(path)
        frf = zwidth.estimate(path)
    assert frf.window_length == 16384  # the CLI's rule at 5 kHz, not 4096
    c = zwidth.Model.load(str(tmp_path / "cli.json"))
    p = res.model
    assert p.delay_samples == c.delay_samples
    assert (p.m, p.b, p.modes) == (c.m, c.b, c.modes)  # to the last digit
    assert res.delay_choice != ""  # the delay was searched, as the CLI's default
    # A Log gives the same estimate as its file (the rule of its rate and length).
    log = zwidth.read_log(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert zwidth.estimate(log) == frf or np.array_equal(zwidth.estimate(log).H, frf.H)


def test_defaults_come_from_the_library_not_the_binding():
    import inspect
    fit_sig = inspect.signature(zwidth.fit).parameters
    est_sig = inspect.signature(zwidth.estimate).parameters
    assert fit_sig["delay_samples"].default == "auto"
    assert est_sig["window_length"].default == 0
    assert inspect.signature(zwidth.estimate_logs).parameters["window_length"].default == 0
    assert inspect.signature(zwidth.run).parameters["modes"].default == "auto"


def test_welch_words_are_parsed_once_with_the_same_message(cli, short_log, tmp_path):
    # ident::ParseWelchOptions: the CLI says the flag, Python the keyword, the same sentence.
    for kw, flag, bad in [("window", "--window", "blackman"), ("detrend", "--detrend", "quadratic"),
                          ("estimator", "--estimator", "h3")]:
        p = cli("estimate", short_log, "-o", tmp_path / "x.csv", flag, bad, check=False)
        assert p.returncode == 2
        with pytest.raises(zwidth.InputError) as e:
            zwidth.estimate(short_log, **{kw: bad})
        py_msg = str(e.value)
        assert py_msg.startswith(f"{kw} '{bad}' is not one of"), py_msg
        assert p.stderr.strip() == "zwidth: error: " + flag + py_msg[len(kw):]
        with pytest.raises(zwidth.InputError, match=kw):
            zwidth.estimate_logs([short_log], **{kw: bad})
