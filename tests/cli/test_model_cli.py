"""`mpeg4fa model ...` on the generic head (skips when it is not built)."""
import json

import pytest

from mpeg4fa.cli import main

pytestmark = pytest.mark.usefixtures("generic_head_installed")



def test_pose_json_has_the_documented_shape(cli):
    code, out, _ = cli("model", "pose", "--fap", "3=200", "--fap", "19=-100", "--json")
    assert code == 0
    data = json.loads(out)
    assert set(data) == {"fapu", "neutral", "posed"}
    assert set(data["fapu"]) == {"ES0", "IRISD0", "ENS0", "MNS0", "MW0"}
    assert len(data["neutral"]) == len(data["posed"]) == 84
    drop = data["neutral"]["2.1"][1] - data["posed"]["2.1"][1]
    assert drop == pytest.approx(200 * data["fapu"]["MNS0"] / 1024, rel=1e-6)
    lift = data["posed"]["3.1"][1] - data["neutral"]["3.1"][1]
    assert lift == pytest.approx(100 * data["fapu"]["IRISD0"] / 1024, rel=1e-6)


def test_pose_text_and_viseme(cli):
    code, out, _ = cli("model", "pose", "--viseme", "AA", "--expression", "joy=30")
    assert code == 0 and "open_jaw" in out and "2.1" in out


def test_pose_arkit_deformer_gives_the_same_points(cli):
    _, a, _ = cli("model", "pose", "--viseme", "ou", "--json")
    _, b, _ = cli("model", "pose", "--viseme", "ou", "--deformer", "arkit", "--json")
    pa, pb = json.loads(a)["posed"], json.loads(b)["posed"]
    assert all(pa[k] == pytest.approx(pb[k], abs=1e-6) for k in pa)


def test_bad_pose_requests(cli):
    with pytest.raises(SystemExit):
        main(["model", "pose", "--fap", "1=3"])
    code, _, err = cli("model", "pose", "--viseme", "XX")
    assert code == 1 and "unknown viseme" in err


def test_info_and_calibration_to_an_fdp(cli, tmp_path):
    code, out, _ = cli("model", "info", "--json")
    info = json.loads(out)
    assert info["parts"]["skin"]["vertices"] > 4000 and len(info["feature_points"]) == 84
    from mpeg4fa.face import FaceModel
    from mpeg4fa.fdp import Fdp, save_fdp
    fdp = FaceModel.default().to_fdp()
    bigger = Fdp.from_points({label: 1.2 * fdp.point(label) for label in fdp.labels})
    path = tmp_path / "face.fdp"
    save_fdp(bigger, path)
    code, out, _ = cli("model", "info", "--fdp", str(path), "--json")
    assert code == 0
    calibrated = json.loads(out)
    assert calibrated["fapu"]["ES0"] == pytest.approx(1.2 * info["fapu"]["ES0"], rel=1e-6)
    assert calibrated["calibration"]["max_error_relative"] < 1e-6
    code, _, err = cli("model", "info", "--fdp", str(tmp_path / "missing.fdp"))
    assert code == 1 and "missing.fdp" in err
