"""``dummy``: a clock alone, for the registry test."""

from quadcosim.orchestrator import Block, System
from quadcosim.scenarios import Option, Scenario


class Clock(Block):
    """Writes the time (s)."""

    outputs = ("t",)
    units = {"t": "s"}

    def step(self, t, u, y):
        y[0] = t


def build(o):
    system = System(dt=o["dt"])
    system.add(Clock("Clock"))
    return system


def report(result, o, out):
    return {"final_time_s": float(result.time[-1])}


OPTIONS = {"duration": Option(0.5, "simulated time (s)", minimum=0.0),
           "dt": Option(0.01, "macro step (s)", minimum=1e-4)}
SCENARIO = Scenario("dummy", "a clock alone", OPTIONS, build, report, duration=lambda o: o["duration"])
