"""Items 20 and 24: a setpoint profile that gives one angle twice (in rad and in deg) is refused
naming both columns, and a file that is not UTF-8 is named as such (not as "utf-8")."""

import pytest

from scenarios.cli import main as cli

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
