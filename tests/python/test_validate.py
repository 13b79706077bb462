"""zwidth.validate (analysis/validate.h) from Python: the same numbers as `zwidth validate -o`,
a model fitted to the log passes and one of a different device is flagged, the provenance names
the Python call and the log's SHA-256."""
import hashlib, json

import zwidth


def test_validate_equals_the_cli_and_flags_another_device(cli, log_csv, tmp_path):
    model_path = tmp_path / "model.json"
    cli("fit", log_csv, "-o", model_path)
    out = tmp_path / "validation.json"
    cli("validate", model_path, log_csv, "-o", out)
    want = json.loads(out.read_text())
    model = zwidth.Model.load(str(model_path))
    got = zwidth.validate(model, log_csv)
    for key in ("quality", "quality_reasons", "fit_percent", "chi2_per_dof", "dof", "correlation_bound",
                "autocorrelation_outside", "cross_correlation_outside"):
        assert got[key] == want[key], key
    assert got["residual_autocorrelation"] == want["residual_autocorrelation"]
    # A Log in memory gives the same as its file.
    assert zwidth.validate(model, zwidth.read_log(log_csv))["chi2_per_dof"] == got["chi2_per_dof"]
    p = got["provenance"]
    assert p["command"].startswith("zwidth.validate(")
    assert p["zwidth_version"] == zwidth.__version__
    assert {i["sha256"] for i in p["inputs"]} == {hashlib.sha256(open(log_csv, "rb").read()).hexdigest()}
    # Another device: the fitted model with its inertia tripled and its first mode 30 % higher.
    other = json.loads(model_path.read_text())
    other["m"] *= 3
    other["modes"][0]["omega"] *= 1.3
    for key in ("std", "covariance", "fit", "provenance"):
        other.pop(key, None)
    bad = zwidth.validate(zwidth.Model.from_json(json.dumps(other)), log_csv)
    assert want["quality"] == "good" and bad["quality"] == "poor", (want["quality"], bad["quality"])
    assert bad["chi2_per_dof"] > 10 * want["chi2_per_dof"]
