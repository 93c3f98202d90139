"""Items 20 and 24: a setpoint profile that gives one angle twice (in rad and in deg) is refused
naming both columns, and a file that is not UTF-8 is named as such (not as "utf-8")."""

import pytest

from quadcosim.main import main as cli

RUN = ["run", "tp", "--set", "duration=0.2"]


@pytest.mark.parametrize("angle", ["theta_d1", "theta_d3"])
def test_an_angle_given_in_rad_and_in_deg_is_refused(tmp_path, capsys, angle):
    profile = tmp_path / "flight.csv"
    profile.write_text(f"t,{angle},{angle}_deg\n0,0,0\n5,1,90\n")
    out = tmp_path / "run"
    assert cli([*RUN, f"flight={profile}", "--out", str(out)]) == 2
    assert f"{profile}: {angle} and {angle}_deg give one angle twice (rad and deg); keep one of the two columns" \
        in capsys.readouterr().err
    assert not out.exists()


def test_a_latin_1_profile_is_named_as_not_utf_8(tmp_path, capsys):
    profile = tmp_path / "vol.csv"
    profile.write_bytes("t,theta_d3_deg\n0,0\n# virage à droite\n5,90\n".encode("latin-1"))
    assert cli([*RUN, f"flight={profile}", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert f"{profile}: not UTF-8 text (byte 0xe0 at byte 28, a Latin-1 or Windows character?); save the file as " \
           "UTF-8" in err
    assert not err.rstrip().endswith(": utf-8")


def test_a_spreadsheets_byte_order_mark_is_not_part_of_the_header(tmp_path):
    from quadcosim.flight import SETPOINT
    from quadcosim.flight.profile_file import read_profile

    marked = tmp_path / "marked.csv"
    marked.write_text("t,z_d\n0,0\n2,-1.5\n", encoding="utf-8-sig")  # "CSV UTF-8" of a spreadsheet
    assert marked.read_bytes().startswith(b"\xef\xbb\xbf")  # before: "unknown column '\ufefft'"
    times, rows = read_profile(marked, SETPOINT)
    assert times.tolist() == [0.0, 2.0] and rows[:, SETPOINT.index("z_d")].tolist() == [0.0, -1.5]


def test_a_fifo_or_a_folder_is_named_as_not_a_file(tmp_path, capsys):
    import os

    os.mkfifo(tmp_path / "pipe.csv")  # exists, and a read would block until a writer came
    (tmp_path / "folder.csv").mkdir()
    for name in ("pipe.csv", "folder.csv"):
        assert cli([*RUN, f"flight={tmp_path / name}", "--out", str(tmp_path / "run")]) == 2
        err = capsys.readouterr().err
        kind = "a FIFO (named pipe)" if name == "pipe.csv" else "a folder"
        assert f"flight={tmp_path / name}: {kind}, not a regular file" in err and "no such file" not in err
