"""The one break of the whole adversarial sweep: SIGTERM 8 s into a calibrate that ended at
that moment killed the process (exit -15): main had returned and restored SIGTERM's default.
A signal while the process leaves now ends it at once with the command's own code (its work is
done), never by the signal."""

import subprocess
import sys

from conftest import ROOT

LEAVING = """
import atexit, os, signal
import quadcosim.cli as program

def finished(argv=None):  # the command's work done; the signal arrives while the process exits
    atexit.register(lambda: os.kill(os.getpid(), signal.{name}))
    return 0

program.main = finished
program.entry()
"""


def test_a_signal_while_the_process_leaves_exits_with_the_commands_code():
    for name, code in (("SIGTERM", 0), ("SIGINT", 0)):
        done = subprocess.run([sys.executable, "-c", LEAVING.format(name=name)], cwd=ROOT, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == code, (name, done.returncode, done.stderr[-1500:])
        assert "Traceback" not in done.stderr
