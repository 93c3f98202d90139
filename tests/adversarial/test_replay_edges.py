"""``quadcosim replay`` on ordinary bad input: complex samples, ``scored`` text, numbers that
overflow (``--rate 1e308``, a file's ``rate=1e308``), angles out of range, a ``meta`` whose
``estimator`` or ``gains`` is a list, ``--out`` where no file can be made, and a nearly full disk
(the JSON is written before the figure). Each exits 2 with a message, never a traceback."""

import json
import subprocess

import numpy as np
import pytest
from conftest import mounted

from quadcosim.main import main as cli


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A real recording: 1 s of tp, written by ``replay --from-tp``."""
    folder = tmp_path_factory.mktemp("replay")
    assert cli(["run", "tp", "--set", "duration=1", "--out", str(folder / "run")]) == 0
    assert cli(["replay", "--from-tp", str(folder / "run"), "--write", str(folder / "rec.npz")]) == 0
    with np.load(folder / "rec.npz") as archive:
        return folder / "rec.npz", {k: archive[k] for k in archive.files}


def _variant(tmp_path, recording, **changes):
    data = recording[1] | changes
    path = tmp_path / "variant.npz"
    np.savez(path, **data)
    return path


def _refused(argv, capsys, said):
    assert cli(["replay", *map(str, argv)]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err, err[-1500:]


def test_complex_samples_are_refused(tmp_path, recording, capsys):
    path = _variant(tmp_path, recording, gyro=recording[1]["gyro"] * (1 + 1e-3j))
    _refused([path], capsys, "variant.npz: gyro holds complex numbers")


@pytest.mark.parametrize("scored", [np.array(["yes", "no"] * 500 + ["no"]), np.full(1001, 2.0)])
def test_scored_text_or_numbers_other_than_0_and_1_are_refused(tmp_path, recording, capsys, scored):
    path = _variant(tmp_path, recording, scored=scored[:len(recording[1]["gyro"])])
    _refused([path], capsys, "variant.npz: scored holds")


@pytest.mark.parametrize(("options", "said"), [
    (["--rate", "1e308"], "--rate 1e+308: a sampling rate is a number of Hz above 0 and at most 100000"),
    (["--dip", "1e308"], "--dip 1e+308: the field's dip is an angle from -90 to 90 deg"),
    (["--field-from-data", "-1"], "--field-from-data -1: give the seconds (0 or more)"),
    (["--field-from-data", "1e308"], "--field-from-data 1e+308 s is longer than the recording (1.001 s)"),
    (["--out", "/proc/r.json"], "/proc/r.json: cannot create a file in /proc/"),
    (["--out", "{tmp}/missing/r.json"], "the folder {tmp}/missing/ does not exist"),
])
def test_numbers_and_outputs_no_replay_can_take_exit_2(tmp_path, recording, capsys, options, said):
    options = [o.format(tmp=tmp_path) for o in options]
    _refused([recording[0], *options], capsys, said.format(tmp=tmp_path))


def test_a_file_rate_that_overflows_is_refused(tmp_path, recording, capsys):
    _refused([_variant(tmp_path, recording, rate=np.array(1e308))], capsys,
             "rate = 1e+308 Hz is beyond any IMU's (at most 100000 Hz)")


@pytest.mark.parametrize(("meta", "said"), [
    ({"estimator": ["explicit"]}, "estimator = ['explicit'] must be a JSON object"),
    ({"estimator": {"kind": "explicit", "gains": [1, 2]}}, "estimator.gains = [1, 2] is a list"),
])
def test_a_meta_holding_lists_is_refused(tmp_path, recording, capsys, meta, said):
    _refused([_variant(tmp_path, recording, meta=np.array(json.dumps(meta)))], capsys, said)


def test_a_nearly_full_disk_keeps_the_json_written_before_the_figure(tmp_path, recording):
    with mounted(tmp_path / "small", "256k") as small:
        filler = small / "filler"
        subprocess.run(["dd", "if=/dev/zero", f"of={filler}", "bs=4k", "count=64"], capture_output=True)
        filler.write_bytes(bytes(max(0, filler.stat().st_size - 24 * 1024)))  # 24 kB left
        code = cli(["replay", str(recording[0]), "--figure", str(small / "replay.png"), "--out",
                    str(small / "r.json")])
        assert code == 1  # the figure did not fit: a full disk is a failure (exit 1), as for every command
        assert json.loads((small / "r.json").read_text())["estimator"] == "linear"
        assert not (small / "replay.png").exists()
