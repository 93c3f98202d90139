"""An adversarial sweep of the command line's edges: broken inputs tried against every surface.

Surfaces: flight logs (truncated, bit-flipped, concatenated, shifted or repeated stamps, zeros
and garbage around them, FIFOs, folders, devices, sparse files, empty files, names that are not
UTF-8) through ``log info``, ``log info --json``, ``log plot``, ``log replay`` and ``calibrate``;
``calibrate``'s options and ``--score`` files; ``plot``/``compare`` of damaged runs and into
refused outputs; CSV setpoint profiles; ``--set`` gains; ``findings``; the edges of one audit
(FIFOs and devices read as inputs, replay's and bench's numbers, scenario options that misled,
user estimators breaking the contract, ``--score`` files misread); interrupts (SIGINT and
SIGTERM at several delays); two processes on one output folder; full disks.

The cheap cases run in this process (``quadcosim.main.main``), each under an alarm: an exception
that escapes is a traceback, an alarm a hang. Interrupts, concurrency and full disks run as
processes. Every case's exit code must be 0, 1, 2, 130 or 143 (as the exit-code table says),
with no traceback and within its time limit.

``python tests/adversarial/sweep.py [--json FILE]`` (as root for the full-disk cases) prints each
failure and the counts by surface; it exits 1 when a case traced back or hung.
"""

from __future__ import annotations

import contextlib
import io
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
LOGS = Path(os.environ.get("QUADCOSIM_FLIGHT_LOGS") or ROOT.parent / "shared" / "data" / "flightlogs")
IN_PROCESS_LIMIT_S = 120
PROCESS_LIMIT_S = 240
EXITS = {0, 1, 2, 130, 143}
SIGNAL = "Setpoint.z_d"  # a signal every run of tp records


class Hang(BaseException):
    """The alarm of a case that ran past its limit."""


def _alarm(signum, frame):
    raise Hang()


class Sweep:
    """Cases run and their outcomes, by surface."""

    def __init__(self, work: Path):
        self.work = work
        self.outcomes: list[dict] = []
        self.counter = 0

    def folder(self) -> Path:
        self.counter += 1
        return self.work / f"case{self.counter}"

    def cli(self, surface: str, what: str, argv: list[str], limit: float = IN_PROCESS_LIMIT_S) -> dict:
        """``quadcosim ARGV`` in this process, under an alarm."""
        from quadcosim.main import main

        out, err = io.StringIO(), io.StringIO()
        started = time.perf_counter()
        previous = signal.signal(signal.SIGALRM, _alarm)
        signal.setitimer(signal.ITIMER_REAL, limit)
        code, problem = None, ""
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                code = main([str(a) for a in argv])
        except Hang:
            problem = "hang"
        except SystemExit as exit_:  # argparse's refusals
            code = exit_.code if isinstance(exit_.code, int) else 2
        except BaseException as error:  # noqa: BLE001 - an escaping exception is the finding
            problem = "traceback: " + "".join(traceback.format_exception_only(error)).strip()[:300]
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
            import matplotlib.pyplot as plt

            plt.close("all")
        if not problem and "Traceback" in err.getvalue():
            problem = "traceback printed"
        if not problem and code not in EXITS:
            problem = f"exit {code}"
        return self._record(surface, what, argv, code, problem, err.getvalue(), time.perf_counter() - started)

    def process(self, surface: str, what: str, argv: list[str], limit: float = PROCESS_LIMIT_S,
                signal_after: tuple[float, int] | None = None, cwd: Path | None = None) -> dict:
        """``quadcosim ARGV`` as a process; ``signal_after`` (seconds, signal) interrupts it."""
        started = time.perf_counter()
        child = subprocess.Popen([sys.executable, "-m", "quadcosim.main", *map(str, argv)], cwd=cwd or ROOT,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 env=os.environ | {"MPLBACKEND": "Agg"})
        return self.finish(surface, what, argv, child, started, limit, signal_after)

    def finish(self, surface, what, argv, child, started, limit=PROCESS_LIMIT_S, signal_after=None) -> dict:
        if signal_after is not None:
            try:
                child.wait(timeout=signal_after[0])
            except subprocess.TimeoutExpired:
                child.send_signal(signal_after[1])
        try:
            _, err = child.communicate(timeout=limit)
            code, problem = child.returncode, ""
        except subprocess.TimeoutExpired:
            child.kill()
            _, err = child.communicate()
            code, problem = None, "hang"
        if not problem and "Traceback" in err:
            problem = "traceback: " + err.strip().splitlines()[-1][:300]
        if not problem and code not in EXITS:
            problem = f"exit {code}"
        return self._record(surface, what, argv, code, problem, err, time.perf_counter() - started)

    def _record(self, surface, what, argv, code, problem, err, seconds) -> dict:
        said = next((line for line in reversed(err.strip().splitlines()) if line.strip()), "")
        outcome = {"surface": surface, "what": what, "argv": [str(a) for a in argv], "exit": code,
                   "problem": problem, "said": said[:300], "seconds": round(seconds, 2)}
        self.outcomes.append(outcome)
        mark = "BROKEN " + problem if problem else f"exit {code}"
        print(f"[{surface}] {what}: {mark} ({seconds:.1f} s) {said[:140]}", flush=True)
        return outcome


# ---------------------------------------------------------------- inputs

def _flip(data: bytes, flips: int, seed: int) -> bytes:
    rng = random.Random(seed)
    buffer = bytearray(data)
    for _ in range(flips):
        k = rng.randrange(len(buffer))
        buffer[k] ^= 1 << rng.randrange(8)
    return bytes(buffer)


def _shift_text(data: bytes, message: str, by_s: float) -> bytes:
    """A text DataFlash log with ``message``'s TimeUS moved by ``by_s``."""
    lines = []
    for line in data.decode().splitlines():
        parts = line.split(", ")
        if parts[0] == message and len(parts) > 1 and parts[1].strip().lstrip("-").isdigit():
            parts[1] = str(int(parts[1]) + int(by_s * 1e6))
        lines.append(", ".join(parts))
    return ("\n".join(lines) + "\n").encode()


def log_inputs(work: Path) -> list[tuple[str, Path]]:
    """(description, path) of every broken log."""
    from tests.flightlog_synthetic import write_log

    folder = work / "logs"
    folder.mkdir()
    text = folder / "synthetic.log"
    write_log(text, duration=20.0)
    data = text.read_bytes()
    made: list[tuple[str, Path]] = [("a whole synthetic text log", text)]

    def put(name: str, content: bytes, what: str):
        path = folder / name
        path.write_bytes(content)
        made.append((what, path))

    for share in (0.0, 0.001, 0.2, 0.5, 0.9, 0.999):
        put(f"cut{share}.log", data[:int(share * len(data))], f"text log cut at {share:.1%}")
    for flips, seed in ((1, 1), (30, 2), (1000, 3), (20000, 4)):
        put(f"flip{flips}.log", _flip(data, flips, seed), f"text log, {flips} bits flipped")
    put("twice.log", data + data, "text log concatenated with itself")
    for message, by in (("MAG", 100.0), ("MAG", -100.0), ("ATT", 15.0), ("IMU", -5.0), ("RCOU", 1000.0),
                        ("BAT", 1e9)):
        put(f"shift_{message}{by:g}.log", _shift_text(data, message, by), f"text log, {message} stamps moved {by:g} s")
    reversed_lines = b"\n".join(reversed(data.splitlines())) + b"\n"
    put("reversed.log", reversed_lines, "text log, lines in reverse order")
    put("zeros.log", data + bytes(1_000_000), "text log, 1 MB of zeros appended")
    put("garbage.log", os.urandom(5000) + data, "text log, 5 kB of random bytes before it")
    put("nan.log", data.replace(b", 0.", b", nan"), "text log, values made nan")
    put("empty.log", b"", "an empty .log")
    put("empty.bin", b"", "an empty .bin")
    put("empty.ulg", b"", "an empty .ulg")
    put("text.bin", data, "a text log named .bin")
    put("ulog_magic.log", b"ULog\x01\x12\x35\x01" + data, "a text log behind the ULog magic")
    for name, cut in (("erlebrain_APM_22.bin", 400_000), ("px4_sample.ulg", 600_000)):
        source = LOGS / name
        if not source.exists():
            continue
        real = source.read_bytes()[:cut]  # the head of a real log: quick to read, every structure in it
        suffix = source.suffix
        put(f"head{suffix}", real, f"the first {cut // 1000} kB of {name}")
        for share in (0.01, 0.3, 0.77):
            put(f"cut{share}{suffix}", real[:int(share * len(real))], f"{name} head cut at {share:.0%}")
        for flips, seed in ((1, 5), (50, 6), (5000, 7)):
            put(f"flip{flips}{suffix}", _flip(real, flips, seed), f"{name} head, {flips} bits flipped")
        put(f"twice{suffix}", real + real, f"{name} head concatenated with itself")
        put(f"zeros{suffix}", real + bytes(2_000_000), f"{name} head, 2 MB of zeros appended")
    quad = LOGS / "quad_2015-10-11_19-53-46.log"
    if quad.exists():
        put("quad_then_synthetic.log", quad.read_bytes()[:300_000] + data, "a real text log's head, then another log")
    fifo = folder / "pipe.log"
    os.mkfifo(fifo)
    made.append(("a FIFO named .log", fifo))
    directory = folder / "folder.ulg"
    directory.mkdir()
    made.append(("a folder named .ulg", directory))
    for name, head in (("sparse.ulg", b"ULog\x01\x12\x35\x01"), ("sparse.bin", b"\xa3\x95\x80\x80")):
        path = folder / name
        with open(path, "wb") as handle:
            handle.write(head)
            handle.truncate(10 * 1024**3)
        made.append((f"a 10 GB sparse file starting like a {path.suffix}", path))
    if os.geteuid() == 0:
        device = folder / "device.bin"
        os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 5))  # the zero device's numbers
        made.append(("a character device named .bin (endless zeros)", device))
    odd = folder / os.fsdecode(b"vol-\xe9t\xe9.log")
    shutil.copy(text, odd)
    made.append(("a whole log under a name that is not UTF-8", odd))
    loop = folder / "loop.log"
    loop.symlink_to(loop)
    made.append(("a symbolic link to itself", loop))
    made.append(("a log that does not exist", folder / "absent.log"))
    return made


# ---------------------------------------------------------------- surfaces

def sweep_logs(s: Sweep, logs: list[tuple[str, Path]]):
    for what, path in logs:
        s.cli("log info", what, ["log", "info", path])
        s.cli("log info --json", what, ["log", "info", path, "--json"])
        s.cli("log plot", what, ["log", "plot", path, "--out", s.folder().with_suffix(".png")])
        s.cli("log replay", what, ["log", "replay", path])
    calibrated = [(w, p) for w, p in logs if not any(k in w for k in ("bits flipped", "2 MB", "1 MB"))] + \
        [(w, p) for w, p in logs if "bits flipped" in w][:3]
    for what, path in calibrated:
        s.cli("calibrate", what, ["calibrate", path, "--out", s.folder(), "--models", "current", "throttle"])


def sweep_calibrate_options(s: Sweep, logs: list[tuple[str, Path]]):
    text = next(p for w, p in logs if w == "a whole synthetic text log")
    shifted = next(p for w, p in logs if "MAG stamps moved 100" in w)
    cases = [
        ("--compass 7", [text, "--compass", "7"]),
        ("--compass -1", [text, "--compass", "-1"]),
        ("--test-fraction 0", [text, "--test-fraction", "0"]),
        ("--test-fraction 0.999", [text, "--test-fraction", "0.999"]),
        ("--test-fraction nan", [text, "--test-fraction", "nan"]),
        ("--train without --test", ["--train", text]),
        ("--train A --test B (B shifted)", ["--train", text, "--test", shifted]),
        ("--train A --test A", ["--train", text, "--test", text]),
        ("two logs, one shifted", [text, shifted]),
        ("--models none", [text, "--models", "none"]),
        ("--attitude sideways", [text, "--attitude", "sideways"]),
        ("--earth sky", [text, "--earth", "sky"]),
        ("--firmware 9.x", [text, "--firmware", "9.x"]),
        ("--firmware 3.4", [text, "--firmware", "3.4", "--models", "current"]),
        ("--no-trim --attitude log", [text, "--no-trim", "--attitude", "log", "--models", "throttle"]),
        ("no file", []),
    ]
    for what, argv in cases:
        s.cli("calibrate options", what, ["calibrate", *argv, "--out", s.folder()])
    out = s.folder()
    s.cli("calibrate options", "a calibration to score", ["calibrate", text, "--out", out, "--models", "current"])
    params = out / "ardupilot.parm"
    folder = s.work / "params"
    folder.mkdir()
    broken = {"empty.parm": b"", "latin1.parm": "COMPASS_OFS_X,1\n# é\n".encode("latin-1"),
              "bad.parm": b"COMPASS_OFS_X\n", "words.parm": b"COMPASS_OFS_X,abc\n",
              "nan.parm": b"COMPASS_OFS_X,nan\nCOMPASS_DIA_X,0\nCOMPASS_DIA_Y,0\nCOMPASS_DIA_Z,0\n",
              "singular.parm": b"COMPASS_DIA_X,1\nCOMPASS_DIA_Y,1\nCOMPASS_DIA_Z,1\nCOMPASS_ODI_X,1\nCOMPASS_ODI_Y,1\n"
                               b"COMPASS_ODI_Z,1\n",
              "huge.parm": b"COMPASS_OFS_X,1e300\nCOMPASS_MOT_X,1e300\nCOMPASS_MOTCT,2\n"}
    for name, content in broken.items():
        (folder / name).write_bytes(content)
    os.mkfifo(folder / "pipe.parm")
    scores = [("the export itself", params), *((f"--score {n}", folder / n) for n in [*broken, "pipe.parm"]),
              ("--score a folder", folder), ("--score missing", folder / "absent.parm")]
    for what, path in scores:
        s.cli("calibrate --score", what, ["calibrate", text, "--score", path, "--out", s.folder()])


def _finished_run(s: Sweep, stream: bool = False) -> Path:
    out = s.folder()
    s.cli("run", "a short run" + (" streamed" if stream else ""),
          ["run", "tp", "--set", "duration=0.5", "--out", out, *(["--stream"] if stream else [])])
    return out


def sweep_plot_compare(s: Sweep):
    whole = _finished_run(s)
    streamed = _finished_run(s, stream=True)
    damaged = []

    def copy(name: str, source: Path, change) -> Path:
        target = s.work / name
        shutil.copytree(source, target)
        change(target)
        damaged.append((name, target))
        return target

    copy("npz_cut", whole, lambda t: (t / "results.npz").write_bytes((t / "results.npz").read_bytes()[:5000]))
    copy("npz_flipped", whole, lambda t: (t / "results.npz").write_bytes(_flip((t / "results.npz").read_bytes(),
                                                                              200, 8)))
    copy("npz_empty", whole, lambda t: (t / "results.npz").write_bytes(b""))
    copy("npz_gone", whole, lambda t: (t / "results.npz").unlink())
    copy("metrics_broken", whole, lambda t: (t / "metrics.json").write_text("{\"files\": [1, "))
    copy("metrics_gone", whole, lambda t: (t / "metrics.json").unlink())
    copy("npz_is_folder", whole, lambda t: ((t / "results.npz").unlink(), (t / "results.npz").mkdir()))

    def chunks_gone(t):
        for chunk in (t / "results.stream").rglob("*.npy"):
            chunk.unlink()

    def chunk_cut(t):
        chunk = sorted((t / "results.stream").rglob("*.npy"))[0]
        chunk.write_bytes(chunk.read_bytes()[:40])

    copy("stream_chunks_gone", streamed, chunks_gone)
    copy("stream_chunk_cut", streamed, chunk_cut)
    copy("stream_index_broken", streamed,
         lambda t: [p.write_text("{") for p in (t / "results.stream").glob("*.json")])
    fifo = s.work / "pipe.png"
    os.mkfifo(fifo)
    targets = [("a missing folder", s.work / "absent" / "x.png"), ("a folder", s.work),
               ("an unknown suffix", s.work / "x.xyz"), ("a FIFO", fifo), ("no suffix", s.work / "plain")]
    for name, folder in [("whole", whole), ("streamed", streamed), *damaged]:
        s.cli("plot", f"{name}: z_d", ["plot", folder, SIGNAL, "--out", s.folder().with_suffix(".png")])
        s.cli("compare", f"{name} with whole: z_d", ["compare", folder, whole, SIGNAL,
                                                     "--out", s.folder().with_suffix(".png")])
    for what, target in targets:
        s.cli("plot", f"into {what}", ["plot", whole, SIGNAL, "--out", target])
        s.cli("compare", f"into {what}", ["compare", whole, streamed, SIGNAL, "--out", target])
    for what, argv in (("unknown signal", ["plot", whole, "no_such_signal"]),
                       ("no signal", ["plot", whole]), ("missing run", ["plot", s.work / "absent", SIGNAL]),
                       ("a file as run", ["plot", whole / "metrics.json", SIGNAL]),
                       ("compare one run", ["compare", whole, SIGNAL]),
                       ("compare unknown signal", ["compare", whole, streamed, "nope"])):
        s.cli("plot/compare", what, argv)


def sweep_profiles(s: Sweep):
    folder = s.work / "profiles"
    folder.mkdir()
    profiles = {
        "ok.csv": "t,theta_d3_deg,z_d\n0,0,0\n0.3,45,-1\n",
        "both_units.csv": "t,theta_d3,theta_d3_deg\n0,0,0\n1,1,90\n",
        "empty.csv": "",
        "header_only.csv": "t,z_d\n",
        "no_t.csv": "z_d\n-1\n",
        "decreasing.csv": "t,z_d\n1,0\n0,-1\n",
        "repeated.csv": "t,z_d\n0,0\n0,-1\n",
        "nan.csv": "t,z_d\n0,nan\n1,-1\n",
        "inf.csv": "t,z_d\n0,inf\n1,-1\n",
        "huge.csv": "t,z_d\n0,0\n0.2,-1e30\n",
        "words.csv": "t,z_d\n0,high\n",
        "unknown_column.csv": "t,altitude\n0,10\n",
        "ragged.csv": "t,z_d,x_d\n0,0\n1,-1,2,3\n",
        "semicolons.csv": "t;z_d\n0;0\n1;-1\n",
        "bom.csv": "\ufefft,z_d\n0,0\n1,-1\n",
        "hold_2.csv": "t,hold\n0,2\n",
        "negative_t.csv": "t,z_d\n-5,0\n1,-1\n",
        "one_row.csv": "t,z_d\n0,-1\n",
    }
    for name, content in profiles.items():
        (folder / name).write_text(content, encoding="utf-8")
    (folder / "latin1.csv").write_bytes("t,z_d\n0,0\n# é\n1,-1\n".encode("latin-1"))
    (folder / "binary.csv").write_bytes(os.urandom(2000))
    os.mkfifo(folder / "pipe.csv")
    (folder / "dir.csv").mkdir()
    for name in [*profiles, "latin1.csv", "binary.csv", "pipe.csv", "dir.csv", "absent.csv"]:
        s.cli("CSV profile", name, ["run", "tp", "--set", "duration=0.3", f"flight={folder / name}",
                                    "--out", s.folder()])


def sweep_gains(s: Sweep):
    values = ["Controller.kp=5000", "Controller.kp=1e300", "Controller.kp=nan", "Controller.kp=inf",
              "Controller.kp=-1", "Controller.kp=0", "Controller.kp=abc", "Controller.kp=", "Controller.nope=1",
              "Nope.kp=1", "kp", "=1", "duration=-1", "duration=0", "duration=1e9", "duration=nan",
              "IMU.gyro_noise_density=1e9", "IMU.gyro_noise_density=-1", "dt=0"]
    for value in values:
        duration = [] if value.startswith("duration") else ["duration=0.5"]
        limit = 150 if value == "duration=1e9" else IN_PROCESS_LIMIT_S
        s.cli("--set gains", value, ["run", "tp", "--set", *duration, value, "--out", s.folder()], limit=limit)


def sweep_findings(s: Sweep):
    """Never without --out (or --check): the findings would be written into this checkout."""
    fifo = s.work / "findings.fifo"
    os.mkfifo(fifo)
    for what, argv in (("unknown group", ["findings", "nope"]), ("--check of an unknown group", ["findings", "nope",
                                                                                                   "--check"]),
                       ("--out into a missing folder", ["findings", "excerpt", "--quick", "--out",
                                                        s.work / "absent" / "f.json", "--no-readme"]),
                       ("--out onto a folder", ["findings", "excerpt", "--quick", "--out", s.work, "--no-readme"]),
                       ("--check of a missing findings file", ["findings", "excerpt", "--quick", "--check",
                                                               "--out", s.work / "none.json"]),
                       ("--out onto a FIFO", ["findings", "excerpt", "--quick", "--no-readme", "--out", fifo])):
        s.cli("findings", what, argv, limit=180)


def sweep_interrupts(s: Sweep, logs: list[tuple[str, Path]]):
    text = next(p for w, p in logs if w == "a whole synthetic text log")
    real = LOGS / "erlebrain_APM_22.bin"
    commands = [("calibrate", ["calibrate", text, "--out", "{out}", "--models", "current"]),
                ("run", ["run", "tp", "--set", "duration=2", "--out", "{out}"]),
                ("run --stream", ["run", "tp", "--set", "duration=2", "--stream", "--out", "{out}"])]
    if real.exists():
        commands.append(("log info of a real .bin", ["log", "info", real]))
    for name, argv in commands:
        for delay in (1.5, 4.0, 8.0):
            for number in (signal.SIGINT, signal.SIGTERM):
                out = s.folder()
                line = [str(a).format(out=out) for a in argv]
                found = s.process("interrupts", f"{name}, {signal.Signals(number).name} after {delay} s", line,
                                  signal_after=(delay, number))
                if out.exists() and any(out.iterdir()):
                    _check_folder(s, found, out)


def _check_folder(s: Sweep, found: dict, out: Path):
    """A folder left by an interrupt or a race: metrics.json, or nothing; no temporary; no empty file."""
    names = sorted(p.name for p in out.iterdir())
    bad = [n for n in names
           if n.startswith(".") or ".part" in n or ((out / n).is_file() and not (out / n).stat().st_size)]
    if bad or "metrics.json" not in names:
        found["problem"] = found["problem"] or f"folder left as {names}"
        print(f"    BROKEN folder: {names}", flush=True)


def sweep_concurrency(s: Sweep, logs: list[tuple[str, Path]]):
    text = next(p for w, p in logs if w == "a whole synthetic text log")
    pairs = [("two runs into one --out", ["run", "tp", "--set", "duration=1", "--out", "{out}"],
              ["run", "tp", "--set", "duration=1", "--out", "{out}"]),
             ("two calibrates into one --out", ["calibrate", text, "--out", "{out}", "--models", "current"],
              ["calibrate", text, "--out", "{out}", "--models", "current"]),
             ("a run and a calibrate into one --out", ["run", "tp", "--set", "duration=1", "--out", "{out}"],
              ["calibrate", text, "--out", "{out}", "--models", "current"]),
             ("two runs --overwrite into one --out", ["run", "tp", "--set", "duration=1", "--overwrite",
                                                      "--out", "{out}"],
              ["run", "tp", "--set", "duration=1", "--overwrite", "--out", "{out}"])]
    for what, first, second in pairs:
        for stagger in (0.0, 2.0):
            out = s.folder()
            started = time.perf_counter()
            children = []
            for k, argv in enumerate((first, second)):
                if k:
                    time.sleep(stagger)
                children.append(subprocess.Popen([sys.executable, "-m", "quadcosim.main",
                                                  *(str(a).format(out=out) for a in argv)], cwd=ROOT,
                                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                                 env=os.environ | {"MPLBACKEND": "Agg"}))
            results = [s.finish("concurrency", f"{what} (stagger {stagger} s), process {k + 1}", argv, child, started)
                       for k, (argv, child) in enumerate(zip((first, second), children, strict=True))]
            succeeded = [r for r in results if r["exit"] == 0]
            if len(succeeded) > 1 and "overwrite" not in what:
                results[1]["problem"] = results[1]["problem"] or "both exited 0 on one folder"
            if out.exists():
                _check_folder(s, results[-1], out)


def sweep_full_disk(s: Sweep, logs: list[tuple[str, Path]]):
    if os.geteuid() != 0:
        return
    text = next(p for w, p in logs if w == "a whole synthetic text log")
    commands = [("plot", ["plot", "{run}", SIGNAL, "--out", "{disk}/yaw.png"]),
                ("compare", ["compare", "{run}", "{run}", SIGNAL, "--out", "{disk}/cmp.png"]),
                ("log plot", ["log", "plot", text, "--out", "{disk}/log.png"]),
                ("log info --json", ["log", "info", text, "--json"]),
                ("diagram", ["diagram", "tp", "--out", "{disk}/diagram.png"]),
                ("findings --out", ["findings", "excerpt", "--quick", "--no-readme", "--out", "{disk}/f.json"])]
    run = _finished_run(s)
    from tests.adversarial.full_disk_matrix import tmpfs

    for name, argv in commands:
        for free in (0, 8192, 40_000):
            disk = s.work / f"disk{s.counter}"
            s.counter += 1
            with tmpfs(disk, free):
                line = [str(a).format(run=run, disk=disk) for a in argv]
                found = s.cli("full disk", f"{name} with {free} B free", line, limit=180)
                for path in disk.iterdir():
                    if path.name != "filler" and (path.name.startswith(".") or not path.stat().st_size):
                        found["problem"] = found["problem"] or f"left {path.name}"


ESTIMATORS = """
from quadcosim.estimators.contract import AttitudeEstimator


class Growing(AttitudeEstimator):
    def update(self, acc, gyro, mag):
        self.q = self.q * 1.01


class Raising(AttitudeEstimator):
    def update(self, acc, gyro, mag):
        raise ZeroDivisionError("a bug of the user's")
"""


def sweep_edges(s: Sweep, logs: list[tuple[str, Path]]):
    """The reads that hung or filled the memory, replay's and bench's numbers, scenario options
    that misled, user estimators that broke the contract, --score files misread."""
    folder = s.work / "edges"
    folder.mkdir()
    for name in ("fifo.json", "fifo.csv", "fifo.npz"):
        os.mkfifo(folder / name)
    (folder / "zero.npz").symlink_to("/dev/zero")
    tp = ["run", "tp", "--set", "duration=0.5"]
    for what, argv in (("calibration=/dev/zero", [*tp, "compensation=static", "calibration=/dev/zero"]),
                       ("calibration= a FIFO", [*tp, "compensation=static", f"calibration={folder / 'fifo.json'}"]),
                       ("metge static= a FIFO", ["run", "metge", "--set", f"static={folder / 'fifo.json'}"])):
        s.process("reads", what, [*argv, "--out", s.folder()], limit=150)
    for name in ("fifo.csv", "fifo.npz", "zero.npz"):
        s.process("reads", f"replay {name}", ["replay", folder / name], limit=150)
    run = _finished_run(s)
    recording = folder / "rec.npz"
    s.cli("replay", "a recording from tp", ["replay", "--from-tp", run, "--write", recording])
    import numpy as np

    with np.load(recording) as archive:
        data = {k: archive[k] for k in archive.files}
    variants = {"complex.npz": {"gyro": data["gyro"] * (1 + 1e-3j)},
                "scored_text.npz": {"scored": np.array(["yes"] * len(data["gyro"]))},
                "rate_1e308.npz": {"rate": np.array(1e308)},
                "meta_list.npz": {"meta": np.array('{"estimator": ["explicit"]}')},
                "gains_list.npz": {"meta": np.array('{"estimator": {"kind": "explicit", "gains": [1]}}')}}
    for name, change in variants.items():
        np.savez(folder / name, **(data | change))
        s.cli("replay", name, ["replay", folder / name])
    for options in (["--rate", "1e308"], ["--field-from-data", "1e308"], ["--field-from-data", "-1"],
                    ["--dip", "1e308"], ["--out", "/proc/r.json"], ["--out", s.work / "absent" / "r.json"]):
        s.cli("replay", " ".join(map(str, options)), ["replay", recording, *options])
    for seconds in ("0", "-1", "nan", "1e-9", "1e308"):
        s.cli("bench", f"--seconds {seconds}", ["bench", f"--seconds={seconds}"])
    for what, argv in (("ir-calibration faults=gps in 60 s", ["run", "ir-calibration", "--set", "duration=60",
                                                              "faults=gps"]),
                       ("ir-calibration GPS for 0.001 s", ["run", "ir-calibration", "--set", "duration=10",
                                                           "gps_resetting=false", "calibration_s=0.001"]),
                       ("static-cal rates=1e6", ["run", "static-cal", "--set", "rates=1e6,0,0"]),
                       ("static-cal rates=nan", ["run", "static-cal", "--set", "rates=nan,1,1"]),
                       ("rig unclamped", ["run", "rig", "--set", "sweep=1", "free=1", "Quadrotor.clamped=false"]),
                       ("metge unclamped", ["run", "metge", "--set", "Quadrotor.clamped=false"])):
        s.cli("scenario options", what, [*argv, "--out", s.folder()])
    (folder / "mine.py").write_text(ESTIMATORS)
    for name in ("Growing", "Raising"):
        s.cli("user estimator", name, [*tp, "--estimator", f"{folder / 'mine.py'}:{name}", "--out", s.folder()])
    text = next(p for w, p in logs if w == "a whole synthetic text log")
    for name, content in (("bom.parm", "\ufeffCOMPASS_MOTCT,2\nCOMPASS_MOT_X,-3\n"),
                          ("twice.parm", "COMPASS_MOTCT,2\nCOMPASS_MOTCT,1\n"),
                          ("other_compass.parm", "COMPASS_OFS2_X,100\n"),
                          ("absurd.parm", "COMPASS_MOTCT,2\nCOMPASS_MOT_X,3e38\n")):
        (folder / name).write_text(content, encoding="utf-8")
        s.cli("calibrate --score", name, ["calibrate", text, "--score", folder / name, "--out", s.folder()])


SURFACES = ("logs", "calibrate", "plot", "profiles", "gains", "findings", "edges", "interrupts", "concurrency",
            "disk")


def main(argv=None) -> int:
    import argparse

    import matplotlib

    matplotlib.use("Agg")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write every case's outcome here")
    parser.add_argument("--surfaces", default=",".join(SURFACES), help="comma-separated, of " + ", ".join(SURFACES))
    args = parser.parse_args(argv)
    chosen = args.surfaces.split(",")
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        s = Sweep(Path(folder))
        logs = log_inputs(s.work)
        steps = {"logs": lambda: sweep_logs(s, logs), "calibrate": lambda: sweep_calibrate_options(s, logs),
                 "plot": lambda: sweep_plot_compare(s), "profiles": lambda: sweep_profiles(s),
                 "gains": lambda: sweep_gains(s), "findings": lambda: sweep_findings(s),
                 "edges": lambda: sweep_edges(s, logs),
                 "interrupts": lambda: sweep_interrupts(s, logs), "concurrency": lambda: sweep_concurrency(s, logs),
                 "disk": lambda: sweep_full_disk(s, logs)}
        for name in chosen:
            steps[name]()
    outcomes = s.outcomes
    print("\n| surface | invocations | tracebacks | hangs | other breaks |\n|---|---|---|---|---|")
    by: dict[str, list] = {}
    for o in outcomes:
        by.setdefault(o["surface"], []).append(o)
    for surface, found in by.items():
        tb = sum(o["problem"].startswith("traceback") for o in found)
        hangs = sum(o["problem"] == "hang" for o in found)
        other = sum(bool(o["problem"]) for o in found) - tb - hangs
        print(f"| {surface} | {len(found)} | {tb} | {hangs} | {other} |")
    broken = [o for o in outcomes if o["problem"]]
    print(f"\n{len(outcomes)} invocations, {len(broken)} broken, in {time.perf_counter() - started:.0f} s")
    for o in broken:
        print(f"  [{o['surface']}] {o['what']}: {o['problem']}")
    if args.json:
        from quadcosim.infra.files import write_json

        write_json(args.json, outcomes)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
